//! Microfacet slope distributions and shadowing-masking terms shared by the microfacet models.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};
use lustre_geometry::material::MicrofacetDistribution;

use crate::error::{BrdfError, Result};

/// A normalised distribution of microfacet normals, `∫ D(h) cos θh dωh = 1` (Walter et al. 2007, "Microfacet models for refraction through rough surfaces", equation 4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Beckmann's distribution `exp(-tan²θ/α²) / (π α² cos⁴θ)` (Beckmann & Spizzichino 1963; Cook & Torrance 1982 equation 12, normalised as Walter et al. 2007 equation 25).
    Beckmann {
        /// RMS slope α (Cook & Torrance's m).
        alpha: f32,
    },
    /// Gaussian in the angle `c exp(-(θ/m)²)` (Torrance & Sparrow 1967 equation 19; Cook & Torrance 1982 equation 13), with `c` normalised numerically at construction.
    Gaussian {
        /// Width m in radians.
        m: f32,
        /// Normalisation constant c.
        c: f32,
    },
    /// Trowbridge-Reitz / GGX `α² / (π cos⁴θ (α² + tan²θ)²)` (Walter et al. 2007 equation 33).
    Ggx {
        /// Roughness α.
        alpha: f32,
    },
}

impl Distribution {
    /// The distribution of `kind` with roughness `alpha` (m for the Gaussian); errors unless `alpha` is positive and finite.
    pub fn new(kind: MicrofacetDistribution, alpha: f32, model: &str) -> Result<Self> {
        if !crate::brdf::is_positive(alpha) {
            return Err(BrdfError::OutOfRange {
                model: model.into(),
                param: "roughness".into(),
                value: alpha,
                expected: "positive and finite".into(),
            });
        }
        Ok(match kind {
            MicrofacetDistribution::Beckmann => Self::Beckmann { alpha },
            MicrofacetDistribution::Ggx => Self::Ggx { alpha },
            MicrofacetDistribution::Gaussian => Self::Gaussian {
                m: alpha,
                c: gaussian_normalisation(alpha),
            },
        })
    }

    /// The width parameter (α or m).
    pub fn alpha(&self) -> f32 {
        match *self {
            Self::Beckmann { alpha } | Self::Ggx { alpha } => alpha,
            Self::Gaussian { m, .. } => m,
        }
    }

    /// `D(h)` per unit solid angle of `h`; zero for `h.z ≤ 0`.
    pub fn d(&self, h: Vec3) -> f32 {
        let cos = h.z;
        if cos <= 0.0 {
            return 0.0;
        }
        let cos2 = cos * cos;
        let tan2 = ((1.0 - cos2).max(0.0) / cos2).max(0.0);
        match *self {
            Self::Beckmann { alpha } => beckmann(alpha, cos2, tan2),
            Self::Ggx { alpha } => {
                let a2 = alpha * alpha;
                let t = a2 + tan2;
                a2 * FRAC_1_PI / (cos2 * cos2 * t * t)
            }
            Self::Gaussian { m, c } => {
                let theta = cos.min(1.0).acos();
                c * (-(theta / m) * (theta / m)).exp()
            }
        }
    }

    /// Draws a microfacet normal with density [`Distribution::pdf_h`] (Walter et al. 2007 equations 28, 35; the Gaussian uses the Beckmann draw with α = m as proposal).
    pub fn sample_h(&self, u: Vec2) -> Vec3 {
        let tan2 = match *self {
            Self::Beckmann { alpha } | Self::Gaussian { m: alpha, .. } => {
                -alpha * alpha * (1.0 - u.x).max(1e-30).ln()
            }
            Self::Ggx { alpha } => alpha * alpha * u.x / (1.0 - u.x).max(1e-30),
        };
        let cos = 1.0 / (1.0 + tan2).sqrt();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
    }

    /// Density of [`Distribution::sample_h`] per solid angle of `h`: `D(h) cos θh` (the Beckmann one for the Gaussian).
    pub fn pdf_h(&self, h: Vec3) -> f32 {
        match *self {
            Self::Gaussian { m, .. } => Self::Beckmann { alpha: m }.d(h) * h.z.max(0.0),
            _ => self.d(h) * h.z.max(0.0),
        }
    }

    /// Smith's masking `G1(v, h)` (Smith 1967; Walter et al. 2007 equations 27 (Beckmann, rational fit) and 34 (GGX)); the Gaussian uses Beckmann's with α = m.
    pub fn smith_g1(&self, v: Vec3, h: Vec3) -> f32 {
        if v.dot(h) * v.z <= 0.0 {
            return 0.0;
        }
        let cos2 = v.z * v.z;
        let tan2 = (1.0 - cos2).max(0.0) / cos2;
        if tan2 == 0.0 {
            return 1.0;
        }
        match *self {
            Self::Beckmann { alpha } | Self::Gaussian { m: alpha, .. } => {
                let a = 1.0 / (alpha * tan2.sqrt());
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            Self::Ggx { alpha } => 2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt()),
        }
    }
}

/// Beckmann `D` from `cos²θ` and `tan²θ`.
fn beckmann(alpha: f32, cos2: f32, tan2: f32) -> f32 {
    let a2 = alpha * alpha;
    (-tan2 / a2).exp() * FRAC_1_PI / (a2 * cos2 * cos2)
}

/// `c` with `2π c ∫₀^{π/2} exp(-(θ/m)²) cos θ sin θ dθ = 1`, by Simpson's rule on 2048 intervals.
fn gaussian_normalisation(m: f32) -> f32 {
    let m = f64::from(m);
    let n = 2048;
    let h = std::f64::consts::FRAC_PI_2 / n as f64;
    let g = |t: f64| (-(t / m) * (t / m)).exp() * t.cos() * t.sin();
    let mut s = g(0.0) + g(std::f64::consts::FRAC_PI_2);
    for i in 1..n {
        s += g(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    let integral = s * h / 3.0 * 2.0 * std::f64::consts::PI;
    (1.0 / integral) as f32
}

/// The shadowing-masking term of a microfacet model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shadowing {
    /// The V-cavity term `min(1, 2 (n·h)(n·o)/(o·h), 2 (n·h)(n·i)/(o·h))` (Torrance & Sparrow 1967 section 5; Blinn 1977; Cook & Torrance 1982 equation 6).
    VCavity,
    /// Separable Smith `G1(i, h) G1(o, h)` (Smith 1967; Walter et al. 2007 equation 23), the one Mitsuba 3 uses.
    Smith,
}

impl Shadowing {
    /// `G(wi, wo, h)` for this term and distribution.
    pub fn g(&self, dist: &Distribution, wi: Vec3, wo: Vec3, h: Vec3) -> f32 {
        match self {
            Self::VCavity => {
                let oh = wo.dot(h);
                if oh <= 0.0 || wi.dot(h) <= 0.0 {
                    return 0.0;
                }
                let a = 2.0 * h.z * wo.z / oh;
                let b = 2.0 * h.z * wi.z / oh;
                1.0_f32.min(a).min(b).max(0.0)
            }
            Self::Smith => dist.smith_g1(wi, h) * dist.smith_g1(wo, h),
        }
    }
}
