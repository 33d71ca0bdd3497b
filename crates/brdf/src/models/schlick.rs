//! Schlick's inexpensive physically plausible BRDF (Schlick 1994).

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample, finish_sample, reflect, same_upper};
use crate::error::{Result, check_range, check_rgb};
use crate::fresnel::fresnel_schlick;

/// Schlick's single-layer model `f = S(u) [G(v)G(v') Z(t) A(w) / (4π v v') + (1 - G(v)G(v'))/π]` (C. Schlick, "An inexpensive BRDF model for physically-based rendering", Computer Graphics Forum 13(3), 1994, equations 15, 24-28).
///
/// `S(u) = C + (1 - C)(1 - u)^5` with `u = wi·h`; `Z(t) = r / (1 + r t² - t²)²`
/// with `t = cos θh`; `A(w) = √(p / (p² - p² w² + w²))` with `w` the cosine of
/// the azimuth of `h` from the tangent; `G(v) = v / (r - r v + v)`. The
/// second term re-emits the light lost to shadowing diffusely (section 5.2).
/// Simplification: the paper's `A(w)` averages to one over the azimuth only
/// for `p = 1`, so it is divided by its numerically computed mean (4096
/// midpoints) to keep `Z A / π` a normalised distribution. Reciprocal. Not
/// claimed energy conserving: the paper argues it is, but with its
/// approximate `G` the re-emitted term over-compensates at grazing angles
/// (numerically, albedo 1.08 at θo = 75° for C = 0.9, r = 0.3, p = 0.4). Sampled by drawing `t` from `Z` (its
/// inverse is closed form) and the azimuth uniformly, and reflecting `wo`,
/// mixed half and half with a cosine hemisphere for the diffuse term.
#[derive(Debug, Clone, PartialEq)]
pub struct Schlick {
    /// Reflectance factor C at normal incidence.
    pub reflectance: Rgb,
    /// Roughness r in (0, 1] (0 is a mirror, 1 is Lambertian).
    pub roughness: f32,
    /// Isotropy p in (0, 1] (1 is isotropic).
    pub isotropy: f32,
    /// Mean of `A(w)` over the azimuth.
    a_mean: f32,
}

impl Schlick {
    /// Schlick's model; errors when C leaves [0, 1] or r, p leave (0, 1].
    pub fn new(reflectance: Rgb, roughness: f32, isotropy: f32) -> Result<Self> {
        check_rgb("schlick", "reflectance", reflectance, 0.0, 1.0)?;
        check_range("schlick", "roughness", roughness, 1e-4, 1.0)?;
        check_range("schlick", "isotropy", isotropy, 1e-4, 1.0)?;
        let n = 4096;
        let mut sum = 0.0_f64;
        for i in 0..n {
            let phi = (i as f64 + 0.5) / n as f64 * std::f64::consts::TAU;
            sum += f64::from(a_factor(isotropy, phi.cos() as f32));
        }
        Ok(Self {
            reflectance,
            roughness,
            isotropy,
            a_mean: (sum / n as f64) as f32,
        })
    }

    /// Schlick's `G(v) = v / (r - r v + v)` (equation 27).
    fn g(&self, v: f32) -> f32 {
        let r = self.roughness;
        v / (r - r * v + v)
    }

    /// Schlick's `Z(t) = r / (1 + r t² - t²)²` (equation 28).
    fn z(&self, t: f32) -> f32 {
        let r = self.roughness;
        let d = 1.0 + r * t * t - t * t;
        r / (d * d)
    }

    /// The normalised azimuthal factor `A(w) / mean(A)` for the half vector `h`.
    fn a(&self, h: Vec3) -> f32 {
        let rxy = (h.x * h.x + h.y * h.y).sqrt();
        let w = if rxy > 0.0 { h.x / rxy } else { 1.0 };
        a_factor(self.isotropy, w) / self.a_mean
    }

    /// Density of the half-vector draw: `Z(t) t / π` (uniform azimuth).
    fn pdf_h(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        self.z(h.z) * h.z * FRAC_1_PI
    }
}

/// Schlick's `A(w) = √(p / (p² - p² w² + w²))` (equation 26).
fn a_factor(p: f32, w: f32) -> f32 {
    (p / (p * p - p * p * w * w + w * w)).sqrt()
}

impl Brdf for Schlick {
    fn name(&self) -> &'static str {
        "schlick"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let gg = self.g(wi.z) * self.g(wo.z);
        let d = gg * self.z(h.z) * self.a(h) / (4.0 * PI * wi.z * wo.z) + (1.0 - gg) * FRAC_1_PI;
        fresnel_schlick(wi.dot(h), self.reflectance) * d
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < 0.5 {
            lustre_geometry::sampling::sample_cosine_hemisphere(u)
        } else {
            // Invert the CDF of x = t², F(x) = r x / (1 + (r - 1) x).
            let r = self.roughness;
            let x = u.x / (r + u.x - u.x * r);
            let t = x.clamp(0.0, 1.0).sqrt();
            let s = (1.0 - t * t).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let h = Vec3::new(s * phi.cos(), s * phi.sin(), t);
            if h.dot(wo) <= 0.0 {
                return None;
            }
            reflect(wo, h)
        };
        finish_sample(self, wi, wo)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !same_upper(wi, wo) {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        0.5 * wi.z * FRAC_1_PI + 0.5 * self.pdf_h(h) / (4.0 * wo.dot(h))
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
