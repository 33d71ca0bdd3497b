//! Material descriptions: plain data naming a reflectance model and its parameters.
//!
//! The geometry crate does not evaluate BRDFs; `lustre-brdf` turns a
//! [`MaterialModel`] into an evaluator. Descriptions come from MTL files (see
//! [`crate::obj`] for the standard fields and the documented `lustre_*` keys)
//! or from the built-in scenes.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use glam::Vec2;

use crate::{Rgb, Texture};

/// Index of a material in [`crate::Scene::materials`].
pub type MaterialId = u32;

/// The Fresnel term of a rough conductor.
#[derive(Debug, Clone, PartialEq)]
pub enum ConductorFresnel {
    /// Fresnel of a conductor with complex index of refraction `eta + i k` (per RGB channel).
    Complex {
        /// Real part of the index of refraction.
        eta: Rgb,
        /// Imaginary part (extinction coefficient).
        k: Rgb,
    },
    /// F = 1 for every angle: a perfect mirror's Fresnel (Mitsuba's `material = "none"`).
    None,
}

/// Microfacet slope distribution of a rough surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MicrofacetDistribution {
    /// Beckmann's distribution (Cook-Torrance 1982), the one Mitsuba calls `beckmann`.
    Beckmann,
    /// The isotropic Gaussian of Torrance-Sparrow / Cook-Torrance's variant.
    Gaussian,
    /// Trowbridge-Reitz / GGX.
    Ggx,
}

/// The `MaterialModel::Named` model of a thin glass slab (a window pane): light passes straight through it, reflected with `R = 2F/(1 + F)` and transmitted with `T = (1 - F)/(1 + F)` times the filter (all internal reflections summed); parameters `ior` (1.5), `roughness` (Beckmann α of both faces, 0) and `transmittance` (one or three values, 1). Used by `lustre-beams` and exported to Mitsuba's `thindielectric`.
pub const THIN_DIELECTRIC: &str = "thin-dielectric";

/// The reflectance model of a material and its parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialModel {
    /// Lambertian reflector with the given reflectance (MTL `Kd`).
    Diffuse {
        /// Hemispherical reflectance in [0, 1].
        reflectance: Rgb,
    },
    /// Microfacet conductor (Cook-Torrance with a slope distribution).
    RoughConductor {
        /// Distribution of microfacet slopes.
        distribution: MicrofacetDistribution,
        /// Roughness alpha (RMS slope for Beckmann); isotropic.
        alpha: f32,
        /// The Fresnel term.
        fresnel: ConductorFresnel,
        /// Scale applied to the whole lobe (MTL `Ks` when given, else white).
        specular: Rgb,
    },
    /// Perfect mirror with a reflectance (MTL `illum 3` with `Ks`).
    Mirror {
        /// Reflectance of the mirror.
        reflectance: Rgb,
    },
    /// Smooth dielectric interface (MTL `Ni` with `d < 1` or `illum 7`).
    Dielectric {
        /// Index of refraction of the inside relative to the outside.
        ior: f32,
        /// Transmittance filter (MTL `Tf`), white when absent.
        transmittance: Rgb,
    },
    /// Phong lobe plus a diffuse term (MTL `Kd`, `Ks`, `Ns`).
    Phong {
        /// Diffuse reflectance.
        diffuse: Rgb,
        /// Specular reflectance.
        specular: Rgb,
        /// Phong exponent.
        exponent: f32,
    },
    /// Ward's (1992) anisotropic Gaussian model.
    Ward {
        /// Diffuse reflectance.
        diffuse: Rgb,
        /// Specular reflectance.
        specular: Rgb,
        /// Standard deviation of the surface slope along the tangent.
        alpha_x: f32,
        /// Standard deviation of the surface slope along the bitangent.
        alpha_y: f32,
    },
    /// `weight * second + (1 - weight) * first`, Mitsuba's `blendbsdf`.
    Blend {
        /// The weight of `second`, in [0, 1].
        weight: f32,
        /// The model weighted by `1 - weight`.
        first: Box<MaterialModel>,
        /// The model weighted by `weight`.
        second: Box<MaterialModel>,
    },
    /// Any other model `lustre-brdf` knows, by name, with named parameters
    /// (MTL `lustre_model NAME` and `lustre_param NAME v1 [v2 v3]`).
    Named {
        /// The model's name, e.g. `oren-nayar`.
        model: String,
        /// Its parameters: one value or an RGB triple each.
        params: BTreeMap<String, Vec<f32>>,
    },
}

impl MaterialModel {
    /// Whether the model is a plain Lambertian reflector: view independent, unlike the "glossy" surfaces of Stürzlinger & Bastos 2.2.1 and García et al. 2.10.
    pub fn is_diffuse(&self) -> bool {
        matches!(self, Self::Diffuse { .. })
    }

