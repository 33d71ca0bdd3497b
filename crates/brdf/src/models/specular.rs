//! Perfect specular reflection: a Dirac lobe in the mirror direction weighted by a Fresnel term.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample, reflect_z};
use crate::error::{BrdfError, Result, check_rgb};
use crate::fresnel::Fresnel;

/// Perfect mirror `f = F(θ) s δ(wi - R(wo)) / cos θ` (Whitted 1980; Fresnel per [`Fresnel`]): reciprocal; energy conserving (F ≤ 1, scale ≤ 1 are enforced).
#[derive(Debug, Clone, PartialEq)]
pub struct SpecularReflection {
    /// Fresnel term at the incident angle.
    pub fresnel: Fresnel,
    /// Scale of the lobe (MTL `Ks`), in [0, 1].
    pub scale: Rgb,
}

impl SpecularReflection {
    /// A perfect mirror; errors when the scale or a constant/Schlick reflectance leaves [0, 1] or an index is not positive.
    pub fn new(fresnel: Fresnel, scale: Rgb) -> Result<Self> {
        check_rgb("mirror", "reflectance", scale, 0.0, 1.0)?;
        check_fresnel("mirror", &fresnel)?;
        Ok(Self { fresnel, scale })
    }

    /// The reflectance `F(cos θo) · scale` of the mirror lobe.
    pub fn reflectance(&self, cos_o: f32) -> Rgb {
        self.fresnel.eval(cos_o) * self.scale
    }
}

/// Validates the parameters of a [`Fresnel`] term for `model` (shared by every model with a Fresnel factor).
pub(crate) fn check_fresnel(model: &str, fresnel: &Fresnel) -> Result<()> {
    match *fresnel {
        Fresnel::One => Ok(()),
        Fresnel::Constant(c) => check_rgb(model, "reflectance", c, 0.0, 1.0).map(|_| ()),
        Fresnel::Schlick { f0 } => check_rgb(model, "f0", f0, 0.0, 1.0).map(|_| ()),
        Fresnel::Dielectric { eta } => {
            if eta.is_nan() || eta <= 0.0 || !eta.is_finite() {
                Err(BrdfError::OutOfRange {
                    model: model.into(),
                    param: "ior".into(),
                    value: eta,
                    expected: "positive and finite".into(),
                })
            } else {
                Ok(())
            }
        }
        Fresnel::Conductor { eta, k } => {
            check_rgb(model, "eta", eta, 1e-6, f32::MAX)?;
            check_rgb(model, "k", k, 0.0, f32::MAX)?;
            Ok(())
        }
    }
}

impl Brdf for SpecularReflection {
    fn name(&self) -> &'static str {
        "mirror"
    }

    fn eval(&self, _wi: Vec3, _wo: Vec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: Vec3, _u: Vec2, _u_lobe: f32) -> Option<BrdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(BrdfSample {
            wi: reflect_z(wo),
            weight: self.reflectance(wo.z),
            pdf: 1.0,
            delta: true,
        })
    }

    fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        if wo.z <= 0.0 {
            Rgb::ZERO
        } else {
            self.reflectance(wo.z)
        }
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
}
