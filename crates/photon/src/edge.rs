//! The kernel's mass on its surface near polygon edges (beyond section 2.2: the paper's future work, "improving the appearance of the polygon edges similarly to \[11\]").
//!
//! Equation 2 sums kernels of unit volume, but near a surface's edge part of
//! the kernel around a point `x` lies off the polygon, where no photon can
//! land: on a uniformly lit surface the estimate falls to one half along an
//! edge and one quarter at a square corner, a dark rim of width `h` along
//! every wall joint and box edge. Dividing the estimate at `x` by the
//! kernel's mass on the surface,
//!
//! `M(x) = ∫_S K((x - y)/h) / h² dy`,
//!
//! makes it exact for a uniform density anywhere on the polygon: the
//! renormalised boundary estimator of kernel density estimation (Jones 1993,
//! "Simple boundary correction for kernel density estimation", the
//! normalisation by the kernel's mass in the domain; Walter et al. 1997 remove
//! the same bias with local linear regression). Away from edges `M = 1` and
//! nothing changes.
//!
//! **Computation.** Per planar surface, `M` is sampled on a regular grid over
//! its `(u, v)` bounding rectangle ([`PlanarFrame::min`]..[`PlanarFrame::max`])
//! with spacing `h/4` (at most [`MAX_SAMPLES_PER_SIDE`] samples per side) and
//! read bilinearly, on the CPU ([`KernelMass::at`]) and, from the same grid,
//! by the GPU splat pass of `lustre-mpr`. A sample farther than `h` from
//! every boundary edge of the surface is 1 (inside) or 0 (outside); the others
//! integrate the kernel by a fixed quadrature of [`RINGS`] × [`ANGLES`] points
//! of equal mass in the unit disc, each tested against the surface's
//! triangles. Curved surfaces are not corrected (`M = 1`).
//!
//! Written here rather than taken from a crate: it needs the surfaces'
//! triangles in their own `(u, v)` frames and must agree bit for bit with the
//! grid the GPU reads.

use std::collections::HashMap;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::kernel::Kernel;
use crate::parameterisation::{PlanarFrame, SurfaceParam, SurfaceParams};
use lustre_geometry::SurfaceId;

/// Largest number of grid samples along either side of one surface; the spacing grows beyond `h/4` to fit.
pub const MAX_SAMPLES_PER_SIDE: usize = 512;

/// Rings of equal kernel mass in the quadrature of `M`.
pub const RINGS: usize = 16;

/// Points per ring in the quadrature of `M`.
pub const ANGLES: usize = 32;

/// How far outside a triangle, relative to the length of its edge, a point still counts as on it ([`Polygon::contains`]).
pub const EDGE_TOLERANCE: f32 = 1e-5;

/// Grid spacing in units of the kernel support `h`.
const SPACING_PER_SUPPORT: f32 = 0.25;

/// `M(x)` sampled over one planar surface: samples `(i, j)` at `min + (i, j) spacing`, row-major by `j`.
#[derive(Debug, Clone, PartialEq)]
pub struct MassGrid {
    /// `(u, v)` of sample `(0, 0)`.
    pub min: Vec2,
    /// Distance between samples along `u` and `v`, in metres.
    pub spacing: Vec2,
    /// Samples along `u`.
    pub columns: u32,
    /// Samples along `v`.
    pub rows: u32,
    /// `M` at each sample, `values[j columns + i]`, in `[0, 1]`.
    pub values: Vec<f32>,
}

impl MassGrid {
    /// `M` at `(u, v)`, bilinear between the four samples around it (clamped to the grid).
    pub fn at(&self, uv: Vec2) -> f32 {
        let last = Vec2::new((self.columns - 1) as f32, (self.rows - 1) as f32);
        let s = ((uv - self.min) / self.spacing).clamp(Vec2::ZERO, last);
        let s = if s.is_finite() { s } else { Vec2::ZERO };
        let i0 = (s.x.floor() as u32).min(self.columns - 1);
        let j0 = (s.y.floor() as u32).min(self.rows - 1);
        let i1 = (i0 + 1).min(self.columns - 1);
        let j1 = (j0 + 1).min(self.rows - 1);
        let f = s - Vec2::new(i0 as f32, j0 as f32);
        let v = |i: u32, j: u32| self.values[(j * self.columns + i) as usize];
        let a = v(i0, j0) + (v(i1, j0) - v(i0, j0)) * f.x;
        let b = v(i0, j1) + (v(i1, j1) - v(i0, j1)) * f.x;
        a + (b - a) * f.y
    }
}

