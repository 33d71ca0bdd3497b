//! Perfectly diffuse reflection (Lambert 1760, *Photometria*).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample, cosine_pdf, same_upper, sample_cosine};
use crate::error::{Result, check_rgb};

/// Lambertian reflector `f = ρ / π` (Lambert 1760): reciprocal; energy conserving for ρ ≤ 1 (albedo = ρ exactly).
#[derive(Debug, Clone, PartialEq)]
pub struct Lambert {
    /// Hemispherical reflectance ρ in [0, 1].
    pub reflectance: Rgb,
}

impl Lambert {
    /// A Lambertian reflector; errors when a channel of `reflectance` is outside [0, 1].
    pub fn new(reflectance: Rgb) -> Result<Self> {
        check_rgb("lambert", "reflectance", reflectance, 0.0, 1.0)?;
        Ok(Self { reflectance })
    }
}

impl Brdf for Lambert {
    fn name(&self) -> &'static str {
        "lambert"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        self.reflectance * FRAC_1_PI
    }

    fn sample(&self, wo: Vec3, u: Vec2, _u_lobe: f32) -> Option<BrdfSample> {
        sample_cosine(self, wo, u)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        cosine_pdf(wi, wo)
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            Rgb::ZERO
        } else {
            self.reflectance
        }
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        true
    }
}
