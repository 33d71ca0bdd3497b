//! The Oren-Nayar rough diffuse model (Oren & Nayar 1994): the qualitative model and the full model.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample, cosine_pdf, same_upper, sample_cosine};
use crate::error::{Result, check_range, check_rgb};

/// Oren-Nayar's qualitative model `f = ρ/π (A + B max(0, cos(φi - φo)) sin α tan β)`, `A = 1 - 0.5 σ²/(σ² + 0.33)`, `B = 0.45 σ²/(σ² + 0.09)`, α = max(θi, θo), β = min(θi, θo) (M. Oren and S. K. Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994, equation 30).
///
/// Simplification: the qualitative model of the paper's section 4.4, not the
/// full model of equations 27-28 (see [`OrenNayarFull`] for that one).
/// Registered as `oren-nayar`. Reciprocal. Not claimed energy
/// conserving (the qualitative fit is not bounded by construction). Sampled
/// from a cosine hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct OrenNayarQualitative {
    /// Albedo ρ of the facets.
    pub reflectance: Rgb,
    /// Standard deviation σ of the facet slope angle, radians.
    pub sigma: f32,
    /// The coefficient A.
    a: f32,
    /// The coefficient B.
    b: f32,
}

impl OrenNayarQualitative {
    /// The qualitative Oren-Nayar model; errors when ρ leaves [0, 1] or σ leaves [0, π/2].
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

impl Brdf for OrenNayarQualitative {
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
        sample_cosine(self, wo, u)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        cosine_pdf(wi, wo)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}

/// Oren-Nayar's full model: the direct term `L1` of equation 27 with the coefficients `C1`, `C2`, `C3` plus the interreflection term `L2` of equation 28, divided by the irradiance `E0 cos θi` (M. Oren and S. K. Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994, section 4.3).
///
/// ```text
/// f = ρ/π [C1 + cos(φr - φi) C2 tan β + (1 - |cos(φr - φi)|) C3 tan((α + β)/2)]
///   + 0.17 ρ²/π σ²/(σ² + 0.13) [1 - cos(φr - φi) (2β/π)²]
/// ```
///
/// with `C1 = 1 - 0.5 σ²/(σ² + 0.33)`, `C2 = 0.45 σ²/(σ² + 0.09) sin α` when
/// `cos(φr - φi) ≥ 0` and `0.45 σ²/(σ² + 0.09) (sin α - (2β/π)³)` otherwise,
/// `C3 = 0.125 σ²/(σ² + 0.09) (4αβ/π²)²`, α = max(θi, θr), β = min(θi, θr).
/// The direct term is clamped at zero: near grazing, at opposite azimuths,
/// the fitted `C2 tan β` can outweigh `C1`. Registered as
/// `oren-nayar-full`. Reciprocal (every term is symmetric in the two
/// directions); equal to Lambert at σ = 0. Not claimed energy conserving
/// (the fitted coefficients bound nothing). Sampled from a cosine
/// hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct OrenNayarFull {
    /// Albedo ρ of the facets.
    pub reflectance: Rgb,
    /// Standard deviation σ of the facet slope angle, radians.
    pub sigma: f32,
}

impl OrenNayarFull {
    /// The full Oren-Nayar model; errors when ρ leaves [0, 1] or σ leaves [0, π/2].
    pub fn new(reflectance: Rgb, sigma: f32) -> Result<Self> {
        check_rgb("oren-nayar-full", "reflectance", reflectance, 0.0, 1.0)?;
        check_range(
            "oren-nayar-full",
            "sigma",
            sigma,
            0.0,
            std::f32::consts::FRAC_PI_2,
        )?;
        Ok(Self { reflectance, sigma })
    }
}

impl Brdf for OrenNayarFull {
    fn name(&self) -> &'static str {
        "oren-nayar-full"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        use std::f32::consts::PI;
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let theta_i = wi.z.min(1.0).acos();
        let theta_r = wo.z.min(1.0).acos();
        let sin_i = theta_i.sin();
        let sin_r = theta_r.sin();
        let cos_dphi = if sin_i > 1e-6 && sin_r > 1e-6 {
            ((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_r)).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let alpha = theta_i.max(theta_r);
        let beta = theta_i.min(theta_r);
        let s2 = self.sigma * self.sigma;
        let c1 = 1.0 - 0.5 * s2 / (s2 + 0.33);
        let two_beta_over_pi = 2.0 * beta / PI;
        let c2 = if cos_dphi >= 0.0 {
            0.45 * s2 / (s2 + 0.09) * alpha.sin()
        } else {
            0.45 * s2 / (s2 + 0.09) * (alpha.sin() - two_beta_over_pi.powi(3))
        };
        let c3 = 0.125 * s2 / (s2 + 0.09) * (4.0 * alpha * beta / (PI * PI)).powi(2);
        // tan β and tan((α + β)/2) stay finite: β ≤ α < π/2 strictly for upper directions.
        let direct = c1
            + cos_dphi * c2 * beta.tan()
            + (1.0 - cos_dphi.abs()) * c3 * (0.5 * (alpha + beta)).tan();
        let inter =
            0.17 * s2 / (s2 + 0.13) * (1.0 - cos_dphi * two_beta_over_pi * two_beta_over_pi);
        let rho = self.reflectance;
        (rho * direct.max(0.0) + rho * rho * inter) * FRAC_1_PI
    }

    fn sample(&self, wo: Vec3, u: Vec2, _u_lobe: f32) -> Option<BrdfSample> {
        sample_cosine(self, wo, u)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        cosine_pdf(wi, wo)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