/// The kernel's mass on its surface, `M(x)`, for every surface of a scene (module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KernelMass {
    /// By surface: the grid of a planar surface with a positive support, `None` otherwise (`M = 1`).
    grids: Vec<Option<MassGrid>>,
}

/// Smallest `M` an estimate is divided by: a point can only be this far off its polygon through bilinear interpolation.
pub const MIN_MASS: f32 = 1.0 / 16.0;

impl KernelMass {
    /// Samples `M` over every planar surface of `params` whose support `supports[surface]` is positive.
    pub fn build(params: &SurfaceParams, supports: &[f32], kernel: Kernel) -> Self {
        let quadrature = quadrature(kernel);
        let grids = (0..params.len())
            .into_par_iter()
            .map(|id| {
                let h = supports.get(id).copied().unwrap_or(0.0);
                match params.get(id as SurfaceId) {
                    Some(SurfaceParam::Planar(frame)) if h > 0.0 && h.is_finite() => {
                        let polygon = Polygon::of(params, id as SurfaceId, frame);
                        Some(polygon.grid(frame, h, &quadrature))
                    }
                    _ => None,
                }
            })
            .collect();
        Self { grids }
    }

    /// The grid of a surface; `None` where `M = 1` (curved surfaces, no photons, unknown surfaces).
    pub fn grid(&self, surface: SurfaceId) -> Option<&MassGrid> {
        self.grids.get(surface as usize)?.as_ref()
    }

    /// `M` at `(u, v)` on `surface`, at least [`MIN_MASS`]; 1 where the surface has no grid.
    pub fn at(&self, surface: SurfaceId, uv: Vec2) -> f32 {
        self.grid(surface).map_or(1.0, |g| g.at(uv).max(MIN_MASS))
    }
}

/// Points of equal mass `1/(RINGS ANGLES)` in the unit disc for `kernel`: ring `j` at the radius that encloses mass `(j + ½)/RINGS`, its points a quarter step off the axes (three quarters on odd rings), so that none lies on an axis-aligned edge through the centre.
pub fn quadrature(kernel: Kernel) -> Vec<Vec2> {
    let mut points = Vec::with_capacity(RINGS * ANGLES);
    for j in 0..RINGS {
        let r = kernel.radius_enclosing((j as f32 + 0.5) / RINGS as f32);
        let offset = if j % 2 == 1 { 0.75 } else { 0.25 };
        for a in 0..ANGLES {
            let phi = std::f32::consts::TAU * (a as f32 + offset) / ANGLES as f32;
            points.push(r * Vec2::new(phi.cos(), phi.sin()));
        }
    }
    points
}

/// A world corner's exact bits, the key that matches the corners two triangles share.
type CornerBits = [u32; 3];

/// A planar surface's triangles and boundary edges in its `(u, v)` frame.
#[derive(Debug, Clone, Default)]
pub struct Polygon {
    /// Triangles, corners in `(u, v)`.
    triangles: Vec<[Vec2; 3]>,
    /// Edges used by exactly one triangle.
    boundary: Vec<[Vec2; 2]>,
}

impl Polygon {
    /// The triangles of `surface` in the frame `frame`.
    pub fn of(params: &SurfaceParams, surface: SurfaceId, frame: &PlanarFrame) -> Self {
        let world: Vec<[Vec3; 3]> = (0..params.triangle_count(surface) as u32)
            .filter_map(|t| params.corners(surface, t))
            .collect();
        Self::from_world(&world, frame)
    }

