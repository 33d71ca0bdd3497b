//! Thin dielectric slab (a window pane): Dirac reflection and straight transmission, all internal reflections summed.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample};
use crate::error::{BrdfError, Result, check_rgb};
use crate::fresnel::fresnel_dielectric;

/// A thin slab of index `ior` between two parallel smooth faces (Born & Wolf, *Principles of Optics*, section 1.6, summed incoherently): with the single-interface Fresnel F, the slab reflects `R = F + (1 - F)² F / (1 - F²) = 2F / (1 + F)` and transmits `T = (1 - F) / (1 + F)` along the incident direction (the two refractions cancel), the transmitted part filtered by `transmittance`. Both lobes are Dirac deltas; reciprocal; energy conserving. The `thin-dielectric` material of `lustre_geometry::material::THIN_DIELECTRIC`, whose `roughness` only `lustre-beams` uses (glossy beams): here the faces are smooth.
#[derive(Debug, Clone, PartialEq)]
pub struct ThinDielectric {
    /// Index of refraction of the slab relative to the outside.
    pub ior: f32,
    /// Transmittance filter of the transmitted lobe, in [0, 1].
    pub transmittance: Rgb,
}

impl ThinDielectric {
    /// A thin slab; errors when `ior` is not positive and finite or the transmittance leaves [0, 1].
    pub fn new(ior: f32, transmittance: Rgb) -> Result<Self> {
        if !crate::brdf::is_positive(ior) {
            return Err(BrdfError::OutOfRange {
                model: "thin-dielectric".into(),
                param: "ior".into(),
                value: ior,
                expected: "positive and finite".into(),
            });
        }
        check_rgb("thin-dielectric", "transmittance", transmittance, 0.0, 1.0)?;
        Ok(Self { ior, transmittance })
    }

    /// The slab's reflectance `R = 2F / (1 + F)` at `|cos θ|`.
    pub fn reflectance(&self, cos: f32) -> f32 {
        let f = fresnel_dielectric(cos.abs(), self.ior);
        2.0 * f / (1.0 + f)
    }
}

impl Brdf for ThinDielectric {
    fn name(&self) -> &'static str {
        "thin-dielectric"
    }

    fn eval(&self, _wi: Vec3, _wo: Vec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: Vec3, _u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u_lobe < r {
            Some(BrdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Rgb::ONE,
                pdf: r,
                delta: true,
            })
        } else {
            Some(BrdfSample {
                wi: -wo,
                weight: self.transmittance,
                pdf: 1.0 - r,
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
        let r = self.reflectance(wo.z);
        Rgb::splat(r) + (1.0 - r) * self.transmittance
    }

    fn is_reciprocal(&self) -> bool {
        true
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
}
