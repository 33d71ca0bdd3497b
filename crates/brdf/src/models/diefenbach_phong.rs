//! Diefenbach's hardware Phong term fitted to Ward's Gaussian, written as a BRDF (Diefenbach & Badler 1997).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{
    Brdf, BrdfSample, diffuse_probability, half_vector_mixture_pdf, same_upper,
    sample_half_vector_mixture,
};
use crate::diefenbach_fit::{DIEFENBACH_AMPLITUDE, DIEFENBACH_EXPONENT_SCALE};
use crate::error::{BrdfError, Result, check_rgb, check_sum};

/// The fitted Phong model `f = ρd/π + c n ρs cos(δ)^n / cos θi`, `n = b/α²`, `c = 0.0398`, `b = 1.999` (P. J. Diefenbach and N. I. Badler, "Multi-pass pipeline rendering", I3D 1997, equation 6).
///
/// Equation 6 stands for `cos θi` times Ward's specular lobe (equation 5),
/// the value a hardware light adds per unit intensity, so the BRDF is it
/// divided by `cos θi`; `f cos θi` is then exactly the paper's hardware term
/// plus the diffuse one. Registered as `diefenbach-phong`. Not reciprocal
/// (the `1/cos θi`), not claimed energy conserving. Sampled like
/// Blinn-Phong: `h` from `(n + 1)/(2π) cos^n δ`, reflected, mixed with a
/// cosine hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct DiefenbachPhong {
    /// Diffuse reflectance ρd.
    pub diffuse: Rgb,
    /// Ward's specular reflectance ρs.
    pub specular: Rgb,
    /// Ward's RMS slope α.
    pub alpha: f32,
    /// The amplitude c of equation 6.
    pub amplitude: f32,
    /// The exponent n = b/α² of equation 6.
    pub exponent: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
}

impl DiefenbachPhong {
    /// The paper's fit (c = 0.0398, b = 1.999); errors when ρd or ρs leaves [0, 1], ρd + ρs > 1, or α is not positive.
    pub fn new(diffuse: Rgb, specular: Rgb, alpha: f32) -> Result<Self> {
        Self::with_coefficients(
            diffuse,
            specular,
            alpha,
            DIEFENBACH_AMPLITUDE,
            DIEFENBACH_EXPONENT_SCALE,
        )
    }

    /// The same form with other fitted coefficients c and b (for instance from [`crate::diefenbach_fit::fit_phong_to_ward`]).
    pub fn with_coefficients(
        diffuse: Rgb,
        specular: Rgb,
        alpha: f32,
        amplitude: f32,
        exponent_scale: f32,
    ) -> Result<Self> {
        let name = "diefenbach-phong";
        check_rgb(name, "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb(name, "specular", specular, 0.0, 1.0)?;
        check_sum(name, diffuse, specular)?;
        for (param, v) in [
            ("alpha", alpha),
            ("amplitude", amplitude),
            ("exponent-scale", exponent_scale),
        ] {
            if !crate::brdf::is_positive(v) {
                return Err(BrdfError::OutOfRange {
                    model: name.into(),
                    param: param.into(),
                    value: v,
                    expected: "positive and finite".into(),
                });
            }
        }
        let exponent = exponent_scale / (alpha * alpha);
        if !exponent.is_finite() {
            return Err(BrdfError::OutOfRange {
                model: name.into(),
                param: "alpha".into(),
                value: alpha,
                expected: "large enough for a finite exponent b/α²".into(),
            });
        }
        Ok(Self {
            diffuse,
            specular,
            alpha,
            amplitude,
            exponent,
            p_diffuse: diffuse_probability(diffuse, specular),
        })
    }

    /// The hardware specular term `c n ρs cos(δ)^n` of equation 6 (that is, `cos θi` times the specular part of [`Brdf::eval`]).
    pub fn hardware_term(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let cos_delta = (wi + wo).normalize().z.clamp(0.0, 1.0);
        self.specular * (self.amplitude * self.exponent * cos_delta.powf(self.exponent))
    }
}

impl Brdf for DiefenbachPhong {
    fn name(&self) -> &'static str {
        "diefenbach-phong"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        self.diffuse * FRAC_1_PI + self.hardware_term(wi, wo) / wi.z
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_half_vector_mixture(self, wo, u, u_lobe, self.p_diffuse, self.exponent)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        half_vector_mixture_pdf(wi, wo, self.p_diffuse, self.exponent)
    }

    fn is_reciprocal(&self) -> bool {
        false
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
