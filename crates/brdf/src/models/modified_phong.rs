//! The energy-normalised modified Phong BRDF (Lafortune & Willems 1994).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use super::phong::check_exponent;
use crate::brdf::{
    Brdf, BrdfSample, diffuse_probability, mirror_lobe_mixture_pdf, reflect_z, same_upper,
    sample_mirror_lobe_mixture,
};
use crate::error::{Result, check_rgb, check_sum};

/// Modified Phong `f = kd/π + ks (n + 2)/(2π) cos^n α` (E. P. Lafortune and Y. D. Willems, "Using the modified Phong reflectance model for physically based rendering", report CW 197, KU Leuven 1994, equation 4).
///
/// Reciprocal; energy conserving when `kd + ks ≤ 1` per channel (enforced):
/// the specular albedo is `ks` at normal incidence and less elsewhere
/// (Lafortune & Willems 1994, section 3). Sampled as the mixture of a cosine
/// hemisphere and the `cos^n α` lobe with their exact densities (section 4).
#[derive(Debug, Clone, PartialEq)]
pub struct ModifiedPhong {
    /// Diffuse reflectance kd.
    pub diffuse: Rgb,
    /// Specular reflectance ks (its albedo at normal incidence).
    pub specular: Rgb,
    /// Phong exponent n ≥ 0.
    pub exponent: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
    /// Name reported by [`Brdf::name`] (the same BRDF is also Lewis 1994's).
    name: &'static str,
}

impl ModifiedPhong {
    /// The modified Phong BRDF; errors when kd or ks leaves [0, 1], kd + ks exceeds one or n is negative.
    pub fn new(diffuse: Rgb, specular: Rgb, exponent: f32) -> Result<Self> {
        Self::named("modified-phong", diffuse, specular, exponent)
    }

    /// As [`ModifiedPhong::new`], reporting `name` in errors and from [`Brdf::name`].
    pub(crate) fn named(
        name: &'static str,
        diffuse: Rgb,
        specular: Rgb,
        exponent: f32,
    ) -> Result<Self> {
        check_rgb(name, "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb(name, "specular", specular, 0.0, 1.0)?;
        check_sum(name, diffuse, specular)?;
        check_exponent(name, exponent)?;
        Ok(Self {
            diffuse,
            specular,
            exponent,
            p_diffuse: diffuse_probability(diffuse, specular),
            name,
        })
    }
}

impl Brdf for ModifiedPhong {
    fn name(&self) -> &'static str {
        self.name
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let cos_alpha = wi.dot(reflect_z(wo)).max(0.0);
        let n = self.exponent;
        self.diffuse * FRAC_1_PI + self.specular * (n + 2.0) * 0.5 * FRAC_1_PI * cos_alpha.powf(n)
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_mirror_lobe_mixture(self, wo, u, u_lobe, self.p_diffuse, self.exponent)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        mirror_lobe_mixture_pdf(wi, wo, self.p_diffuse, self.exponent)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        true
    }
}
