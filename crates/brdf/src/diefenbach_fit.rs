//! Diefenbach's chi-square fit of the hardware Phong term to Ward's isotropic Gaussian (P. J. Diefenbach and N. I. Badler, "Multi-pass pipeline rendering: realism for dynamic environments", I3D 1997, section 5, equations 3-6).
//!
//! Ward's isotropic specular lobe (equation 3) is
//! `ρs exp(-tan²δ/α²) / (4π α² √(cos θi cos θr))`, δ the angle between the
//! half vector and the normal. The hardware term (equation 4) is
//! `ρs cos(δ)^E` with no `cos θi`, so the paper fits it not to the BRDF but
//! to the BRDF times `cos θi` (equation 5): the reflected radiance of a
//! point light of unit intensity.
//!
//! **The `sin θi` convention.** Written over the light's polar angle, the
//! rendering equation's solid angle is `dω = sin θi dθi dφi`, so a
//! Monte-Carlo or area-light integration of equation 3 carries an extra
//! `sin θi` that a point light does not. The paper drops it ("to provide
//! some consistency between the diffuse and specular computations"): the
//! fitted target is `cos θi f` alone, with no `sin θi` factor and no
//! `sin θi` weight in the chi-square. [`WardFitSetup::samples`] follows the
//! paper: unweighted (σ = 1) residuals of `cos θi f` with no `sin θi`.
//!
//! **The fitted form.** Equation 6 is `c n ρs cos(δ)^n` with `n = b/α²`:
//! two parameters, `c = 0.0398` and `b = 1.999`. Both have a closed-form
//! small-α limit: `cos(δ)^n ≈ exp(-n δ²/2)` and `tan²δ ≈ δ²` give `b → 2`,
//! and matching the peak `1/(4π α²)` gives `c n = 1/(4π α²)`, so
//! `c → 1/(8π) = 0.03979`. The paper's `b` slightly below two comes from
//! the factor `cos θi / √(cos θi cos θr)` of equation 5, which rises away
//! from the mirror direction when the light is near the normal.
//!
//! **What reproduces the paper.** With the light along the normal
//! (θi = 0, the first curve of the paper's figure 13), the viewer swept
//! across the plane of incidence and α between 0.035 and 0.05, the fit
//! gives c = 0.0398 and b = 1.999 to the printed digits for any sampling
//! step between 0.5° and 5°. The chi-square, an unweighted sum of squared
//! residuals, grows with the number of samples inside the lobe (about
//! `1/(α³ step)`); the paper's 0.00008003 is met at α = 0.04 with 5° steps
//! ([`WardFitSetup::paper`]), which is what the tests check.

use crate::error::{BrdfError, Result};

/// The amplitude `c` of equation 6, `0.0398` (Diefenbach & Badler 1997, equation 6).
pub const DIEFENBACH_AMPLITUDE: f32 = 0.0398;

/// The exponent scale `b` of equation 6, `1.999`: the Phong exponent is `b/α²` (Diefenbach & Badler 1997, equation 6).
pub const DIEFENBACH_EXPONENT_SCALE: f32 = 1.999;

/// The chi-square the paper reports for its fit, `0.00008003` (Diefenbach & Badler 1997, below equation 6).
pub const DIEFENBACH_CHI_SQUARE: f64 = 0.000_080_03;

/// The Phong exponent `E = b/α²` of equation 6 for Ward's α (Diefenbach & Badler 1997, equation 6).
pub fn diefenbach_exponent(alpha: f32) -> f32 {
    DIEFENBACH_EXPONENT_SCALE / (alpha * alpha)
}

/// Equation 6, the fitted hardware specular term `0.0398 (1.999/α²) ρs cos(δ)^(1.999/α²)`, which approximates `cos θi` times Ward's specular BRDF (Diefenbach & Badler 1997, equation 6); zero for `cos δ ≤ 0`.
pub fn diefenbach_phong_term(cos_delta: f32, rho_s: f32, alpha: f32) -> f32 {
    if !(cos_delta > 0.0) {
        return 0.0;
    }
    let n = diefenbach_exponent(alpha);
    DIEFENBACH_AMPLITUDE * n * rho_s * cos_delta.min(1.0).powf(n)
}

