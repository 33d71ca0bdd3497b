//! The He-Torrance-Sillion-Greenberg physical optics model (He et al. 1991).

use std::f32::consts::FRAC_1_PI;
use std::f64::consts::PI as PI64;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use super::specular::check_fresnel;
use crate::brdf::{Brdf, BrdfSample, finish_sample, mean, reflect, same_upper, sampled_albedo};
use crate::error::{BrdfError, Result, check_rgb};
use crate::fresnel::Fresnel;
use crate::microfacet::Distribution;
use crate::special::erfc;

/// Relative size of the bound on the omitted tail of the `m` series at which it is truncated.
pub const HTSG_SERIES_TOLERANCE: f64 = 1e-6;
/// Hard cap on the number of terms of the `m` series (reached only for `g` above about 2000).
pub const HTSG_MAX_TERMS: usize = 4000;
/// Number of tabulated `cos θo` values of the cached albedo.
const ALBEDO_TABLE: usize = 33;

/// He-Torrance-Sillion-Greenberg `ρ = ρ_sp + ρ_dd + ρ_ud` (X. D. He, K. E. Torrance, F. X. Sillion, D. P. Greenberg, "A comprehensive physical model for light reflection", SIGGRAPH 1991, equations 2, 7-9, 13-15, 18-22 and 43-46 (appendix)).
///
/// * Specular (a Dirac lobe): `ρ_s = |F(θi)|² e^{-g} S` with `g` at the
///   mirror direction.
/// * Directional diffuse: `ρ_dd = |F(θ'i)|² G S D / (π cos θi cos θr)`,
///   `D = (π² τ² / 4λ²) Σ_{m≥1} g^m e^{-g} / (m! m) exp(-v_xy² τ² / 4m)`,
///   `g = σ² v_z²`, `v = (2π/λ)(wi + wo)`, F at the bisector angle
///   `cos θ'i = |wi + wo| / 2`.
/// * Uniform diffuse: `ρ_ud = a / π` (the paper's `a(λ)` read as a reflectance).
///
/// `σ` is the effective roughness `σ0 / √(1 + z0²/σ0²)` with `z0` solved
/// from `√(π/2) z0 = (σ0/4)(K_i + K_r) exp(-z0²/2σ0²)`,
/// `K = tan θ erfc(τ / (2 σ0 tan θ))` (equations 44-45), by bisection. The
/// shadowing is Smith's `S(θ) = (1 - ½ erfc(τ cot θ / 2σ0)) / (Λ(cot θ) + 1)`,
/// `Λ(c) = ½ ((2/√π)(σ0/τ)/c · exp(-τ²c²/4σ0²) - erfc(τ c / 2σ0))`
/// (equations 23-24), `S = S(θi) S(θr)`.
///
/// Convergence: the series is summed term by term in log space until
/// `m ≥ max(1, 2g)` and the Poisson bound on the omitted tail (each
/// `exp(-v_xy² τ²/4m) ≤ 1`), `2 g^{m+1} e^{-g} / ((m+1)! (m+1))`, is below
/// [`HTSG_SERIES_TOLERANCE`] times the partial sum, capped at
/// [`HTSG_MAX_TERMS`] terms.
///
/// Simplifications: light is unpolarised and F is the average of the s and
/// p reflectances, in which case the polarisation factor of the paper's G
/// (equation 22) reduces to `(v·v / v_z²)²`; each RGB channel is evaluated
/// at one wavelength (`wavelengths`, µm). Reciprocal. Not claimed energy
/// conserving (the Kirchhoff approximation does not bound the albedo).
/// Sampled as: the specular delta with probability `mean(ρ_s)` (at most
/// 0.9), else half a cosine hemisphere and half a Beckmann half-vector lobe
/// with the surface's RMS slope `2σ0/τ`. The albedo is cached over `cos θo`.
#[derive(Debug)]
pub struct Htsg {
    /// RMS roughness σ0 of the surface heights, µm.
    pub sigma0: f32,
    /// Autocorrelation length τ, µm.
    pub tau: f32,
    /// Fresnel term of the material (dielectric index or conductor `n + ik`).
    pub fresnel: Fresnel,
    /// Uniform-diffuse reflectance `a`.
    pub diffuse: Rgb,
    /// Wavelength of each channel, µm.
    pub wavelengths: Rgb,
    /// The Beckmann proposal with slope `2σ0/τ`.
    proposal: Distribution,
    /// The albedo table over `cos θo` in [0, 1], filled on first use.
    albedo_table: OnceLock<Vec<Rgb>>,
}

