//! Materials on the GPU: each scene material flattened into weighted BRDF
//! lobes ([`GpuMaterial`]) that `shaders/common/material.wgsl` evaluates with
//! the WGSL twins of `lustre-brdf` (Stürzlinger & Bastos 1997, section 2.2:
//! "the BRDF for the current view evaluated per splat"; Diefenbach & Badler
//! 1997, equation 6 for the fitted Phong option).
//!
//! A [`MaterialModel::Blend`] becomes the lobes of both sides, weighted
//! `1 - w` and `w` as in `lustre_brdf::from_model`. Delta lobes (mirror,
//! smooth dielectric) have no finite BRDF: they are flagged [`LOBE_DELTA`] and
//! evaluate to zero, as the CPU estimator's `eval` does; their images come
//! from the specular passes. Models without a WGSL twin are reported, never
//! silently replaced.

use bytemuck::{Pod, Zeroable};
use lustre_brdf::diefenbach_fit::{DIEFENBACH_AMPLITUDE, DIEFENBACH_EXPONENT_SCALE};
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::{Rgb, Scene};

use crate::error::{MprError, Result};

/// Most lobes one material may flatten into.
pub const MAX_LOBES: usize = 4;

/// An unused lobe slot.
pub const LOBE_NONE: u32 = 0;
/// Lambert: `kd / π`.
pub const LOBE_LAMBERT: u32 = 1;
/// Modified Phong (Lafortune & Willems 1994): `kd`, `ks`, exponent in `params.x`.
pub const LOBE_MODIFIED_PHONG: u32 = 2;
/// Isotropic Ward (1992, original normalisation): `kd`, `ks`, α in `params.x`.
pub const LOBE_WARD: u32 = 3;
/// Cook-Torrance, Beckmann D, Smith G, conductor Fresnel `eta + i k`: `ks`, α in `params.x`.
pub const LOBE_COOK_TORRANCE: u32 = 4;
/// Cook-Torrance, Beckmann D, Smith G, `F = 1`: `ks`, α in `params.x`.
pub const LOBE_COOK_TORRANCE_F1: u32 = 5;
/// Diefenbach's fitted Phong (equation 6): `kd`, `ks`, α, `c`, `b` in `params.xyz`.
pub const LOBE_DIEFENBACH_PHONG: u32 = 6;
/// A delta lobe (mirror, smooth dielectric): zero for every pair of directions.
pub const LOBE_DELTA: u32 = 7;

/// One weighted lobe (`GpuLobe` in `material.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuLobe {
    /// `LOBE_*` kind.
    pub kind: u32,
    /// Weight of the lobe in the material (blend weights multiplied out).
    pub weight: f32,
    /// Padding to 16 bytes.
    pub pad: [f32; 2],
    /// Diffuse reflectance `kd` (rgb, w unused).
    pub kd: [f32; 4],
    /// Specular reflectance `ks` (rgb, w unused).
    pub ks: [f32; 4],
    /// Model scalars: α or the Phong exponent in `x`; `c`, `b` of equation 6 in `y`, `z`.
    pub params: [f32; 4],
    /// Conductor `eta` (rgb).
    pub eta: [f32; 4],
    /// Conductor `k` (rgb).
    pub k: [f32; 4],
}

/// A material as weighted lobes (`GpuMaterial` in `material.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// The lobes; unused slots are [`LOBE_NONE`].
    pub lobes: [GpuLobe; MAX_LOBES],
    /// `x`: the layer of the material's diffuse map in [`crate::diffuse_map::DiffuseMaps`], which scales every lobe's `kd` ([`crate::diffuse_map::WHITE_LAYER`]: none); `yzw` unused.
    pub diffuse_map: [u32; 4],
}

/// How glossy lobes are evaluated on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GlossyModel {
    /// Each lobe's own model.
    #[default]
    Exact,
    /// Beckmann and Ward lobes replaced by Diefenbach's fitted Phong of the same α (equation 6; `c` and `b` of the paper).
    FittedPhong,
}

fn rgb4(c: Rgb) -> [f32; 4] {
    [c.x, c.y, c.z, 0.0]
}

fn lobe(kind: u32, weight: f32, kd: Rgb, ks: Rgb, params: [f32; 4]) -> GpuLobe {
    GpuLobe {
        kind,
        weight,
        pad: [0.0; 2],
        kd: rgb4(kd),
        ks: rgb4(ks),
        params,
        eta: [0.0; 4],
        k: [0.0; 4],
    }
}

/// Diefenbach's equation 6 lobe standing for a Ward or Beckmann lobe of slope `alpha`.
fn fitted_phong(weight: f32, kd: Rgb, ks: Rgb, alpha: f32) -> GpuLobe {
    lobe(
        LOBE_DIEFENBACH_PHONG,
        weight,
        kd,
        ks,
        [alpha, DIEFENBACH_AMPLITUDE, DIEFENBACH_EXPONENT_SCALE, 0.0],
    )
}

