//! Tabulated BRDFs with multilinear interpolation, their resolution chosen by an error bound (Stürzlinger & Bastos 1997, "Interactive rendering of globally illuminated glossy scenes", section 3.2: "A four dimensional table is used to speed up the evaluation of the BRDF").
//!
//! Two layouts: a 3D table over `(θi, θo, Δφ)` for isotropic models and the
//! paper's 4D table over `(θi, φi, θo, φo)` for anisotropic ones. Polar
//! angles have `n` nodes `θk = k Θ / (n - 1)` from the normal to
//! [`TABLE_MAX_THETA`] Θ = 85°: no node sits at grazing incidence, where
//! several models diverge (Phong's and Ward's `1/cos`, Oren-Nayar's `tan β`),
//! and lookups beyond Θ clamp to it. `Δφ = |φi - φo|` in `[0, π]`
//! has nodes at both ends (an isotropic table assumes the model is also
//! symmetric under `Δφ → -Δφ`, which [`BrdfTable::with_error_bound`]
//! checks); azimuths of the 4D table are periodic with `2n` nodes over
//! `[0, 2π)`.
//!
//! **Error bound.** The error of the table at `(wi, wo)` in one channel is
//! `|t - f| / max(f, 0.01 f_peak)`: relative, except that values below 1 %
//! of the largest value on the validation set are judged against that 1 %
//! floor (a relative error of a value near zero says nothing about the
//! image). The bound holds for both directions within Θ of the normal.
//! [`BrdfTable::with_error_bound`] doubles the resolution until the largest
//! error over 16384 random direction pairs (uniform in solid angle within Θ,
//! independent of the grid) is at most half the requested bound: the factor
//! two is the margin for directions the validation set missed.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample, cosine_pdf, same_upper, sample_cosine};
use crate::error::{BrdfError, Result};

/// The parameterisation of a [`BrdfTable`] (Stürzlinger & Bastos 1997, section 3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableLayout {
    /// 3D `(θi, θo, Δφ)` with `n` polar nodes each and `n` azimuth-difference nodes over `[0, π]`: isotropic, mirror-symmetric models.
    Isotropic,
    /// 4D `(θi, φi, θo, φo)` with `n` polar and `2n` azimuth nodes each: any model, the paper's four-dimensional table.
    Anisotropic,
}

/// Largest polar angle Θ of the table's nodes, 85° (the domain of its error bound; lookups beyond clamp).
pub const TABLE_MAX_THETA: f32 = 85.0 * std::f32::consts::PI / 180.0;

/// Number of random direction pairs on which [`BrdfTable::with_error_bound`] validates.
pub const VALIDATION_PAIRS: usize = 16384;

/// Values below this fraction of the peak are judged against it in [`BrdfTable::max_relative_error`].
pub const ERROR_FLOOR: f32 = 0.01;

/// Largest polar resolution tried for the 3D layout (128³ nodes, 25 MB).
pub const MAX_ISOTROPIC_RESOLUTION: usize = 128;

/// Largest polar resolution tried for the 4D layout (32² × 64² nodes, 50 MB).
pub const MAX_ANISOTROPIC_RESOLUTION: usize = 32;

/// A BRDF tabulated on a regular grid and evaluated by multilinear interpolation (Stürzlinger & Bastos 1997, section 3.2).
#[derive(Debug, Clone, PartialEq)]
pub struct BrdfTable {
    /// The parameterisation.
    pub layout: TableLayout,
    /// Nodes per polar axis (azimuth axes: `n` for Δφ, `2n` for φ).
    pub resolution: usize,
    /// Node counts per axis, in the axis order of the layout.
    dims: Vec<usize>,
    /// Node values, last axis fastest.
    values: Vec<Rgb>,
    /// Whether the tabulated model was reciprocal.
    reciprocal: bool,
}

/// A seeded SplitMix64 generator for the validation directions (Steele, Lea & Flood 2014).
struct SplitMix(u64);

impl SplitMix {
    /// The next uniform number in [0, 1).
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A direction uniform in solid angle over the cap within [`TABLE_MAX_THETA`] of the normal.
    fn upper(&mut self) -> Vec3 {
        let c_min = TABLE_MAX_THETA.cos();
        let c = (c_min + (1.0 - c_min) * self.next()).min(1.0);
        let s = (1.0 - c * c).max(0.0).sqrt();
        let p = std::f32::consts::TAU * self.next();
        Vec3::new(s * p.cos(), s * p.sin(), c)
    }
}

/// The direction with polar angle `theta` and azimuth `phi`.
fn spherical(theta: f32, phi: f32) -> Vec3 {
    let s = theta.sin();
    Vec3::new(s * phi.cos(), s * phi.sin(), theta.cos())
}

/// Polar angle and azimuth in [0, 2π) of a unit direction.
fn polar(w: Vec3) -> (f32, f32) {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += std::f32::consts::TAU;
    }
    (theta, phi)
}