impl Htsg {
    /// HTSG; errors unless σ0 ≥ 0, τ > 0, wavelengths > 0, `a` in [0, 1] and the Fresnel parameters are valid.
    pub fn new(
        sigma0: f32,
        tau: f32,
        fresnel: Fresnel,
        diffuse: Rgb,
        wavelengths: Rgb,
    ) -> Result<Self> {
        let positive = |param: &str, v: f32, zero_ok: bool| {
            if v.is_nan() || !v.is_finite() || v < 0.0 || (!zero_ok && v == 0.0) {
                Err(BrdfError::OutOfRange {
                    model: "htsg".into(),
                    param: param.into(),
                    value: v,
                    expected: if zero_ok { "at least 0" } else { "positive" }.into(),
                })
            } else {
                Ok(())
            }
        };
        positive("sigma", sigma0, true)?;
        positive("tau", tau, false)?;
        for l in wavelengths.to_array() {
            positive("wavelength", l, false)?;
        }
        check_rgb("htsg", "diffuse", diffuse, 0.0, 1.0)?;
        check_fresnel("htsg", &fresnel)?;
        let slope = (2.0 * sigma0 / tau).max(1e-3);
        Ok(Self {
            sigma0,
            tau,
            fresnel,
            diffuse,
            wavelengths,
            proposal: Distribution::Beckmann { alpha: slope },
            albedo_table: OnceLock::new(),
        })
    }

    /// The shadowing `S(θ)` of equations 23-24 for `cos θ`.
    fn shadowing(&self, cos: f64) -> f64 {
        let (s0, tau) = (f64::from(self.sigma0), f64::from(self.tau));
        if s0 == 0.0 || cos >= 1.0 {
            return 1.0;
        }
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        if sin == 0.0 {
            return 1.0;
        }
        let cot = cos / sin;
        let x = tau * cot / (2.0 * s0);
        let lambda = 0.5 * (2.0 / PI64.sqrt() * (s0 / tau) / cot * (-x * x).exp() - erfc(x));
        ((1.0 - 0.5 * erfc(x)) / (lambda + 1.0)).clamp(0.0, 1.0)
    }

    /// The effective roughness σ of equations 44-45 for the two cosines.
    fn effective_sigma(&self, cos_i: f64, cos_r: f64) -> f64 {
        let (s0, tau) = (f64::from(self.sigma0), f64::from(self.tau));
        if s0 == 0.0 {
            return 0.0;
        }
        let k = |c: f64| {
            let c = c.clamp(1e-9, 1.0);
            let tan = (1.0 - c * c).max(0.0).sqrt() / c;
            if tan == 0.0 {
                0.0
            } else {
                tan * erfc(tau / (2.0 * s0 * tan))
            }
        };
        let rhs = 0.25 * s0 * (k(cos_i) + k(cos_r));
        if rhs <= 0.0 {
            return s0;
        }
        let c = (PI64 / 2.0).sqrt();
        let f = |z: f64| c * z - rhs * (-z * z / (2.0 * s0 * s0)).exp();
        let (mut lo, mut hi) = (0.0, rhs / c);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let z0 = 0.5 * (lo + hi);
        s0 / (1.0 + z0 * z0 / (s0 * s0)).sqrt()
    }

    /// The series `Σ_{m≥1} g^m e^{-g} / (m! m) exp(-c/m)` truncated as documented on [`Htsg`].
    pub fn series(g: f64, c: f64) -> f64 {
        if g <= 0.0 {
            return 0.0;
        }
        let ln_g = g.ln();
        let mut ln_fact = 0.0;
        let mut sum = 0.0;
        for m in 1..=HTSG_MAX_TERMS {
            let mf = m as f64;
            ln_fact += mf.ln();
            sum += (mf * ln_g - g - ln_fact - mf.ln() - c / mf).exp();
            if mf >= (2.0 * g).max(1.0) {
                let next = mf + 1.0;
                let tail = 2.0 * (next * ln_g - g - ln_fact - next.ln() - next.ln()).exp();
                if tail <= HTSG_SERIES_TOLERANCE * sum || tail < 1e-300 {
                    break;
                }
            }
        }
        sum
    }