/// One datum of the fit: the half-vector angle δ and the target value of equation 5 (with ρs = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WardSample {
    /// Polar angle δ of the half vector, radians.
    pub delta: f64,
    /// `cos θi · f_Ward,specular(θi, θr, δ)` for ρs = 1 (equation 5).
    pub value: f64,
}

/// The sampling of equation 5 that the fit runs on: Ward's α, the light's polar angle θi, and the viewer swept across the plane of incidence in steps (Diefenbach & Badler 1997, section 5, figure 13).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WardFitSetup {
    /// Ward's RMS slope α.
    pub alpha: f64,
    /// Polar angle of the light θi, radians, in [0, π/2).
    pub theta_i: f64,
    /// Step of the viewer's signed polar angle across the plane of incidence, radians.
    pub step: f64,
}

impl WardFitSetup {
    /// The sampling that reproduces the paper's numbers: α = 0.04, light along the normal, 5° steps (see the module documentation).
    pub fn paper() -> Self {
        Self {
            alpha: 0.04,
            theta_i: 0.0,
            step: 5f64.to_radians(),
        }
    }

    /// The data: the viewer at signed polar angles `θi + k·step` (k = 0, ±1, ±2, …) strictly inside (-π/2, π/2) in the plane of incidence, on the far side of the normal from the light for positive angles, so that δ = |θr - θi|/2; each value is equation 5 with ρs = 1 and no `sin θi` (Diefenbach & Badler 1997, equation 5).
    pub fn samples(&self) -> Result<Vec<WardSample>> {
        let bad = |param: &str, value: f64, expected: &str| BrdfError::OutOfRange {
            model: "diefenbach-fit".into(),
            param: param.into(),
            value: value as f32,
            expected: expected.into(),
        };
        if !(self.alpha.is_finite() && self.alpha > 0.0) {
            return Err(bad("alpha", self.alpha, "positive and finite"));
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        if !(self.theta_i >= 0.0 && self.theta_i < half_pi) {
            return Err(bad("theta_i", self.theta_i, "0 to π/2 (exclusive)"));
        }
        if !(self.step.is_finite() && self.step >= 1e-4 && self.step < half_pi) {
            return Err(bad("step", self.step, "1e-4 to π/2 radians"));
        }
        let a2 = self.alpha * self.alpha;
        let cos_i = self.theta_i.cos();
        let mut out = Vec::new();
        let k_max = (2.0 * half_pi / self.step).ceil() as i64 + 1;
        for k in -k_max..=k_max {
            let theta_r = self.theta_i + k as f64 * self.step;
            if theta_r.abs() >= half_pi {
                continue;
            }
            let delta = 0.5 * (theta_r - self.theta_i).abs();
            let cos_r = theta_r.cos();
            let lobe = (-delta.tan().powi(2) / a2).exp()
                / ((cos_i * cos_r).sqrt() * 4.0 * std::f64::consts::PI * a2);
            out.push(WardSample {
                delta,
                value: cos_i * lobe,
            });
        }
        Ok(out)
    }
}

/// The result of the two-parameter fit `c n cos(δ)^n`, `n = b/α²` (Diefenbach & Badler 1997, equation 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhongFit {
    /// The amplitude c (the paper's 0.0398).
    pub amplitude: f64,
    /// The exponent scale b (the paper's 1.999).
    pub exponent_scale: f64,
    /// `χ² = Σ (yₖ - c n cos(δₖ)^n)²` with unit errors σₖ = 1 at the optimum.
    pub chi_square: f64,
    /// Levenberg-Marquardt iterations used.
    pub iterations: usize,
}

impl PhongFit {
    /// The fitted term `c (b/α²) cos(δ)^(b/α²)` for ρs = 1 (equation 6 with the fitted constants).
    pub fn term(&self, cos_delta: f64, alpha: f64) -> f64 {
        if !(cos_delta > 0.0) {
            return 0.0;
        }
        let n = self.exponent_scale / (alpha * alpha);
        self.amplitude * n * cos_delta.min(1.0).powf(n)
    }
}

