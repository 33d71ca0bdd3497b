//! glTF 2.0 materials as Lustre's reflectance models: the metallic-roughness
//! model of the glTF specification (appendix B) with `KHR_materials_ior`,
//! `KHR_materials_transmission`, `KHR_materials_volume` and
//! `KHR_materials_emissive_strength`.
//!
//! glTF's BRDF is `mix(dielectric, metal, metallic)` with GGX lobes of
//! `α = roughness²`. Each part maps to the nearest model `lustre-brdf` has:
//!
//! - metal: a rough conductor with `F = 1` scaled by the base colour
//!   (Schlick's Fresnel with `F0 = baseColor` is exact at normal incidence;
//!   the brightening towards grazing angles is left out) and Beckmann's
//!   distribution of the same `α` in place of GGX (the GPU passes evaluate
//!   Beckmann only; the two agree near the peak, GGX has the longer tails), or
//!   a mirror of the base colour when `α < 10⁻³`;
//! - dielectric: a Phong lobe of reflectance `F0 = ((ior − 1)/(ior + 1))²` on a
//!   Lambertian base of `(1 − F0) · baseColor`, the Phong exponent from `α` by
//!   Walter et al. 2007's equivalence `n = 2/α² − 2` (the Fresnel rise at
//!   grazing angles is again left out), or the base colour alone when `n < 1`;
//! - transmission (`KHR_materials_transmission`) with a transmission factor
//!   of at least ½: with a volume (`KHR_materials_volume`, thickness above
//!   zero) a smooth dielectric interface of the material's `ior`, its
//!   transmittance filter the base colour times the volume's attenuation over
//!   its thickness (Beer–Lambert: `attenuationColor^(thickness /
//!   attenuationDistance)`), rough transmission drawn smooth with a warning;
//!   without one the specification's thin-walled surface, Lustre's
//!   [`THIN_DIELECTRIC`] pane of that `ior`, Beckmann `α = roughness²` and
//!   transmittance the base colour. A factor below ½ is left out with a
//!   warning;
//! - `0 < metallic < 1`: Mitsuba-style blend of the two with weight `metallic`.
//!
//! glTF leaves the unit of `emissiveFactor` open; Lustre reads
//! `emissiveFactor × emissiveStrength` as radiance in W/(m² sr).

use crate::Rgb;
use crate::material::{
    ConductorFresnel, Material, MaterialModel, MicrofacetDistribution, THIN_DIELECTRIC,
};

/// Largest Phong exponent a smooth dielectric gets (its `α` near zero).
const MAX_PHONG_EXPONENT: f32 = 10_000.0;

/// Below this GGX `α` a metal is drawn as a perfect mirror.
const MIRROR_ALPHA: f32 = 1e-3;

/// The glTF parameters of one material, as read from the file (defaults of the specification where absent).
#[derive(Debug, Clone, PartialEq)]
pub struct GltfMaterial {
    /// The material's name.
    pub name: String,
    /// `baseColorFactor` (linear RGB; alpha is not used).
    pub base_color: Rgb,
    /// `metallicFactor`.
    pub metallic: f32,
    /// `roughnessFactor` (perceptual roughness; `α = roughness²`).
    pub roughness: f32,
    /// `emissiveFactor` times `KHR_materials_emissive_strength`.
    pub emission: Rgb,
    /// `KHR_materials_ior` (1.5 when absent).
    pub ior: f32,
    /// `KHR_materials_transmission`'s factor (0 when absent).
    pub transmission: f32,
    /// `KHR_materials_volume`: thickness, attenuation distance and colour.
    pub volume: Option<(f32, f32, Rgb)>,
}

impl GltfMaterial {
    /// The specification's default material (appendix: every property at its default), used by primitives without one.
    pub fn default_material() -> Self {
        Self {
            name: "gltf-default".into(),
            base_color: Rgb::ONE,
            metallic: 1.0,
            roughness: 1.0,
            emission: Rgb::ZERO,
            ior: 1.5,
            transmission: 0.0,
            volume: None,
        }
    }

