//! The reflectance modulation texture R of Bastos et al.'s BRDF decomposition, `F / (π (N·L)(N·V))`, as a sphere map and as the 1D radial table the paper recommends for isotropic BRDFs (R. Bastos, K. Hoff, W. Wynn and A. Lastra, I3D 1999, section 8.2.2, equation 4, and section 9).
//!
//! **Sphere-map parameterisation** (OpenGL's `GL_SPHERE_MAP`, the paper's
//! reference 15). A texel at texture coordinates `(s, t)` in [0, 1]² has
//! disk coordinates `(x, y) = (2s - 1, 2t - 1)` and radius `ρ = √(x² + y²)`;
//! texels with `ρ > 1` lie outside the inscribed disk and are zero. Inside,
//! the texel is the point of a mirrored unit sphere with normal
//! `n = (x, y, √(1 - ρ²))`, seen along `v = +Z`; the reflected vector is
//! `r = 2 (n·v) n - v = (2 nz x, 2 nz y, 2 nz² - 1)`. Conversely a reflected
//! vector indexes the map at `(s, t) = (rx/m + ½, ry/m + ½)` with
//! `m = 2 √(rx² + ry² + (rz + 1)²)`. In the mirror configuration of the
//! texel `N·L = N·V = cos θ = nz = √(1 - ρ²)`: the centre (ρ = 0) is normal
//! incidence, reflected vector parallel to the normal, and the ring
//! (ρ → 1) is grazing, reflected vector orthogonal to the normal, as the
//! paper describes. So a texel holds `R = F(cos θ) / (π cos² θ)` with
//! `cos θ = √(1 - ρ²)`, growing without bound towards the ring (the
//! outermost texel centres stay inside it, so every value is finite).
//!
//! **Radial table.** R depends on ρ only, so an isotropic BRDF needs only a
//! 1D texture indexed by ρ (section 9): entry k holds R at the texel centre
//! `ρk = (k + ½) / M`, and [`RadialReflectance::eval`] interpolates linearly
//! with clamp-to-edge, as a GPU's linear filter would.

use lustre_geometry::Rgb;

use crate::error::{BrdfError, Result};
use crate::fresnel::Fresnel;
use crate::texture::TextureRgba32F;

/// `R = F(cos θ) / (π cos² θ)`, the second factor of equation 4 in the mirror configuration `N·L = N·V = cos θ` (Bastos et al. 1999, equation 4); zero for `cos θ ≤ 0`.
pub fn reflectance_modulation(fresnel: &Fresnel, cos_theta: f32) -> Rgb {
    if !(cos_theta > 0.0) {
        return Rgb::ZERO;
    }
    let c = cos_theta.min(1.0);
    fresnel.eval(c) / (std::f32::consts::PI * c * c)
}

/// `cos θ = √(1 - ρ²)` of the mirror configuration at sphere-map radius ρ (module documentation).
pub fn sphere_map_cos_theta(rho: f32) -> f32 {
    (1.0 - rho * rho).max(0.0).sqrt()
}

/// Checks a texture size: 1 to 8192 texels.
fn check_size(param: &str, size: u32) -> Result<()> {
    if !(1..=8192).contains(&size) {
        return Err(BrdfError::OutOfRange {
            model: "reflectance-modulation".into(),
            param: param.into(),
            value: size as f32,
            expected: "1 to 8192".into(),
        });
    }
    Ok(())
}

/// The reflectance sphere map: a `size × size` texture of R over the sphere-map parameterisation, RGB = R and A = 1 inside the inscribed disk, all zero outside (Bastos et al. 1999, section 8.2.2, figure 6).
pub fn reflectance_sphere_map(fresnel: &Fresnel, size: u32) -> Result<TextureRgba32F> {
    check_size("size", size)?;
    let mut t = TextureRgba32F::zeros(size, size);
    let n = size as f32;
    for j in 0..size {
        for i in 0..size {
            let x = (2.0 * i as f32 + 1.0 - n) / n;
            let y = (2.0 * j as f32 + 1.0 - n) / n;
            let rho = (x * x + y * y).sqrt();
            if rho > 1.0 {
                continue;
            }
            let r = reflectance_modulation(fresnel, sphere_map_cos_theta(rho));
            t.set_texel(i, j, [r.x, r.y, r.z, 1.0]);
        }
    }
    Ok(t)
}