/// Appends the lobes of `model` with weight `weight` to `out`.
fn flatten(
    name: &str,
    model: &MaterialModel,
    weight: f32,
    glossy: GlossyModel,
    out: &mut Vec<GpuLobe>,
) -> Result<()> {
    let unsupported = |why: String| MprError::UnsupportedMaterial {
        material: name.to_owned(),
        message: why,
    };
    match model {
        MaterialModel::Diffuse { reflectance } => {
            out.push(lobe(
                LOBE_LAMBERT,
                weight,
                *reflectance,
                Rgb::ZERO,
                [0.0; 4],
            ));
        }
        MaterialModel::RoughConductor {
            distribution,
            alpha,
            fresnel,
            specular,
        } => {
            if *distribution != MicrofacetDistribution::Beckmann {
                return Err(unsupported(format!(
                    "{distribution:?} microfacet distribution has no GPU twin (Beckmann has)"
                )));
            }
            if glossy == GlossyModel::FittedPhong {
                // Equation 6 has no Fresnel term: the lobe keeps ks times the normal-incidence reflectance.
                let f0 = match fresnel {
                    ConductorFresnel::Complex { eta, k } => conductor_f0(*eta, *k),
                    ConductorFresnel::None => Rgb::ONE,
                };
                out.push(fitted_phong(weight, Rgb::ZERO, *specular * f0, *alpha));
                return Ok(());
            }
            let mut l = match fresnel {
                ConductorFresnel::Complex { eta, k } => {
                    let mut l = lobe(
                        LOBE_COOK_TORRANCE,
                        weight,
                        Rgb::ZERO,
                        *specular,
                        [*alpha, 0.0, 0.0, 0.0],
                    );
                    l.eta = rgb4(*eta);
                    l.k = rgb4(*k);
                    l
                }
                ConductorFresnel::None => lobe(
                    LOBE_COOK_TORRANCE_F1,
                    weight,
                    Rgb::ZERO,
                    *specular,
                    [*alpha, 0.0, 0.0, 0.0],
                ),
            };
            l.weight = weight;
            out.push(l);
        }
        MaterialModel::Mirror { .. } | MaterialModel::Dielectric { .. } => {
            out.push(lobe(LOBE_DELTA, weight, Rgb::ZERO, Rgb::ZERO, [0.0; 4]));
        }
        MaterialModel::Phong {
            diffuse,
            specular,
            exponent,
        } => out.push(lobe(
            LOBE_MODIFIED_PHONG,
            weight,
            *diffuse,
            *specular,
            [*exponent, 0.0, 0.0, 0.0],
        )),
        MaterialModel::Ward {
            diffuse,
            specular,
            alpha_x,
            alpha_y,
        } => {
            if alpha_x != alpha_y {
                return Err(unsupported(format!(
                    "anisotropic Ward (alpha_x {alpha_x}, alpha_y {alpha_y}) has no GPU twin"
                )));
            }
            if glossy == GlossyModel::FittedPhong {
                out.push(fitted_phong(weight, *diffuse, *specular, *alpha_x));
            } else {
                out.push(lobe(
                    LOBE_WARD,
                    weight,
                    *diffuse,
                    *specular,
                    [*alpha_x, 0.0, 0.0, 0.0],
                ));
            }
        }
        MaterialModel::Blend {
            weight: w,
            first,
            second,
        } => {
            flatten(name, first, weight * (1.0 - w), glossy, out)?;
            flatten(name, second, weight * w, glossy, out)?;
        }
        // A window pane: Dirac reflection and straight transmission, no
        // lobe to evaluate (the beams carry the light it passes on).
        MaterialModel::Named { model, .. }
            if model == lustre_geometry::material::THIN_DIELECTRIC =>
        {
            out.push(lobe(LOBE_DELTA, weight, Rgb::ZERO, Rgb::ZERO, [0.0; 4]));
        }
        MaterialModel::Named { model, .. } => {
            return Err(unsupported(format!(
                "model `{model}` has no GPU twin (GPU models: diffuse, phong, ward, rough-conductor with Beckmann, blend, mirror, dielectric, thin-dielectric)"
            )));
        }
    }
    Ok(())
}

/// Normal-incidence reflectance of a conductor, `((η-1)² + k²) / ((η+1)² + k²)`.
fn conductor_f0(eta: Rgb, k: Rgb) -> Rgb {
    let num = (eta - Rgb::ONE) * (eta - Rgb::ONE) + k * k;
    let den = (eta + Rgb::ONE) * (eta + Rgb::ONE) + k * k;
    num / den
}

