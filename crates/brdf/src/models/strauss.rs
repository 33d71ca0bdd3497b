//! Strauss's realistic lighting model for animators (Strauss 1990).

use std::f32::consts::{FRAC_1_PI, FRAC_2_PI};

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{
    Brdf, BrdfSample, mirror_lobe_mixture_pdf, reflect_z, same_upper, sample_mirror_lobe_mixture,
};
use crate::error::{Result, check_range, check_rgb};

/// Strauss's constant k in `rs = min(1, rn + (rn + k) j)` (Strauss 1990, section 3.2).
const K: f32 = 0.1;
/// The pole of Strauss's Fresnel approximation (`kf = 1.12`).
const KF: f32 = 1.12;
/// The pole of Strauss's shadow approximation (`kg = 1.01`).
const KG: f32 = 1.01;

/// Strauss's Fresnel approximation `F(x) = (1/(x - kf)² - 1/kf²) / (1/(1 - kf)² - 1/kf²)`, x the angle over π/2 (Strauss 1990, section 3.3).
fn strauss_f(x: f32) -> f32 {
    (1.0 / ((x - KF) * (x - KF)) - 1.0 / (KF * KF))
        / (1.0 / ((1.0 - KF) * (1.0 - KF)) - 1.0 / (KF * KF))
}

/// Strauss's shadow approximation `G(x) = (1/(1 - kg)² - 1/(x - kg)²) / (1/(1 - kg)² - 1/kg²)` (Strauss 1990, section 3.3).
fn strauss_g(x: f32) -> f32 {
    (1.0 / ((1.0 - KG) * (1.0 - KG)) - 1.0 / ((x - KG) * (x - KG)))
        / (1.0 / ((1.0 - KG) * (1.0 - KG)) - 1.0 / (KG * KG))
}

/// Strauss's model (P. S. Strauss, "A realistic lighting model for computer animators", IEEE CG&A 10(6), 1990, section 3): diffuse `d rd C` with `d = 1 - m s`, `rd = (1 - s³)(1 - t)`, specular `rs Cs (R·V)^h` with `h = 3/(1 - s)`, `rs = min(1, rn + (rn + k) F(θi) G(θi) G(θo))`, `rn = (1 - t) - rd`, `Cs = 1 + m (1 - F(θi))(C - 1)`.
///
/// Strauss's terms are shading intensities `Q = Qd + Qs` with
/// `Qd = cos θi · d rd C`; as a BRDF `f = d rd C / π + rs Cs cos^h α / cos θi`
/// (the diffuse coefficient read as a reflectance, as for [`super::phong::Phong`]).
/// Transparency only removes energy here (the transmitted term of the paper
/// is not modelled). Not reciprocal (F and G act on θi only, and the
/// `1/cos θi`), not energy conserving. Sampled as a cosine hemisphere mixed
/// with a `cos^h` lobe about the mirror direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Strauss {
    /// Surface colour C.
    pub color: Rgb,
    /// Smoothness s in [0, 1).
    pub smoothness: f32,
    /// Metalness m in [0, 1].
    pub metalness: f32,
    /// Transparency t in [0, 1].
    pub transparency: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
}

impl Strauss {
    /// Strauss's model; errors when C, m, t leave [0, 1] or s leaves [0, 0.999].
    pub fn new(color: Rgb, smoothness: f32, metalness: f32, transparency: f32) -> Result<Self> {
        check_rgb("strauss", "color", color, 0.0, 1.0)?;
        check_range("strauss", "smoothness", smoothness, 0.0, 0.999)?;
        check_range("strauss", "metalness", metalness, 0.0, 1.0)?;
        check_range("strauss", "transparency", transparency, 0.0, 1.0)?;
        let s = smoothness;
        let rd = (1.0 - s * s * s) * (1.0 - transparency);
        let diffuse = (1.0 - metalness * s) * rd * crate::brdf::mean(color);
        let rn = (1.0 - transparency) - rd;
        let spec = (rn + K).min(1.0);
        let p_diffuse = if diffuse + spec > 0.0 {
            diffuse / (diffuse + spec)
        } else {
            1.0
        };
        Ok(Self {
            color,
            smoothness,
            metalness,
            transparency,
            p_diffuse,
        })
    }

    /// The highlight exponent `h = 3 / (1 - s)`.
    fn exponent(&self) -> f32 {
        3.0 / (1.0 - self.smoothness)
    }
}

impl Brdf for Strauss {
    fn name(&self) -> &'static str {
        "strauss"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let (s, m, t) = (self.smoothness, self.metalness, self.transparency);
        let d = 1.0 - m * s;
        let rd = (1.0 - s * s * s) * (1.0 - t);
        let diffuse = self.color * (d * rd * FRAC_1_PI);
        let x_i = wi.z.clamp(0.0, 1.0).acos() * FRAC_2_PI;
        let x_o = wo.z.clamp(0.0, 1.0).acos() * FRAC_2_PI;
        let f_i = strauss_f(x_i);
        let j = f_i * strauss_g(x_i) * strauss_g(x_o);
        let rn = (1.0 - t) - rd;
        let rs = (rn + (rn + K) * j).clamp(0.0, 1.0);
        let cs = Rgb::ONE + m * (1.0 - f_i) * (self.color - Rgb::ONE);
        let cos_alpha = wi.dot(reflect_z(wo)).max(0.0);
        diffuse + cs * (rs * cos_alpha.powf(self.exponent()) / wi.z)
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_mirror_lobe_mixture(self, wo, u, u_lobe, self.p_diffuse, self.exponent())
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        mirror_lobe_mixture_pdf(wi, wo, self.p_diffuse, self.exponent())
    }

    fn is_reciprocal(&self) -> bool {
        false
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