impl BrdfTable {
    /// Tabulates `brdf` in `layout` with `resolution` polar nodes per axis; errors when the resolution is below 2 or above the layout's maximum.
    pub fn new<B: Brdf + ?Sized>(brdf: &B, layout: TableLayout, resolution: usize) -> Result<Self> {
        let max = match layout {
            TableLayout::Isotropic => MAX_ISOTROPIC_RESOLUTION,
            TableLayout::Anisotropic => MAX_ANISOTROPIC_RESOLUTION,
        };
        if !(2..=max).contains(&resolution) {
            return Err(BrdfError::OutOfRange {
                model: "brdf-table".into(),
                param: "resolution".into(),
                value: resolution as f32,
                expected: format!("2 to {max}"),
            });
        }
        let n = resolution;
        let theta = |k: usize| k as f32 * TABLE_MAX_THETA / (n - 1) as f32;
        let (dims, values) = match layout {
            TableLayout::Isotropic => {
                let dphi = |k: usize| k as f32 * std::f32::consts::PI / (n - 1) as f32;
                let mut v = Vec::with_capacity(n * n * n);
                for i in 0..n {
                    for o in 0..n {
                        let wo = spherical(theta(o), 0.0);
                        for d in 0..n {
                            v.push(brdf.eval(spherical(theta(i), dphi(d)), wo));
                        }
                    }
                }
                (vec![n, n, n], v)
            }
            TableLayout::Anisotropic => {
                let m = 2 * n;
                let phi = |k: usize| k as f32 * std::f32::consts::TAU / m as f32;
                let mut v = Vec::with_capacity(n * m * n * m);
                for ti in 0..n {
                    for pi in 0..m {
                        let wi = spherical(theta(ti), phi(pi));
                        for to in 0..n {
                            for po in 0..m {
                                v.push(brdf.eval(wi, spherical(theta(to), phi(po))));
                            }
                        }
                    }
                }
                (vec![n, m, n, m], v)
            }
        };
        let values = values
            .into_iter()
            .map(|c| if c.is_finite() { c } else { Rgb::ZERO })
            .collect();
        Ok(Self {
            layout,
            resolution,
            dims,
            values,
            reciprocal: brdf.is_reciprocal(),
        })
    }

    /// The coarsest table (doubling from 8 polar nodes) whose [`BrdfTable::max_relative_error`] over [`VALIDATION_PAIRS`] random pairs is at most `max_relative_error / 2`; the 3D layout when the model passes an isotropy check, else the 4D one (Stürzlinger & Bastos 1997, section 3.2, with the resolution set by an error bound).
    pub fn with_error_bound<B: Brdf + ?Sized>(brdf: &B, max_relative_error: f32) -> Result<Self> {
        if !crate::brdf::is_positive(max_relative_error) {
            return Err(BrdfError::OutOfRange {
                model: "brdf-table".into(),
                param: "max_relative_error".into(),
                value: max_relative_error,
                expected: "positive and finite".into(),
            });
        }
        let layout = if is_isotropic(brdf, 0.25 * max_relative_error) {
            TableLayout::Isotropic
        } else {
            TableLayout::Anisotropic
        };
        Self::with_layout_and_error_bound(brdf, layout, max_relative_error)
    }

    /// As [`BrdfTable::with_error_bound`] with the layout given; errors with [`BrdfError::ErrorBoundNotMet`] when the largest resolution does not meet the bound.
    pub fn with_layout_and_error_bound<B: Brdf + ?Sized>(
        brdf: &B,
        layout: TableLayout,
        max_relative_error: f32,
    ) -> Result<Self> {
        let max = match layout {
            TableLayout::Isotropic => MAX_ISOTROPIC_RESOLUTION,
            TableLayout::Anisotropic => MAX_ANISOTROPIC_RESOLUTION,
        };
        let pairs = validation_pairs(0x5754_u64, VALIDATION_PAIRS);
        let mut n = 8;
        loop {
            let table = Self::new(brdf, layout, n)?;
            let err = table.max_relative_error(brdf, &pairs);
            if err <= 0.5 * max_relative_error {
                return Ok(table);
            }
            if n >= max {
                return Err(BrdfError::ErrorBoundNotMet {
                    model: brdf.name().into(),
                    requested: max_relative_error,
                    achieved: 2.0 * err,
                    resolution: n,
                });
            }
            n = (2 * n).min(max);
        }
    }

    /// The largest error `|t - f| / max(f, 0.01 f_peak)` over `pairs` and channels, `f_peak` the largest value of `brdf` on `pairs` per channel (the error measure of the module documentation).
    pub fn max_relative_error<B: Brdf + ?Sized>(&self, brdf: &B, pairs: &[(Vec3, Vec3)]) -> f32 {
        let exact: Vec<Rgb> = pairs.iter().map(|&(i, o)| brdf.eval(i, o)).collect();
        let peak = exact
            .iter()
            .filter(|c| c.is_finite())
            .fold(Rgb::ZERO, |a, &c| a.max(c));
        let floor = (peak * ERROR_FLOOR).max(Rgb::splat(1e-12));
        let mut worst = 0.0f32;
        for (&(wi, wo), &f) in pairs.iter().zip(&exact) {
            if !f.is_finite() {
                continue;
            }
            let t = self.lookup(wi, wo);
            let e = ((t - f).abs() / f.max(floor)).max_element();
            worst = worst.max(e);
        }
        worst
    }

