//! Perfectly diffuse reflection (Lambert 1760, *Photometria*).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;
use lustre_geometry::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

use crate::brdf::{Brdf, BrdfSample, finish_sample, same_upper};
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
        if wo.z <= 0.0 {
            return None;
        }
        finish_sample(self, sample_cosine_hemisphere(u), wo)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !same_upper(wi, wo) {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi.z)
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
