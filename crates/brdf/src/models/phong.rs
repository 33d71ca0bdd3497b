//! Phong's original model written as a BRDF (Phong 1975).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{
    Brdf, BrdfSample, diffuse_probability, mirror_lobe_mixture_pdf, reflect_z, same_upper,
    sample_mirror_lobe_mixture,
};
use crate::error::{BrdfError, Result, check_rgb};

/// Phong's model (B. T. Phong, "Illumination for computer generated pictures", CACM 18(6), 1975, equation 6) as a BRDF: `f = kd/π + ks cos^n α / cos θi`, α the angle between `wi` and the mirror direction of `wo`.
///
/// The shading formula `I = kd cos θi + ks cos^n α` becomes a BRDF by
/// dividing by `cos θi` (the rewriting of Lafortune & Willems 1994,
/// section 2), with the diffuse coefficient taken as a reflectance (hence
/// `/π`). Not reciprocal (the `1/cos θi`) and not energy conserving (the
/// albedo of the specular term grows without bound at grazing angles).
/// Sampled as a mixture of a cosine hemisphere and a `cos^n` lobe about the
/// mirror direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Phong {
    /// Diffuse reflectance kd in [0, 1].
    pub diffuse: Rgb,
    /// Specular coefficient ks, non-negative.
    pub specular: Rgb,
    /// Phong exponent n ≥ 0.
    pub exponent: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
}

/// Checks a Phong-like exponent: finite and non-negative.
pub(crate) fn check_exponent(model: &str, exponent: f32) -> Result<f32> {
    if !crate::brdf::is_non_negative(exponent) {
        return Err(BrdfError::OutOfRange {
            model: model.into(),
            param: "exponent".into(),
            value: exponent,
            expected: "finite and at least 0".into(),
        });
    }
    Ok(exponent)
}

impl Phong {
    /// Phong's model; errors when kd leaves [0, 1], ks is negative or n is negative or not finite.
    pub fn new(diffuse: Rgb, specular: Rgb, exponent: f32) -> Result<Self> {
        check_rgb("phong", "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb("phong", "specular", specular, 0.0, f32::MAX)?;
        check_exponent("phong", exponent)?;
        Ok(Self {
            diffuse,
            specular,
            exponent,
            p_diffuse: diffuse_probability(diffuse, specular),
        })
    }
}

impl Brdf for Phong {
    fn name(&self) -> &'static str {
        "phong"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let cos_alpha = wi.dot(reflect_z(wo)).max(0.0);
        self.diffuse * FRAC_1_PI + self.specular * cos_alpha.powf(self.exponent) / wi.z
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_mirror_lobe_mixture(self, wo, u, u_lobe, self.p_diffuse, self.exponent)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        mirror_lobe_mixture_pdf(wi, wo, self.p_diffuse, self.exponent)
    }

    fn is_reciprocal(&self) -> bool {
        false
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