    /// The Lambertian reflectance `ρ` of the model's diffuse part (García et al. section 2.4, equation 2.2 holds for it): `Diffuse` its reflectance, `Phong` and `Ward` their diffuse term, `Blend` the weighted sum of its sides; zero for models without one (rough conductor, mirror, dielectric) and for `Named` models, whose parameters are not interpreted here.
    pub fn diffuse_reflectance(&self) -> Rgb {
        match self {
            Self::Diffuse { reflectance } => *reflectance,
            Self::Phong { diffuse, .. } | Self::Ward { diffuse, .. } => *diffuse,
            Self::Blend {
                weight,
                first,
                second,
            } => {
                (1.0 - weight) * first.diffuse_reflectance() + weight * second.diffuse_reflectance()
            }
            Self::RoughConductor { .. }
            | Self::Mirror { .. }
            | Self::Dielectric { .. }
            | Self::Named { .. } => Rgb::ZERO,
        }
    }

    /// A short name of the model, as used in messages and `lustre info`.
    pub fn name(&self) -> String {
        match self {
            Self::Diffuse { .. } => "diffuse".into(),
            Self::RoughConductor { .. } => "rough-conductor".into(),
            Self::Mirror { .. } => "mirror".into(),
            Self::Dielectric { .. } => "dielectric".into(),
            Self::Phong { .. } => "phong".into(),
            Self::Ward { .. } => "ward".into(),
            Self::Blend { first, second, .. } => {
                format!("blend({}, {})", first.name(), second.name())
            }
            Self::Named { model, .. } => model.clone(),
        }
    }
}

/// A material: a reflectance model, an optional emission and texture maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The material's name (from MTL `newmtl` or the built-in scene).
    pub name: String,
    /// The reflectance model.
    pub model: MaterialModel,
    /// Emitted radiance in W/(m^2 sr) (MTL `Ke`); zero for non-emitters.
    pub emission: Rgb,
    /// Diffuse texture (MTL `map_Kd`, glTF `baseColorTexture`): the file it names, resolved relative to the MTL or glTF file (`None` for an embedded image).
    pub diffuse_texture: Option<PathBuf>,
    /// The decoded diffuse texture, which scales the diffuse reflectance of the model's Lambertian part ([`MaterialModel::diffuse_reflectance`]) texel by texel at the hit's UV (MTL: `Kd` times `map_Kd`; glTF: `baseColorFactor` times `baseColorTexture`); `None` for an untextured material or a file that could not be read (a warning at load).
    pub diffuse_map: Option<Arc<Texture>>,
    /// Specular texture (MTL `map_Ks`), resolved relative to the MTL file.
    pub specular_texture: Option<PathBuf>,
    /// Opacity (MTL `d`), 1 for opaque.
    pub opacity: f32,
}

impl Material {
    /// A Lambertian material with the given reflectance.
    pub fn diffuse(name: impl Into<String>, reflectance: Rgb) -> Self {
        Self::new(name, MaterialModel::Diffuse { reflectance })
    }

    /// A non-emissive, untextured, opaque material with the given model.
    pub fn new(name: impl Into<String>, model: MaterialModel) -> Self {
        Self {
            name: name.into(),
            model,
            emission: Rgb::ZERO,
            diffuse_texture: None,
            diffuse_map: None,
            specular_texture: None,
            opacity: 1.0,
        }
    }

    /// This material with an emitted radiance.
    pub fn with_emission(mut self, emission: Rgb) -> Self {
        self.emission = emission;
        self
    }

    /// This material with a diffuse texture map.
    pub fn with_diffuse_map(mut self, map: Arc<Texture>) -> Self {
        self.diffuse_map = Some(map);
        self
    }

    /// The factor by which [`Material::diffuse_map`] scales the Lambertian part's reflectance at texture coordinates `uv` (bilinear, repeated: [`Texture::sample`]); one without a map.
    pub fn diffuse_tint(&self, uv: Vec2) -> Rgb {
        self.diffuse_map.as_ref().map_or(Rgb::ONE, |t| t.sample(uv))
    }

    /// The Lambertian reflectance `ρ_d ⊙ t(uv)` at texture coordinates `uv`: [`MaterialModel::diffuse_reflectance`] scaled by [`Material::diffuse_tint`]; `ρ_d` itself without a map.
    pub fn diffuse_reflectance_at(&self, uv: Vec2) -> Rgb {
        let rho = self.model.diffuse_reflectance();
        if self.diffuse_map.is_some() {
            rho * self.diffuse_tint(uv)
        } else {
            rho
        }
    }

    /// The change `(t(uv) − 1) ⊙ ρ_d / π` the diffuse map makes to the BRDF's smooth part at `uv`, where the Lambertian part lives (both directions above the surface): the textured BRDF is `f + shift`; `None` without a map, so untextured materials evaluate the BRDF alone.
    pub fn diffuse_shift(&self, uv: Vec2) -> Option<Rgb> {
        self.diffuse_map.as_ref()?;
        Some(
            (self.diffuse_tint(uv) - Rgb::ONE)
                * self.model.diffuse_reflectance()
                * std::f32::consts::FRAC_1_PI,
        )
    }

    /// Whether the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
