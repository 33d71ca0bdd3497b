//! The Blinn(-Phong) half-vector model (Blinn 1977).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use super::phong::check_exponent;
use crate::brdf::{
    Brdf, BrdfSample, diffuse_probability, half_vector_mixture_pdf, same_upper,
    sample_half_vector_mixture,
};
use crate::error::{Result, check_rgb};

/// Blinn-Phong `f = kd/π + ks (n + 8)/(8π) cos^n θh`, θh the angle between the half vector and the normal (J. F. Blinn, "Models of light reflection for computer synthesized pictures", SIGGRAPH 1977, the `(N·H)^n` distribution; normalisation of Akenine-Möller & Haines, *Real-Time Rendering* 2nd ed., equation 7.49).
///
/// Reciprocal. Not guaranteed energy conserving: the `(n + 8)/(8π)` factor
/// is an approximate normalisation. Sampled by drawing the half vector
/// from `(n + 1)/(2π) cos^n θh` and reflecting `wo` about it (density
/// `p_h / (4 wo·h)`, Walter et al. 2007 equation 14), mixed with a cosine
/// hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct BlinnPhong {
    /// Diffuse reflectance kd.
    pub diffuse: Rgb,
    /// Specular coefficient ks.
    pub specular: Rgb,
    /// Exponent n ≥ 0.
    pub exponent: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
}

impl BlinnPhong {
    /// Blinn-Phong; errors when kd or ks leaves [0, 1] or n is negative.
    pub fn new(diffuse: Rgb, specular: Rgb, exponent: f32) -> Result<Self> {
        check_rgb("blinn-phong", "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb("blinn-phong", "specular", specular, 0.0, 1.0)?;
        check_exponent("blinn-phong", exponent)?;
        Ok(Self {
            diffuse,
            specular,
            exponent,
            p_diffuse: diffuse_probability(diffuse, specular),
        })
    }
}

impl Brdf for BlinnPhong {
    fn name(&self) -> &'static str {
        "blinn-phong"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let n = self.exponent;
        self.diffuse * FRAC_1_PI + self.specular * (n + 8.0) * 0.125 * FRAC_1_PI * h.z.powf(n)
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_half_vector_mixture(self, wo, u, u_lobe, self.p_diffuse, self.exponent)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        half_vector_mixture_pdf(wi, wo, self.p_diffuse, self.exponent)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
