//! Smooth dielectric interface: Dirac reflection and refraction weighted by the dielectric Fresnel term.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample};
use crate::error::{BrdfError, Result, check_rgb};
use crate::fresnel::fresnel_dielectric;

/// Smooth dielectric (Fresnel 1823; Snell's law; Whitted 1980): reflects with probability F and refracts with 1 - F; both lobes are Dirac deltas.
///
/// `wo.z < 0` means the viewer is inside. The refracted weight is
/// `(1 - F) · transmittance` without the `1/η²` radiance compression: it is
/// the weight that carries flux (particles, importance), which is what the
/// photon, DETP and beam techniques trace; a radiance path tracer multiplies
/// by `(η_o/η_i)²` itself. Reciprocal in the generalised sense
/// `f(wi, wo)/η_o² = f(wo, wi)/η_i²` (Veach 1997, section 5.2); energy
/// conserving (albedo `F + (1 - F) T ≤ 1`).
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothDielectric {
    /// Index of refraction of the inside (−Z side) relative to the outside.
    pub ior: f32,
    /// Transmittance filter of the refracted lobe, in [0, 1].
    pub transmittance: Rgb,
}

impl SmoothDielectric {
    /// A smooth dielectric; errors when `ior` is not positive and finite or the transmittance leaves [0, 1].
    pub fn new(ior: f32, transmittance: Rgb) -> Result<Self> {
        if !crate::brdf::is_positive(ior) {
            return Err(BrdfError::OutOfRange {
                model: "dielectric".into(),
                param: "ior".into(),
                value: ior,
                expected: "positive and finite".into(),
            });
        }
        check_rgb("dielectric", "transmittance", transmittance, 0.0, 1.0)?;
        Ok(Self { ior, transmittance })
    }

    /// Refraction of `wo` through the interface (Snell's law in vector form, Heckbert 1989); `None` under total internal reflection.
    pub fn refract(&self, wo: Vec3) -> Option<Vec3> {
        let (eta, sign) = if wo.z >= 0.0 {
            (self.ior, 1.0)
        } else {
            (1.0 / self.ior, -1.0)
        };
        let cos_i = wo.z.abs();
        let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
        if sin2_t >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let n = Vec3::new(0.0, 0.0, sign);
        Some((-wo / eta + (cos_i / eta - cos_t) * n).normalize())
    }
}

impl Brdf for SmoothDielectric {
    fn name(&self) -> &'static str {
        "dielectric"
    }

    fn eval(&self, _wi: Vec3, _wo: Vec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: Vec3, _u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let f = fresnel_dielectric(wo.z, self.ior);
        if u_lobe < f {
            Some(BrdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Rgb::ONE,
                pdf: f,
                delta: true,
            })
        } else {
            let wi = self.refract(wo)?;
            Some(BrdfSample {
                wi,
                weight: self.transmittance,
                pdf: 1.0 - f,
                delta: true,
            })
        }
    }

    fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        if wo.z == 0.0 {
            return Rgb::ZERO;
        }
        let f = fresnel_dielectric(wo.z, self.ior);
        Rgb::splat(f) + (1.0 - f) * self.transmittance
    }

    fn is_reciprocal(&self) -> bool {
        false
    }

    fn is_energy_conserving(&self) -> bool {
        true
    }

    fn has_delta(&self) -> bool {
        true
    }

    fn transmits(&self) -> bool {
        true
    }

    fn is_two_sided(&self) -> bool {
        false
    }
}