impl GpuMaterial {
    /// Flattens a material model into lobes; `name` is used in errors.
    pub fn from_model(name: &str, model: &MaterialModel, glossy: GlossyModel) -> Result<Self> {
        // The CPU twin must accept the model too (energy checks, ranges).
        lustre_brdf::from_model(model).map_err(|e| MprError::UnsupportedMaterial {
            material: name.to_owned(),
            message: e.to_string(),
        })?;
        let mut lobes = Vec::new();
        flatten(name, model, 1.0, glossy, &mut lobes)?;
        lobes.retain(|l| l.weight > 0.0);
        if lobes.len() > MAX_LOBES {
            return Err(MprError::UnsupportedMaterial {
                material: name.to_owned(),
                message: format!("{} lobes; the GPU takes at most {MAX_LOBES}", lobes.len()),
            });
        }
        let mut out = Self::zeroed();
        out.lobes[..lobes.len()].copy_from_slice(&lobes);
        Ok(out)
    }

    /// Whether every lobe is Lambertian (view independent: section 2.2.1's precomputed diffuse surfaces).
    pub fn is_diffuse(&self) -> bool {
        self.lobes
            .iter()
            .all(|l| l.kind == LOBE_NONE || l.kind == LOBE_LAMBERT)
    }

    /// Whether some lobe is Lambertian with a non-zero reflectance (the part a diffuse texture can hold, section 2.2.1).
    pub fn has_lambert(&self) -> bool {
        self.diffuse_reflectance().max_element() > 0.0
    }

    /// The material without its Lambertian lobes: what the splats of a surface add when a diffuse texture holds `Σ w kd / π` (its other lobes, Ward's and Phong's own `kd` included, unchanged).
    pub fn without_lambert(&self) -> Self {
        let mut out = *self;
        for l in &mut out.lobes {
            if l.kind == LOBE_LAMBERT {
                *l = GpuLobe::zeroed();
            }
        }
        out
    }

    /// The Lambertian reflectance `Σ w kd` of the material's Lambertian lobes.
    pub fn diffuse_reflectance(&self) -> Rgb {
        self.lobes
            .iter()
            .filter(|l| l.kind == LOBE_LAMBERT)
            .map(|l| Rgb::from_slice(&l.kd[..3]) * l.weight)
            .sum()
    }
}

/// Every material of a scene, in `MaterialId` order, each with the layer of its diffuse map ([`crate::diffuse_map::diffuse_map_layers`]).
pub fn scene_materials(scene: &Scene, glossy: GlossyModel) -> Result<Vec<GpuMaterial>> {
    let (layers, _) = crate::diffuse_map::diffuse_map_layers(scene);
    scene
        .materials()
        .iter()
        .zip(layers)
        .map(|(m, layer)| {
            let mut g = GpuMaterial::from_model(&m.name, &m.model, glossy)?;
            g.diffuse_map[0] = layer;
            Ok(g)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    #[test]
    fn gpu_material_is_the_std430_size_of_four_lobes_and_a_map_layer() {
        assert_eq!(size_of::<GpuLobe>(), 96);
        assert_eq!(size_of::<GpuMaterial>(), 4 * 96 + 16);
    }

    #[test]
    fn glosbox_floor_flattens_into_weighted_diffuse_and_rough_mirror() {
        let scene = builtin("glosbox").unwrap();
        let mats = scene_materials(&scene, GlossyModel::Exact).unwrap();
        let floor = scene
            .materials()
            .iter()
            .position(|m| matches!(m.model, MaterialModel::Blend { .. }))
            .unwrap();
        let lobes = &mats[floor].lobes;
        assert_eq!(lobes[0].kind, LOBE_LAMBERT);
        assert!((lobes[0].weight - 0.7).abs() < 1e-6);
        assert_eq!(lobes[1].kind, LOBE_COOK_TORRANCE_F1);
        assert!((lobes[1].weight - 0.3).abs() < 1e-6);
        assert_eq!(lobes[2].kind, LOBE_NONE);
    }

    #[test]
    fn unsupported_models_are_named_in_the_error() {
        let model = MaterialModel::Ward {
            diffuse: Rgb::splat(0.2),
            specular: Rgb::splat(0.1),
            alpha_x: 0.1,
            alpha_y: 0.3,
        };
        let err = GpuMaterial::from_model("brushed", &model, GlossyModel::Exact).unwrap_err();
        assert!(err.to_string().contains("brushed"), "{err}");
    }

    #[test]
    fn conductor_f0_of_gold_matches_the_fresnel_crate_at_normal_incidence() {
        let eta = Rgb::new(0.143, 0.374, 1.442);
        let k = Rgb::new(3.983, 2.385, 1.603);
        let f0 = conductor_f0(eta, k);
        let fresnel = lustre_brdf::Fresnel::Conductor { eta, k };
        let expected = fresnel.eval(1.0);
        assert!(
            (f0 - expected).abs().max_element() < 1e-5,
            "{f0} vs {expected}"
        );
    }
}