    /// Reflectance of the specular Dirac lobe at `cos θo`: `|F(θ)|² e^{-g} S(θ)²` (equation 7).
    pub fn specular_reflectance(&self, cos_o: f32) -> Rgb {
        if cos_o <= 0.0 {
            return Rgb::ZERO;
        }
        let c = f64::from(cos_o);
        let sigma = self.effective_sigma(c, c);
        let s = self.shadowing(c);
        let f = self.fresnel.eval(cos_o);
        let mut out = [0.0; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            let k = 2.0 * PI64 / f64::from(self.wavelengths[ch]);
            let g = (sigma * k * 2.0 * c).powi(2);
            *o = (f64::from(f[ch]) * (-g).exp() * s * s) as f32;
        }
        Rgb::from_array(out)
    }

    /// The directional-diffuse term `ρ_dd` alone.
    pub fn directional_diffuse(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let (ci, cr) = (f64::from(wi.z), f64::from(wo.z));
        let sum = (wi + wo).as_dvec3();
        let vz_unit = sum.z;
        let vxy2_unit = sum.x * sum.x + sum.y * sum.y;
        let geometric = (sum.length_squared() / (vz_unit * vz_unit)).powi(2);
        let s = self.shadowing(ci) * self.shadowing(cr);
        let sigma = self.effective_sigma(ci, cr);
        let cos_local = (0.5 * (wi + wo).length()).min(1.0);
        let f = self.fresnel.eval(cos_local);
        let tau = f64::from(self.tau);
        let mut out = [0.0; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            let lambda = f64::from(self.wavelengths[ch]);
            let k = 2.0 * PI64 / lambda;
            let g = sigma * sigma * k * k * vz_unit * vz_unit;
            let c = k * k * vxy2_unit * tau * tau / 4.0;
            let d = PI64 * PI64 * tau * tau / (4.0 * lambda * lambda) * Self::series(g, c);
            *o = (f64::from(f[ch]) * geometric * s * d / (PI64 * ci * cr)) as f32;
        }
        Rgb::from_array(out)
    }

    /// Probability of drawing the specular delta lobe from `wo`.
    fn p_specular(&self, cos_o: f32) -> f32 {
        mean(self.specular_reflectance(cos_o)).clamp(0.0, 0.9)
    }

    /// The uncached albedo (specular reflectance plus the smooth part sampled on 64 × 64 strata).
    fn albedo_uncached(&self, wo: Vec3) -> Rgb {
        sampled_albedo(self, wo, 64)
    }
}

impl Brdf for Htsg {
    fn name(&self) -> &'static str {
        "htsg"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        self.directional_diffuse(wi, wo) + self.diffuse * FRAC_1_PI
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let p_spec = self.p_specular(wo.z);
        if u_lobe < p_spec {
            return Some(BrdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: self.specular_reflectance(wo.z) / p_spec,
                pdf: p_spec,
                delta: true,
            });
        }
        let v = (u_lobe - p_spec) / (1.0 - p_spec);
        let wi = if v < 0.5 {
            lustre_geometry::sampling::sample_cosine_hemisphere(u)
        } else {
            let h = self.proposal.sample_h(u);
            if h.dot(wo) <= 0.0 {
                return None;
            }
            reflect(wo, h)
        };
        finish_sample(self, wi, wo)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !same_upper(wi, wo) {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        let lobe = self.proposal.pdf_h(h) / (4.0 * wo.dot(h));
        (1.0 - self.p_specular(wo.z)) * (0.5 * wi.z * FRAC_1_PI + 0.5 * lobe)
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let table = self.albedo_table.get_or_init(|| {
            (0..ALBEDO_TABLE)
                .map(|j| {
                    let c = (j as f32 / (ALBEDO_TABLE - 1) as f32).max(1e-3);
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    self.albedo_uncached(Vec3::new(s, 0.0, c))
                })
                .collect()
        });
        let x = wo.z.clamp(0.0, 1.0) * (ALBEDO_TABLE - 1) as f32;
        let j = (x.floor() as usize).min(ALBEDO_TABLE - 2);
        let t = x - j as f32;
        table[j] * (1.0 - t) + table[j + 1] * t
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }

    fn has_delta(&self) -> bool {
        true
    }
}