    /// The interpolated value at `(wi, wo)`, both in the upper hemisphere (the table lookup of section 3.2).
    pub fn lookup(&self, wi: Vec3, wo: Vec3) -> Rgb {
        let n = self.resolution as f32;
        let (ti, pi) = polar(wi);
        let (to, po) = polar(wo);
        // Continuous node coordinates; θ beyond Θ clamps in `interpolate`.
        let theta_coord = |t: f32| t / TABLE_MAX_THETA * (n - 1.0);
        match self.layout {
            TableLayout::Isotropic => {
                let mut d = (pi - po).abs();
                if d > std::f32::consts::PI {
                    d = std::f32::consts::TAU - d;
                }
                let dcoord = d / std::f32::consts::PI * (n - 1.0);
                self.interpolate(&[theta_coord(ti), theta_coord(to), dcoord], &[false; 3])
            }
            TableLayout::Anisotropic => {
                let m = 2.0 * n;
                let pcoord = |p: f32| p / std::f32::consts::TAU * m;
                self.interpolate(
                    &[theta_coord(ti), pcoord(pi), theta_coord(to), pcoord(po)],
                    &[false, true, false, true],
                )
            }
        }
    }

    /// Multilinear interpolation at continuous node coordinates; clamped axes stop at the end nodes, periodic ones wrap.
    fn interpolate(&self, coords: &[f32], periodic: &[bool]) -> Rgb {
        let d = coords.len();
        let mut lo = [0usize; 4];
        let mut hi = [0usize; 4];
        let mut t = [0f32; 4];
        for a in 0..d {
            let size = self.dims[a];
            let x = if coords[a].is_finite() {
                coords[a]
            } else {
                0.0
            };
            if periodic[a] {
                let f = x.floor();
                t[a] = x - f;
                let i = (f as i64).rem_euclid(size as i64) as usize;
                lo[a] = i;
                hi[a] = (i + 1) % size;
            } else {
                let x = x.clamp(0.0, (size - 1) as f32);
                let i = (x.floor() as usize).min(size - 2);
                lo[a] = i;
                hi[a] = i + 1;
                t[a] = x - i as f32;
            }
        }
        let mut sum = Rgb::ZERO;
        for corner in 0..(1usize << d) {
            let mut w = 1.0;
            let mut index = 0usize;
            for a in 0..d {
                let up = corner >> a & 1 == 1;
                w *= if up { t[a] } else { 1.0 - t[a] };
                index = index * self.dims[a] + if up { hi[a] } else { lo[a] };
            }
            if w != 0.0 {
                sum += self.values[index] * w;
            }
        }
        sum
    }

    /// Number of stored nodes.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the table stores no node (never true for a constructed table).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// `count` direction pairs uniform in solid angle within [`TABLE_MAX_THETA`] of the normal from `seed` (the validation set of [`BrdfTable::with_error_bound`]).
pub fn validation_pairs(seed: u64, count: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = SplitMix(seed);
    (0..count).map(|_| (rng.upper(), rng.upper())).collect()
}

/// Whether `f` is unchanged, within `tolerance` in the error measure of the module, by a rotation about the normal and by the mirror `y → -y` on 256 random pairs.
fn is_isotropic<B: Brdf + ?Sized>(brdf: &B, tolerance: f32) -> bool {
    let mut rng = SplitMix(0x1507);
    let pairs = validation_pairs(0x1508, 256);
    let peak = pairs
        .iter()
        .map(|&(i, o)| brdf.eval(i, o))
        .filter(|c| c.is_finite())
        .fold(Rgb::ZERO, |a, c| a.max(c));
    let floor = (peak * ERROR_FLOOR).max(Rgb::splat(1e-12));
    pairs.iter().all(|&(wi, wo)| {
        let f = brdf.eval(wi, wo);
        let angle = std::f32::consts::TAU * rng.next();
        let rot = glam::Quat::from_rotation_z(angle);
        let mirror = Vec3::new(1.0, -1.0, 1.0);
        let g = brdf.eval(rot * wi, rot * wo);
        let h = brdf.eval(wi * mirror, wo * mirror);
        !f.is_finite()
            || ((g - f).abs() / f.max(floor)).max_element() <= tolerance
                && ((h - f).abs() / f.max(floor)).max_element() <= tolerance
    })
}

impl Brdf for BrdfTable {
    fn name(&self) -> &'static str {
        "brdf-table"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        self.lookup(wi, wo)
    }

    fn sample(&self, wo: Vec3, u: Vec2, _u_lobe: f32) -> Option<BrdfSample> {
        sample_cosine(self, wo, u)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        cosine_pdf(wi, wo)
    }

    fn is_reciprocal(&self) -> bool {
        // Both layouts tabulate the two directions on identical axes, but
        // interpolation is symmetric only in the 4D layout's exchange of the
        // (θ, φ) pairs and the 3D layout's exchange of θi and θo: reciprocal
        // to interpolation precision when the source is.
        self.reciprocal
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