/// Linear interpolation of a non-empty table whose entry k sits at `(k + ½)/M` in [0, 1], clamped to its end entries: a GPU's linear filter on a 1D texture.
fn linear_clamped(values: &[Rgb], u: f32) -> Rgb {
    let m = values.len();
    if m == 1 {
        return values[0];
    }
    let x = (u.max(0.0) * m as f32 - 0.5).clamp(0.0, (m - 1) as f32);
    let i = (x.floor() as usize).min(m - 2);
    let t = x - i as f32;
    values[i] * (1.0 - t) + values[i + 1] * t
}

/// The 1D radial reflectance table for isotropic BRDFs: R at `ρk = (k + ½)/M` (Bastos et al. 1999, section 9: "a one-dimensional texture-map indexed by the radius of the sphere-mapping indexing scheme").
#[derive(Debug, Clone, PartialEq)]
pub struct RadialReflectance {
    /// R at the entry centres ρk = (k + ½)/M.
    pub values: Vec<Rgb>,
}

impl RadialReflectance {
    /// The table with `len` entries for `fresnel`.
    pub fn new(fresnel: &Fresnel, len: u32) -> Result<Self> {
        check_size("len", len)?;
        let m = len as f32;
        let values = (0..len)
            .map(|k| reflectance_modulation(fresnel, sphere_map_cos_theta((k as f32 + 0.5) / m)))
            .collect();
        Ok(Self { values })
    }

    /// Linear interpolation at radius ρ in [0, 1] with clamp-to-edge (a GPU's linear filter on the 1D texture); zero beyond the disk (ρ > 1).
    pub fn eval(&self, rho: f32) -> Rgb {
        if !(rho <= 1.0) || self.values.is_empty() {
            return Rgb::ZERO;
        }
        linear_clamped(&self.values, rho)
    }

    /// The table as a `M × 1` RGBA texture (A = 1).
    pub fn to_texture(&self) -> TextureRgba32F {
        let mut t = TextureRgba32F::zeros(self.values.len() as u32, 1);
        for (k, v) in self.values.iter().enumerate() {
            t.set_texel(k as u32, 0, [v.x, v.y, v.z, 1.0]);
        }
        t
    }
}

/// The 1D reflectance table indexed by the flipped sphere-map scheme of section 9: entry k holds R at `cos θ = (k + ½)/M`, so grazing directions (`cos θ → 0`) index the start of the table, the region of finest angular resolution, instead of the sphere map's outer ring (Bastos et al. 1999, section 9: "flip the sphere-mapping indexing scheme").
///
/// With the sphere map's index `ρ = sin θ`, the outermost of `M` entries
/// spans `cos θ` from 0 to `√(2/M)`; indexed by `cos θ` it spans `1/M`, a
/// `√(2M)` times finer step where R = F/(π cos² θ) changes fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct FlippedRadialReflectance {
    /// R at the entry centres `cos θk = (k + ½)/M`.
    pub values: Vec<Rgb>,
}

impl FlippedRadialReflectance {
    /// The table with `len` entries for `fresnel`.
    pub fn new(fresnel: &Fresnel, len: u32) -> Result<Self> {
        check_size("len", len)?;
        let m = len as f32;
        let values = (0..len)
            .map(|k| reflectance_modulation(fresnel, (k as f32 + 0.5) / m))
            .collect();
        Ok(Self { values })
    }

    /// A table of `len` entries of any modulation `f(cos θ)` under the same flipped index (a BRDF's directional albedo, for one).
    pub fn from_fn(len: u32, f: impl Fn(f32) -> Rgb) -> Result<Self> {
        check_size("len", len)?;
        let m = len as f32;
        let values = (0..len).map(|k| f((k as f32 + 0.5) / m)).collect();
        Ok(Self { values })
    }

    /// Linear interpolation at `cos θ` in [0, 1] with clamp-to-edge (a GPU's linear filter); zero for `cos θ ≤ 0`.
    pub fn eval(&self, cos_theta: f32) -> Rgb {
        if !(cos_theta > 0.0) || self.values.is_empty() {
            return Rgb::ZERO;
        }
        linear_clamped(&self.values, cos_theta.min(1.0))
    }

    /// The table as a `M × 1` RGBA texture (A = 1).
    pub fn to_texture(&self) -> TextureRgba32F {
        let mut t = TextureRgba32F::zeros(self.values.len() as u32, 1);
        for (k, v) in self.values.iter().enumerate() {
            t.set_texel(k as u32, 0, [v.x, v.y, v.z, 1.0]);
        }
        t
    }
}