/// The model `c (b/α²) cos(δ)^(b/α²)` and its partial derivatives with respect to c and b.
fn model(c: f64, b: f64, alpha: f64, delta: f64) -> (f64, f64, f64) {
    let inv_a2 = 1.0 / (alpha * alpha);
    let n = b * inv_a2;
    let cos = delta.cos().max(1e-300);
    let cn = cos.powf(n);
    let m = c * n * cn;
    let dm_dc = n * cn;
    // d/db [c (b/α²) cos^(b/α²)] = c/α² cos^n (1 + n ln cos δ).
    let dm_db = c * inv_a2 * cn * (1.0 + n * cos.ln());
    (m, dm_dc, dm_db)
}

/// `Σ (yₖ - m(δₖ))²` for the parameters (c, b).
fn chi_square(data: &[WardSample], alpha: f64, c: f64, b: f64) -> f64 {
    data.iter()
        .map(|s| {
            let r = s.value - model(c, b, alpha, s.delta).0;
            r * r
        })
        .sum()
}

/// Fits `c (b/α²) cos(δ)^(b/α²)` to the data of `setup` by Levenberg-Marquardt, minimising the unweighted chi-square (Diefenbach & Badler 1997, section 5, "a Chi-Square two-parameter fit"; Press et al., *Numerical Recipes* 2nd ed., section 15.5).
pub fn fit_phong_to_ward(setup: &WardFitSetup) -> Result<PhongFit> {
    let data = setup.samples()?;
    fit_phong(&data, setup.alpha, (0.05, 1.5))
}

/// Levenberg-Marquardt on (c, b) from the starting point `start` for any data set (the fitting engine of [`fit_phong_to_ward`]).
pub fn fit_phong(data: &[WardSample], alpha: f64, start: (f64, f64)) -> Result<PhongFit> {
    const MAX_ITERATIONS: usize = 500;
    let (mut c, mut b) = start;
    let mut chi = chi_square(data, alpha, c, b);
    let mut lambda = 1e-3;
    for iteration in 1..=MAX_ITERATIONS {
        // Normal equations J^T J δp = J^T r, with the diagonal damped by (1 + λ).
        let (mut a11, mut a12, mut a22, mut g1, mut g2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for s in data {
            let (m, jc, jb) = model(c, b, alpha, s.delta);
            let r = s.value - m;
            a11 += jc * jc;
            a12 += jc * jb;
            a22 += jb * jb;
            g1 += jc * r;
            g2 += jb * r;
        }
        let mut accepted = false;
        while lambda < 1e16 {
            let d11 = a11 * (1.0 + lambda);
            let d22 = a22 * (1.0 + lambda);
            let det = d11 * d22 - a12 * a12;
            if det.is_finite() && det != 0.0 {
                let dc = (g1 * d22 - g2 * a12) / det;
                let db = (d11 * g2 - a12 * g1) / det;
                let (nc, nb) = (c + dc, b + db);
                if nb > 0.0 {
                    let nchi = chi_square(data, alpha, nc, nb);
                    if nchi.is_finite() && nchi <= chi {
                        let converged = (chi - nchi) <= 1e-12 * chi.max(1e-300)
                            && dc.abs() <= 1e-10 * c.abs().max(1e-12)
                            && db.abs() <= 1e-10 * b.abs();
                        c = nc;
                        b = nb;
                        chi = nchi;
                        lambda = (lambda * 0.1).max(1e-12);
                        accepted = true;
                        if converged {
                            return Ok(PhongFit {
                                amplitude: c,
                                exponent_scale: b,
                                chi_square: chi,
                                iterations: iteration,
                            });
                        }
                        break;
                    }
                }
            }
            lambda *= 10.0;
        }
        if !accepted {
            // No step lowers χ² at any damping: the minimum is reached to machine precision.
            return Ok(PhongFit {
                amplitude: c,
                exponent_scale: b,
                chi_square: chi,
                iterations: iteration,
            });
        }
    }
    Err(BrdfError::FitDidNotConverge {
        fit: "Diefenbach Phong fit".into(),
        iterations: MAX_ITERATIONS,
        chi_square: chi,
    })
}