    /// The polygon of world triangles lying in the plane of `frame`.
    pub fn from_world(world: &[[Vec3; 3]], frame: &PlanarFrame) -> Self {
        // Undirected edges by their corners' exact bits: corners shared within a mesh are identical.
        let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let mut uses: HashMap<(CornerBits, CornerBits), (usize, [Vec2; 2])> = HashMap::new();
        let mut triangles = Vec::with_capacity(world.len());
        for t in world {
            let uv = t.map(|p| frame.to_uv(p));
            triangles.push(uv);
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let (ka, kb) = (key(a), key(b));
                let k = if ka <= kb { (ka, kb) } else { (kb, ka) };
                uses.entry(k).or_insert((0, [uv[e], uv[(e + 1) % 3]])).0 += 1;
            }
        }
        let mut boundary: Vec<[Vec2; 2]> = uses
            .into_values()
            .filter(|(n, _)| *n == 1)
            .map(|(_, e)| e)
            .collect();
        boundary.sort_by(|a, b| {
            (a[0].x, a[0].y, a[1].x, a[1].y)
                .partial_cmp(&(b[0].x, b[0].y, b[1].x, b[1].y))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        Self {
            triangles,
            boundary,
        }
    }

    /// Whether `p` lies in one of the triangles or within [`EDGE_TOLERANCE`] of an edge's length outside it (a point on the edge two triangles share must not fall between them by rounding).
    pub fn contains(&self, p: Vec2) -> bool {
        self.triangles.iter().any(|&[a, b, c]| {
            // Signed distances to the edges times their lengths, with the slack scaled alike.
            let side = |e0: Vec2, e1: Vec2| {
                let d = e1 - e0;
                (d.perp_dot(p - e0), EDGE_TOLERANCE * d.length_squared())
            };
            let sides = [side(a, b), side(b, c), side(c, a)];
            sides.iter().all(|&(d, eps)| d >= -eps) || sides.iter().all(|&(d, eps)| d <= eps)
        })
    }

    /// Distance from `p` to the nearest boundary edge (infinite without one).
    pub fn boundary_distance(&self, p: Vec2) -> f32 {
        self.boundary
            .iter()
            .map(|&[a, b]| {
                let d = b - a;
                let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                let t = if t.is_finite() { t } else { 0.0 };
                (a + t * d).distance(p)
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// `M(x)` at `(u, v)` for support `h`: 1 or 0 farther than `h` from the boundary, else the quadrature's share of points on the polygon.
    pub fn mass(&self, uv: Vec2, h: f32, quadrature: &[Vec2]) -> f32 {
        if self.boundary_distance(uv) >= h {
            return if self.contains(uv) { 1.0 } else { 0.0 };
        }
        let inside = quadrature
            .iter()
            .filter(|&&q| self.contains(uv + h * q))
            .count();
        inside as f32 / quadrature.len() as f32
    }

    /// `M` sampled over the frame's bounding rectangle at spacing `h/4` (coarser where [`MAX_SAMPLES_PER_SIDE`] requires).
    pub fn grid(&self, frame: &PlanarFrame, h: f32, quadrature: &[Vec2]) -> MassGrid {
        let extent = (frame.max - frame.min).max(Vec2::ZERO);
        let cap = (MAX_SAMPLES_PER_SIDE - 1) as f32;
        let steps = (extent / (SPACING_PER_SUPPORT * h))
            .ceil()
            .clamp(Vec2::ONE, Vec2::splat(cap));
        let spacing = (extent / steps).max(Vec2::splat(f32::MIN_POSITIVE));
        let (columns, rows) = (steps.x as u32 + 1, steps.y as u32 + 1);
        let values = (0..rows * columns)
            .map(|k| {
                let (i, j) = (k % columns, k / columns);
                let uv = frame.min + Vec2::new(i as f32, j as f32) * spacing;
                self.mass(uv, h, quadrature)
            })
            .collect();
        MassGrid {
            min: frame.min,
            spacing,
            columns,
            rows,
            values,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square `[0, 1]²` as two triangles in the plane z = 0, with its frame.
    fn square() -> (Polygon, PlanarFrame) {
        let frame = PlanarFrame {
            origin: Vec3::ZERO,
            u_axis: Vec3::X,
            v_axis: Vec3::Y,
            normal: Vec3::Z,
            min: Vec2::ZERO,
            max: Vec2::ONE,
        };
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        (Polygon::from_world(&[[a, b, c], [a, c, d]], &frame), frame)
    }

    /// Silverman's kernel mass beyond a line at distance `t` (in units of `h`) from the centre, by Simpson's rule on its marginal `16/(5π) (1 - x²)^(5/2)`: independent of the disc quadrature.
    fn silverman_tail(t: f64) -> f64 {
        let n = 20_000;
        let g = |x: f64| 16.0 / (5.0 * std::f64::consts::PI) * (1.0 - x * x).max(0.0).powf(2.5);
        let step = (1.0 - t) / n as f64;
        let mut sum = g(t) + g(1.0);
        for i in 1..n {
            sum += g(t + i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * step / 3.0
    }

    #[test]
    fn the_marginal_integrates_to_one() {
        assert!((silverman_tail(-1.0) - 1.0).abs() < 1e-6);
        assert!((silverman_tail(0.0) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn square_has_four_boundary_edges_and_no_diagonal() {
        let (polygon, _) = square();
        assert_eq!(polygon.boundary.len(), 4);
        assert!(polygon.contains(Vec2::new(0.3, 0.7)));
        assert!(!polygon.contains(Vec2::new(1.2, 0.5)));
        assert!((polygon.boundary_distance(Vec2::new(0.5, 0.2)) - 0.2).abs() < 1e-6);
    }

    /// `M` against its exact values: 1 inside, 1/2 on an edge, 1/4 at a corner (by symmetry), and `1 − T(t)` at distance `t h` from one edge, for both kernels' quadratures where exact.
    #[test]
    fn mass_matches_the_half_plane_and_corner_values() {
        let (polygon, _) = square();
        let q = quadrature(Kernel::Silverman);
        let h = 0.2;
        assert_eq!(polygon.mass(Vec2::splat(0.5), h, &q), 1.0);
        for kernel in [Kernel::Silverman, Kernel::Gaussian] {
            let q = quadrature(kernel);
            let edge = polygon.mass(Vec2::new(0.5, 0.0), h, &q);
            assert!((edge - 0.5).abs() < 0.01, "{kernel:?} edge {edge}");
            let corner = polygon.mass(Vec2::ZERO, h, &q);
            assert!((corner - 0.25).abs() < 0.01, "{kernel:?} corner {corner}");
        }
        for t in [0.1f64, 0.3, 0.5, 0.8] {
            let got = polygon.mass(Vec2::new(0.5, t as f32 * h), h, &q) as f64;
            let want = 1.0 - silverman_tail(t);
            assert!((got - want).abs() < 0.012, "t {t}: {got} vs {want}");
        }
    }

    #[test]
    fn grid_interpolates_the_mass_and_stays_one_inside() {
        let (polygon, frame) = square();
        let q = quadrature(Kernel::Silverman);
        let h = 0.2;
        let grid = polygon.grid(&frame, h, &q);
        assert_eq!((grid.columns, grid.rows), (21, 21));
        assert_eq!(grid.at(Vec2::splat(0.5)), 1.0);
        for uv in [
            Vec2::new(0.37, 0.013),
            Vec2::new(0.02, 0.91),
            Vec2::new(0.6, 0.95),
        ] {
            let (g, m) = (grid.at(uv), polygon.mass(uv, h, &q));
            assert!((g - m).abs() < 0.02, "{uv}: grid {g} exact {m}");
        }
    }

    #[test]
    fn an_l_shaped_polygon_has_its_notch_outside() {
        // [0,2]x[0,1] plus [0,1]x[1,2]: six boundary edges once the shared ones cancel.
        let frame = PlanarFrame {
            origin: Vec3::ZERO,
            u_axis: Vec3::X,
            v_axis: Vec3::Y,
            normal: Vec3::Z,
            min: Vec2::ZERO,
            max: Vec2::splat(2.0),
        };
        let p = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let tris = [
            [p(0., 0.), p(1., 0.), p(1., 1.)],
            [p(0., 0.), p(1., 1.), p(0., 1.)],
            [p(1., 0.), p(2., 0.), p(2., 1.)],
            [p(1., 0.), p(2., 1.), p(1., 1.)],
            [p(0., 1.), p(1., 1.), p(1., 2.)],
            [p(0., 1.), p(1., 2.), p(0., 2.)],
        ];
        let polygon = Polygon::from_world(&tris, &frame);
        assert_eq!(polygon.boundary.len(), 8);
        let q = quadrature(Kernel::Silverman);
        // The re-entrant corner at (1, 1): three quarters of the kernel lie on the polygon.
        let m = polygon.mass(Vec2::ONE, 0.3, &q);
        assert!((m - 0.75).abs() < 0.01, "{m}");
        assert_eq!(polygon.mass(Vec2::splat(1.6), 0.3, &q), 0.0);
    }
}