    /// The Lustre material, with a warning for each approximation beyond the ones in the module docs.
    pub fn to_material(&self, warnings: &mut Vec<String>) -> Material {
        let clamp01 = |v: f32| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let base = self.base_color.map(clamp01);
        let metallic = clamp01(self.metallic);
        let roughness = clamp01(self.roughness);
        let alpha = roughness * roughness;
        let ior = if self.ior.is_finite() && self.ior >= 1.0 {
            self.ior
        } else {
            warnings.push(format!(
                "material `{}`: ior {} is not at least 1; 1.5 used",
                self.name, self.ior
            ));
            1.5
        };
        let transmission = clamp01(self.transmission);
        let solid = self.volume.is_some_and(|(thickness, _, _)| thickness > 0.0);
        let dielectric = if transmission >= 0.5 && !solid {
            MaterialModel::Named {
                model: THIN_DIELECTRIC.into(),
                params: [
                    ("ior".to_owned(), vec![ior]),
                    ("roughness".to_owned(), vec![alpha]),
                    ("transmittance".to_owned(), base.to_array().to_vec()),
                ]
                .into(),
            }
        } else if transmission >= 0.5 {
            if roughness > 0.1 {
                warnings.push(format!(
                    "material `{}`: rough transmission (roughness {roughness}) is drawn as a smooth dielectric",
                    self.name
                ));
            }
            MaterialModel::Dielectric {
                ior,
                transmittance: base * self.volume_filter(),
            }
        } else {
            if transmission > 0.0 {
                warnings.push(format!(
                    "material `{}`: transmission factor {transmission} below ½ is left out (the surface is drawn opaque)",
                    self.name
                ));
            }
            opaque_dielectric(base, alpha, ior)
        };
        let metal = if alpha < MIRROR_ALPHA {
            MaterialModel::Mirror { reflectance: base }
        } else {
            MaterialModel::RoughConductor {
                distribution: MicrofacetDistribution::Beckmann,
                alpha,
                fresnel: ConductorFresnel::None,
                specular: base,
            }
        };
        let model = if metallic <= 0.0 {
            dielectric
        } else if metallic >= 1.0 {
            metal
        } else {
            MaterialModel::Blend {
                weight: metallic,
                first: Box::new(dielectric),
                second: Box::new(metal),
            }
        };
        let emission = self
            .emission
            .map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
        Material::new(self.name.clone(), model).with_emission(emission)
    }

    /// The volume's Beer–Lambert transmittance over its thickness; white without a volume.
    fn volume_filter(&self) -> Rgb {
        match self.volume {
            Some((thickness, distance, colour))
                if thickness > 0.0 && distance.is_finite() && distance > 0.0 =>
            {
                colour.map(|c| c.clamp(0.0, 1.0)).powf(thickness / distance)
            }
            _ => Rgb::ONE,
        }
    }
}

impl GltfMaterial {
    /// The glTF parameters that load back as `material` ([`GltfMaterial::to_material`]): exactly for the models the loader makes (diffuse, mirror, a conductor without Fresnel, a smooth dielectric, a Phong lobe of grey specular reflectance `F0 ≤ 1/4` over a Lambertian base, and their metallic blend), up to rounding of `α`; other models are approximated, with a warning each.
    pub fn from_material(material: &Material, warnings: &mut Vec<String>) -> Self {
        let mut out = Self {
            name: material.name.clone(),
            emission: material.emission,
            ..Self::default_material()
        };
        out.set_model(&material.model, &material.name, warnings);
        out
    }

