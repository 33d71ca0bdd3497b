//! The Oren-Nayar rough diffuse model (Oren & Nayar 1994).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;
use lustre_geometry::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

use crate::brdf::{Brdf, BrdfSample, finish_sample, same_upper};
use crate::error::{Result, check_range, check_rgb};

/// Oren-Nayar's qualitative model `f = ρ/π (A + B max(0, cos(φi - φo)) sin α tan β)`, `A = 1 - 0.5 σ²/(σ² + 0.33)`, `B = 0.45 σ²/(σ² + 0.09)`, α = max(θi, θo), β = min(θi, θo) (M. Oren and S. K. Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994, equation 30).
///
/// Simplification: the qualitative model of the paper's section 4.4, not the
/// full model of equation 27 with its `C2`, `C3` terms and the
/// interreflection term of equation 28. Reciprocal. Not claimed energy
/// conserving (the qualitative fit is not bounded by construction). Sampled
/// from a cosine hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct OrenNayar {
    /// Albedo ρ of the facets.
    pub reflectance: Rgb,
    /// Standard deviation σ of the facet slope angle, radians.
    pub sigma: f32,
    /// The coefficient A.
    a: f32,
    /// The coefficient B.
    b: f32,
}

impl OrenNayar {
    /// Oren-Nayar; errors when ρ leaves [0, 1] or σ leaves [0, π/2].
    pub fn new(reflectance: Rgb, sigma: f32) -> Result<Self> {
        check_rgb("oren-nayar", "reflectance", reflectance, 0.0, 1.0)?;
        check_range(
            "oren-nayar",
            "sigma",
            sigma,
            0.0,
            std::f32::consts::FRAC_PI_2,
        )?;
        let s2 = sigma * sigma;
        Ok(Self {
            reflectance,
            sigma,
            a: 1.0 - 0.5 * s2 / (s2 + 0.33),
            b: 0.45 * s2 / (s2 + 0.09),
        })
    }
}

impl Brdf for OrenNayar {
    fn name(&self) -> &'static str {
        "oren-nayar"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let sin_i = (1.0 - wi.z * wi.z).max(0.0).sqrt();
        let sin_o = (1.0 - wo.z * wo.z).max(0.0).sqrt();
        let mut extra = 0.0;
        if sin_i > 1e-6 && sin_o > 1e-6 {
            let cos_dphi = ((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o)).clamp(-1.0, 1.0);
            if cos_dphi > 0.0 {
                // α = max(θi, θo) has the smaller cosine; β = min has the larger.
                let (sin_alpha, tan_beta) = if wi.z < wo.z {
                    (sin_i, sin_o / wo.z)
                } else {
                    (sin_o, sin_i / wi.z)
                };
                extra = self.b * cos_dphi * sin_alpha * tan_beta;
            }
        }
        self.reflectance * FRAC_1_PI * (self.a + extra)
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

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