    /// Sets base colour, metallic, roughness, ior and transmission from a model.
    fn set_model(&mut self, model: &MaterialModel, name: &str, warnings: &mut Vec<String>) {
        let mut approximated = |why: &str| {
            warnings.push(format!(
                "material `{name}`: {} has no glTF counterpart; exported as {why}",
                model.name()
            ));
        };
        match model {
            MaterialModel::Diffuse { reflectance } => {
                (self.base_color, self.metallic, self.roughness) = (*reflectance, 0.0, 1.0);
            }
            MaterialModel::Mirror { reflectance } => {
                (self.base_color, self.metallic, self.roughness) = (*reflectance, 1.0, 0.0);
            }
            MaterialModel::RoughConductor {
                distribution,
                alpha,
                fresnel,
                specular,
            } => {
                let f0 = match fresnel {
                    ConductorFresnel::None => Rgb::ONE,
                    ConductorFresnel::Complex { eta, k } => {
                        approximated("a metal of its normal-incidence reflectance");
                        ((*eta - 1.0) * (*eta - 1.0) + *k * *k)
                            / ((*eta + 1.0) * (*eta + 1.0) + *k * *k)
                    }
                };
                if *distribution != MicrofacetDistribution::Beckmann
                    && !matches!(fresnel, ConductorFresnel::Complex { .. })
                {
                    approximated("a metal of the same α");
                }
                self.base_color = *specular * f0;
                self.metallic = 1.0;
                self.roughness = alpha.max(0.0).sqrt();
            }
            MaterialModel::Dielectric { ior, transmittance } => {
                self.base_color = *transmittance;
                (self.metallic, self.roughness) = (0.0, 0.0);
                (self.ior, self.transmission) = (*ior, 1.0);
                // A solid: any thickness, no attenuation.
                self.volume = Some((1.0, f32::INFINITY, Rgb::ONE));
            }
            MaterialModel::Named { model, params } if model == THIN_DIELECTRIC => {
                let value = |key: &str, default: f32| {
                    params
                        .get(key)
                        .and_then(|v| v.first().copied())
                        .unwrap_or(default)
                };
                self.base_color = match params.get("transmittance").map(Vec::as_slice) {
                    Some(&[r, g, b]) => Rgb::new(r, g, b),
                    Some(&[t]) => Rgb::splat(t),
                    _ => Rgb::ONE,
                };
                (self.metallic, self.roughness) = (0.0, value("roughness", 0.0).max(0.0).sqrt());
                (self.ior, self.transmission, self.volume) = (value("ior", 1.5), 1.0, None);
            }
            MaterialModel::Phong {
                diffuse,
                specular,
                exponent,
            } => {
                // F0 = ((ior − 1)/(ior + 1))², so ior = (1 + √F0)/(1 − √F0); n = 2/α² − 2.
                let f0 = specular.element_sum() / 3.0;
                let grey = (specular.max_element() - specular.min_element()) <= 1e-6 * f0.max(1e-6);
                if !grey || !(0.0..=0.25).contains(&f0) {
                    approximated("a dielectric of its mean specular reflectance");
                }
                let f0 = f0.clamp(0.0, 0.25);
                let root = f0.sqrt();
                self.ior = (1.0 + root) / (1.0 - root);
                self.base_color = *diffuse / (1.0 - f0);
                self.metallic = 0.0;
                let alpha = (2.0 / (exponent.max(0.0) + 2.0)).sqrt();
                self.roughness = alpha.sqrt();
            }
            MaterialModel::Blend {
                weight,
                first,
                second,
            } => {
                let mut dielectric = self.clone();
                dielectric.set_model(first, name, warnings);
                let mut metal = self.clone();
                metal.set_model(second, name, warnings);
                if dielectric.metallic != 0.0 || metal.metallic != 1.0 {
                    warnings.push(format!(
                        "material `{name}`: a blend that is not of a dielectric and a metal is exported as its weighted parameters"
                    ));
                }
                let w = weight.clamp(0.0, 1.0);
                let mix = |a: f32, b: f32| (1.0 - w) * a + w * b;
                self.base_color = (1.0 - w) * dielectric.base_color + w * metal.base_color;
                self.metallic = w;
                self.roughness = mix(dielectric.roughness, metal.roughness);
                (self.ior, self.transmission) = (dielectric.ior, dielectric.transmission);
                if self.roughness != dielectric.roughness || self.roughness != metal.roughness {
                    warnings.push(format!(
                        "material `{name}`: glTF has one roughness for both parts of a blend; the weighted mean {} is exported",
                        self.roughness
                    ));
                }
            }
            MaterialModel::Ward { diffuse, .. } => {
                approximated("its diffuse part");
                (self.base_color, self.metallic, self.roughness) = (*diffuse, 0.0, 1.0);
            }
            MaterialModel::Named { .. } => {
                approximated("the specification's default material");
            }
        }
    }
}

/// The dielectric (non-metal) part: a Phong lobe of reflectance `F0` over a Lambertian base of `(1 − F0)` times the base colour.
fn opaque_dielectric(base: Rgb, alpha: f32, ior: f32) -> MaterialModel {
    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
    let exponent = if alpha > 0.0 {
        (2.0 / (alpha * alpha) - 2.0).min(MAX_PHONG_EXPONENT)
    } else {
        MAX_PHONG_EXPONENT
    };
    if exponent < 1.0 {
        return MaterialModel::Diffuse { reflectance: base };
    }
    MaterialModel::Phong {
        diffuse: (1.0 - f0) * base,
        specular: Rgb::splat(f0),
        exponent,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(metallic: f32, roughness: f32) -> GltfMaterial {
        GltfMaterial {
            name: "m".into(),
            base_color: Rgb::new(0.8, 0.4, 0.2),
            metallic,
            roughness,
            ..GltfMaterial::default_material()
        }
    }

    #[test]
    fn metals_dielectrics_and_their_blend() {
        let mut warnings = Vec::new();
        let rough_metal = material(1.0, 0.5).to_material(&mut warnings).model;
        assert_eq!(
            rough_metal,
            MaterialModel::RoughConductor {
                distribution: MicrofacetDistribution::Beckmann,
                alpha: 0.25,
                fresnel: ConductorFresnel::None,
                specular: Rgb::new(0.8, 0.4, 0.2),
            }
        );
        assert_eq!(
            material(1.0, 0.0).to_material(&mut warnings).model,
            MaterialModel::Mirror {
                reflectance: Rgb::new(0.8, 0.4, 0.2)
            }
        );
        // Roughness 0.5: α = 0.25, n = 2/α² − 2 = 30; F0 of ior 1.5 is 0.04.
        let MaterialModel::Phong {
            diffuse,
            specular,
            exponent,
        } = material(0.0, 0.5).to_material(&mut warnings).model
        else {
            panic!("a rough dielectric is a Phong lobe on a Lambertian base");
        };
        assert!((exponent - 30.0).abs() < 1e-3, "{exponent}");
        assert!((specular - Rgb::splat(0.04)).abs().max_element() < 1e-6);
        assert!(
            (diffuse - 0.96 * Rgb::new(0.8, 0.4, 0.2))
                .abs()
                .max_element()
                < 1e-6
        );
        // Fully rough: n < 1, the base colour alone.
        assert_eq!(
            material(0.0, 1.0).to_material(&mut warnings).model,
            MaterialModel::Diffuse {
                reflectance: Rgb::new(0.8, 0.4, 0.2)
            }
        );
        let MaterialModel::Blend { weight, .. } =
            material(0.3, 0.5).to_material(&mut warnings).model
        else {
            panic!("a partly metallic material is a blend");
        };
        assert_eq!(weight, 0.3);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn transmission_volume_and_emission() {
        let mut warnings = Vec::new();
        let glass = GltfMaterial {
            transmission: 1.0,
            ior: 1.33,
            metallic: 0.0,
            roughness: 0.0,
            // Half the light left after 2 cm, 4 cm thick: a quarter.
            volume: Some((0.04, 0.02, Rgb::new(0.5, 1.0, 1.0))),
            ..material(0.0, 0.0)
        };
        let MaterialModel::Dielectric { ior, transmittance } =
            glass.to_material(&mut warnings).model
        else {
            panic!("transmission makes a dielectric");
        };
        assert_eq!(ior, 1.33);
        let expected = Rgb::new(0.8 * 0.25, 0.4, 0.2);
        assert!(
            (transmittance - expected).abs().max_element() < 1e-6,
            "{transmittance}"
        );
        assert!(warnings.is_empty());
        // Rough or partial transmission: approximated, with a warning each.
        let rough = GltfMaterial {
            transmission: 1.0,
            volume: Some((0.1, f32::INFINITY, Rgb::ONE)),
            ..material(0.0, 0.6)
        };
        assert!(matches!(
            rough.to_material(&mut warnings).model,
            MaterialModel::Dielectric { .. }
        ));
        let partial = GltfMaterial {
            transmission: 0.2,
            ..material(0.0, 0.6)
        };
        assert!(matches!(
            partial.to_material(&mut warnings).model,
            MaterialModel::Phong { .. }
        ));
        assert_eq!(warnings.len(), 2, "{warnings:?}");

        // Without a volume: the specification's thin-walled surface, a pane.
        let pane = GltfMaterial {
            transmission: 1.0,
            ior: 1.4,
            ..material(0.0, 0.5)
        };
        let MaterialModel::Named { model, params } = pane.to_material(&mut warnings).model else {
            panic!("a thin-walled transmissive surface is a named model");
        };
        assert_eq!(model, THIN_DIELECTRIC);
        assert_eq!(params["ior"], vec![1.4]);
        assert_eq!(params["roughness"], vec![0.25]);
        assert_eq!(params["transmittance"], vec![0.8, 0.4, 0.2]);
        assert_eq!(warnings.len(), 2, "{warnings:?}");

        let lamp = GltfMaterial {
            emission: Rgb::new(2.0, -1.0, f32::NAN),
            ..material(0.0, 1.0)
        };
        assert_eq!(
            lamp.to_material(&mut warnings).emission,
            Rgb::new(2.0, 0.0, 0.0)
        );
    }

    #[test]
    fn out_of_range_parameters_are_clamped_or_replaced() {
        let mut warnings = Vec::new();
        let odd = GltfMaterial {
            metallic: 7.0,
            roughness: -1.0,
            ior: 0.5,
            ..material(0.0, 0.0)
        };
        assert!(matches!(
            odd.to_material(&mut warnings).model,
            MaterialModel::Mirror { .. }
        ));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("ior 0.5"), "{warnings:?}");
    }
}
