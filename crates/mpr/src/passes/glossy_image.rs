//! Glossy images (Diefenbach & Badler 1997, section 3, "glossy marble" and
//! figure 4): the specular image of a planar glossy face drawn `N` times from
//! its mirror view sheared stochastically in (x, y) about the face's normal
//! (`shear_view`), each image optionally fogged with its distance from the
//! face, accumulated in a float target (`accbuf(ACCUMULATE)`) and the average
//! times the face's glossy reflectance added inside the face's stencil mask
//! (`accbuf(RETURN)`), like a mirror's restore.
//!
//! # The shear and the roughness
//!
//! [`crate::View::sheared_reflection`] pushes the world transform
//! `p ↦ p − z(p) Δ` after the mirror transform (`z` the distance from the
//! face, `Δ` a tangent vector): a ray that leaves a face point `x` with
//! direction `r` in the mirror view leaves it with the slope (tangential over
//! normal component) `r_t / r_z + Δ` in the sheared view, for every `x`; the
//! sheared view is the exact virtual camera at `e' − d_e Δ`. So `Δ` is a
//! displacement of the reflected direction in slope space.
//!
//! A microfacet lobe (Beckmann) reflects about facet normals whose slopes
//! `m`, weighted by projected area, follow `P₂₂(m) = exp(−|m|²/α²)/(π α²)`:
//! a Gaussian with variance `α²/2` per axis and `E|m|² = α²`. Tilting the
//! normal by a small slope `m` tilts the reflected direction by twice as
//! much, `Δ ≈ 2m`, at normal incidence (at incidence θ the displacement in
//! the plane of incidence grows by `1/cos²θ` and the constant shear, like the
//! paper's, underestimates it there). So the shear samples are `Δ = 2m`,
//! Gaussian with variance `2α²` per axis, RMS length `2α` ([`shear_slopes`]:
//! `N` stratified samples, Rayleigh radius `2α √(−ln(1 − u))` over
//! [`hammersley_centred`] strata). Other lobes map to an `α`
//! ([`glossy_lobe`]): Ward's `α` is the same RMS slope (the geometric mean of
//! `α_x`, `α_y`); Phong's exponent `n` by `α² = 2/(n + 2)` (the Beckmann lobe
//! Phong's cosine power matches near the peak); GGX's `α` is used as if it
//! were Beckmann's.
//!
//! The constant shear is exact only near normal incidence. [`ShearModel::Microfacet`]
//! (not the paper's; `--glossy-shear microfacet`) instead reflects the
//! view's ray to the face's centroid about each sampled facet normal and
//! weights the sample by the microfacet estimator ([`microfacet_shears`]):
//! exact at the centroid at any incidence, still one shear for the whole
//! face. On glosbox (floor seen at 71–79°) it measured no better: relMSE
//! 0.00171 against the isotropic 0.00173 at 256², so the paper's shear
//! stays the default.
//!
//! # Fog
//!
//! The paper fogs the image with hardware fog, "the minimum fog set at the
//! (specular) plane distance and the maximum at the desired distance
//! depending on the material property": a linear blend of the image towards
//! the fog colour, `f L + (1 − f) L_fog` with `f = clamp(1 − z / f_max, 0,
//! 1)`, `z` the distance of the visible point from the face (the paper's
//! fog is linear in eye depth; it asks for "a more versatile fog function",
//! which this distance to the plane is). [`Fog::Material`] derives `f_max`
//! from the lobe: the shear spreads a point at distance `z` over an RMS
//! radius `2α z`, which reaches the scene's size `D` (bounding-box diagonal)
//! at `z = D / (2α)`; beyond it the reflection is the scene's mean radiance,
//! the fog radiance (the specular limit radiance, [`GlossySettings::fog_radiance`]).
//!
//! # Composition
//!
//! A glossy image carries the glossy lobe's reflection of everything the
//! sheared views show — direct light on other surfaces, their diffuse and
//! glossy indirect light, deeper specular images — except the emitters:
//! the sheared views hide them ([`crate::View::shows_emitters`]), because the
//! direct pass already adds the glossy highlight of the point lights on the
//! face. The face's photon splats must then not carry its glossy lobe: the
//! renderer keeps the face's Lambertian lobe in the diffuse textures and
//! drops its splats (`SplatBuffers::new_excluding_imaged`). At the
//! recursion limit, or deeper than [`GlossySettings::depth`], the face shows
//! `R · L_lim` as a mirror does.
//!
//! # Images in images
//!
//! A glossy face seen inside another glossy image (`GlossySettings::depth`
//! above 1) makes one sheared image per sample of the outer image, not `N`:
//! the outer image's `N` samples become `N` paths through both lobes, the
//! inner shear of path `p` its `nested_shear_index(p, N)`-th, and the
//! accumulation over the outer samples averages the product lobe (`N`
//! views per face instead of `N²`). A mirror or slab inside a sample
//! passes the path on.
//!
//! # Frosted glass
//!
//! Section 3's frosted glass is the same accumulation over slab views
//! sheared about the near face ([`crate::View::sheared_through_slab`],
//! [`frosted`]): a rough entry face of roughness α moves the outgoing slope
//! by `(η − 1) m`. Without a rough dielectric material, the roughness is
//! [`GlossySettings::frosted_alpha`] for every slab.
//!
//! CPU twins: [`shear_slopes`] and [`fog_factor`]; `tests/glossy_image.rs`
//! holds the GPU's zero-shear image to the mirror path and the blur of a
//! bright emitter to the integral of the sheared lobe.

use std::sync::Mutex;

use glam::{Vec2, Vec3};
use lustre_geometry::Scene;
use lustre_geometry::SurfaceKind;
use lustre_geometry::light::hammersley_centred;
use lustre_geometry::material::{ConductorFresnel, MaterialModel};
use wgpu::util::DeviceExt;

use crate::passes::redraw::{ADDITIVE, scene_module, view_stencil};
use crate::passes::specular::{
    GlossyImage, SpecularFace, SpecularKind, SpecularPass, SpecularSettings,
};
use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::shaders::with_view;
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The glossy image pass's own WGSL (`src/passes/glossy_image.wgsl`); compiled after the view block.
pub const GLOSSY_IMAGE_WGSL: &str = include_str!("glossy_image.wgsl");

/// The most samples one glossy image may take.
pub const MAX_GLOSSY_SAMPLES: u32 = 256;

/// How the images are fogged with distance from the face (section 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fog {
    /// No fog.
    Off,
    /// `f_max = D / (2α)`, `D` the scene's bounding-box diagonal (module docs).
    Material,
    /// A fixed `f_max` in m.
    Distance(f32),
}

/// Which faces make glossy images and how (section 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlossySettings {
    /// Sheared images `N` per glossy image; 0 makes none.
    pub samples: u32,
    /// Glossy images are made from views of recursion level below this (1:
    /// from the camera only; 2, the default: also inside those, one shear per
    /// outer sample); deeper, a glossy face shows `R · L_lim`.
    pub depth: u32,
    /// The fog of each image.
    pub fog: Fog,
    /// `L_fog`, the radiance the fog fades towards (W/(m² sr)).
    pub fog_radiance: Vec3,
    /// Whether the sheared views hide emitters (the direct pass adds the
    /// highlight of point lights; see the module docs). False makes an
    /// image of everything, the emitters included.
    pub hide_emitters: bool,
    /// How the shears are drawn from the lobe.
    pub shear: ShearModel,
    /// Frosted glass (section 3, figure 3): the Beckmann roughness α of one
    /// face of every glass slab, 0 for clear glass. There is no rough
    /// dielectric material; this makes every slab of the scene frosted.
    pub frosted_alpha: f32,
}

/// How a glossy image's shears are drawn from its lobe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ShearModel {
    /// The paper's: isotropic `Δ = 2m`, equal weights ([`shear_slopes`]).
    #[default]
    Isotropic,
    /// The microfacet reflection at the face's centroid seen from the
    /// view's eye, each sample weighted by the microfacet estimator
    /// ([`microfacet_shears`]): exact at the centroid at any incidence.
    Microfacet,
}

impl Default for GlossySettings {
    fn default() -> Self {
        Self {
            samples: 0,
            depth: 2,
            fog: Fog::Material,
            fog_radiance: Vec3::ZERO,
            hide_emitters: true,
            shear: ShearModel::Isotropic,
            frosted_alpha: 0.0,
        }
    }
}

impl GlossySettings {
    /// Checks the settings (sample count, fog distance and radiance).
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(MprError::InvalidSetting {
                what: "glossy images",
                message,
            })
        };
        if self.samples > MAX_GLOSSY_SAMPLES {
            return bad(format!(
                "{} samples exceed the {MAX_GLOSSY_SAMPLES} a glossy image may take",
                self.samples
            ));
        }
        if let Fog::Distance(d) = self.fog
            && !(d > 0.0)
        {
            return bad(format!("fog distance {d} m is not positive"));
        }
        if !(self.frosted_alpha >= 0.0 && self.frosted_alpha.is_finite()) {
            return bad(format!(
                "frosted glass roughness {} is not ≥ 0",
                self.frosted_alpha
            ));
        }
        if !self.fog_radiance.is_finite() || self.fog_radiance.min_element() < 0.0 {
            return bad(format!(
                "fog radiance {} is not a radiance",
                self.fog_radiance
            ));
        }
        Ok(())
    }
}

/// The glossy part of a material as one lobe: its roughness `α` (RMS slope)
/// and its reflectance factor `R` (section 3's scattering reflective surface).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlossyLobe {
    /// RMS slope of the facet normals.
    pub alpha: f32,
    /// What the face passes of its image: the lobe's reflectance at normal incidence.
    pub factor: Vec3,
}

/// Phong's exponent `n` as a Beckmann roughness: `α = √(2/(n + 2))`.
pub fn phong_alpha(exponent: f32) -> f32 {
    (2.0 / (exponent.max(0.0) + 2.0)).sqrt()
}

/// Schlick-free Fresnel reflectance of a conductor at normal incidence, `((η−1)² + k²)/((η+1)² + k²)`.
fn conductor_f0(fresnel: &ConductorFresnel) -> Vec3 {
    match fresnel {
        ConductorFresnel::None => Vec3::ONE,
        ConductorFresnel::Complex { eta, k } => {
            let (eta, k) = (*eta, *k);
            ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k)
        }
    }
}

/// The glossy lobe of `model`, if it has one ([`GlossyLobe`]): a rough
/// conductor's `α` and `specular · F(0)`, Phong's `Ks` and `α² = 2/(n+2)`,
/// Ward's `ρ_s` and `√(α_x α_y)`; a blend's lobes weighted, `α` the
/// reflectance-weighted mean of its sides'. `None` for Lambertian, mirror,
/// dielectric and named models.
pub fn glossy_lobe(model: &MaterialModel) -> Option<GlossyLobe> {
    let lobe = match model {
        MaterialModel::RoughConductor {
            alpha,
            fresnel,
            specular,
            ..
        } => GlossyLobe {
            alpha: *alpha,
            factor: *specular * conductor_f0(fresnel),
        },
        MaterialModel::Phong {
            specular, exponent, ..
        } => GlossyLobe {
            alpha: phong_alpha(*exponent),
            factor: *specular,
        },
        MaterialModel::Ward {
            specular,
            alpha_x,
            alpha_y,
            ..
        } => GlossyLobe {
            alpha: (alpha_x * alpha_y).abs().sqrt(),
            factor: *specular,
        },
        MaterialModel::Blend {
            weight,
            first,
            second,
        } => {
            let sides = [
                glossy_lobe(first).map(|l| (l, 1.0 - weight)),
                glossy_lobe(second).map(|l| (l, *weight)),
            ];
            let mut factor = Vec3::ZERO;
            let (mut alpha_sum, mut mass) = (0.0, 0.0);
            for (lobe, w) in sides.into_iter().flatten() {
                factor += lobe.factor * w;
                let m = (lobe.factor * w).element_sum();
                alpha_sum += lobe.alpha * m;
                mass += m;
            }
            if mass <= 0.0 {
                return None;
            }
            GlossyLobe {
                alpha: alpha_sum / mass,
                factor,
            }
        }
        _ => return None,
    };
    (lobe.alpha.is_finite()
        && lobe.alpha > 0.0
        && lobe.factor.is_finite()
        && lobe.factor.max_element() > 0.0)
        .then_some(lobe)
}

/// The `N` shear slopes `Δ = 2m` of a lobe of roughness `α` (module docs):
/// stratified over [`hammersley_centred`], radius `2α √(−ln(1 − u))`
/// (the Rayleigh radius of a Gaussian with variance `2α²` per axis), angle
/// `2π v`. One sample is no shear (the mirror image).
pub fn shear_slopes(alpha: f32, samples: u32) -> Vec<Vec2> {
    if samples <= 1 {
        return vec![Vec2::ZERO; samples as usize];
    }
    (0..samples)
        .map(|i| {
            let u = hammersley_centred(i, samples);
            let radius = 2.0 * alpha * (-(1.0 - u.x).ln()).sqrt();
            let angle = std::f32::consts::TAU * u.y;
            Vec2::new(angle.cos(), angle.sin()) * radius
        })
        .collect()
}

/// Smith's masking `G₁` of the Beckmann distribution for a direction `cos θ`
/// from the normal (Walter et al. 2007's rational fit, within 0.35 %).
fn beckmann_g1(cos_theta: f32, alpha: f32) -> f32 {
    let cos = cos_theta.clamp(1e-6, 1.0);
    let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos;
    let a = 1.0 / (alpha * tan).max(1e-12);
    if a >= 1.6 {
        1.0
    } else {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    }
}

/// The `N` (shear, weight) pairs of a Beckmann lobe of roughness `alpha` at
/// the face point `centroid` of `plane` seen from `eye`: facet slopes `m`
/// from the stratified samples of [`shear_slopes`] (`m = Δ/2`, the slope
/// distribution `P₂₂`, i.e. half vectors drawn ∝ `D(h) cos θ_h`), the eye ray
/// reflected about each facet, the shear its slope minus the mirror
/// direction's, and the weight of the half-vector estimator
/// `G(i, o) |o·h| / (|i·n| (h·n))` (Walter et al. 2007, F taken out into the
/// face's factor); weight 0 where the facet is turned away from the eye or
/// reflects below the face. Near normal incidence and for small α this is
/// the isotropic `Δ ≈ 2m` with weights ≈ 1; at incidence θ the shear in the
/// plane of incidence grows by about `1/cos²θ`.
pub fn microfacet_shears(
    alpha: f32,
    samples: u32,
    eye: Vec3,
    plane: &lustre_geometry::Plane,
    centroid: Vec3,
) -> Vec<(Vec2, f32)> {
    let n = plane.normal.normalize();
    let (t, b) = crate::view::face_frame(plane);
    let to_eye = (eye - centroid).normalize();
    let i = -to_eye;
    let reflect = |h: Vec3| i - 2.0 * i.dot(h) * h;
    let slope = |v: Vec3| Vec2::new(v.dot(t), v.dot(b)) / v.dot(n);
    let mirror = slope(reflect(n));
    let cos_i = to_eye.dot(n);
    if !(cos_i > 0.0) {
        return vec![(Vec2::ZERO, 0.0); samples as usize];
    }
    let count = samples.max(1);
    let slopes = if count == 1 {
        vec![Vec2::ZERO]
    } else {
        shear_slopes(alpha, count)
    };
    slopes
        .into_iter()
        .map(|s| {
            let m = 0.5 * s;
            let h = (n + t * m.x + b * m.y).normalize();
            let o = reflect(h);
            let (cos_o, cos_h, o_h) = (o.dot(n), h.dot(n), o.dot(h));
            if !(cos_o > 1e-4) || to_eye.dot(h) <= 0.0 {
                return (Vec2::ZERO, 0.0);
            }
            let g = beckmann_g1(cos_i, alpha) * beckmann_g1(cos_o, alpha);
            (slope(o) - mirror, g * o_h.abs() / (cos_i * cos_h))
        })
        .collect()
}

/// The fog factor `f = clamp(1 − z / f_max, 0, 1)` of a point `z` m from the face (1: no fog).
pub fn fog_factor(z: f32, f_max: f32) -> f32 {
    if !f_max.is_finite() {
        return 1.0;
    }
    (1.0 - z.max(0.0) / f_max).clamp(0.0, 1.0)
}

/// The `f_max` of a lobe of roughness `alpha` in `scene` under `fog`.
pub fn fog_distance(scene: &Scene, alpha: f32, fog: Fog) -> f32 {
    match fog {
        Fog::Off => f32::INFINITY,
        Fog::Distance(d) => d,
        Fog::Material => {
            let bounds = scene.bounds();
            let diagonal = (bounds.max - bounds.min).length();
            if alpha > 0.0 && diagonal.is_finite() && diagonal > 0.0 {
                diagonal / (2.0 * alpha)
            } else {
                f32::INFINITY
            }
        }
    }
}

/// The glossy faces of `scene`: planar surfaces whose material has a glossy
/// lobe ([`glossy_lobe`]), each a [`SpecularKind::Glossy`] face of
/// `settings.samples` sheared images; none when `settings.samples` is 0.
pub fn glossy_faces(scene: &Scene, settings: &GlossySettings) -> Vec<SpecularFace> {
    if settings.samples == 0 {
        return Vec::new();
    }
    scene
        .surfaces()
        .iter()
        .enumerate()
        .filter_map(|(id, surface)| {
            let SurfaceKind::Planar(plane) = surface.kind else {
                return None;
            };
            let material = scene.materials().get(surface.material as usize)?;
            let lobe = glossy_lobe(&material.model)?;
            let positions = scene.world_positions(surface.mesh);
            let mesh = &scene.meshes()[surface.mesh as usize];
            let corners = surface
                .triangles
                .iter()
                .flat_map(|&t| mesh.indices[t as usize])
                .map(|i| positions[i as usize])
                .collect();
            Some(SpecularFace {
                surface: id as u32,
                plane,
                kind: SpecularKind::Glossy(GlossyImage {
                    alpha: lobe.alpha,
                    samples: settings.samples,
                    depth: settings.depth,
                    fog_distance: fog_distance(scene, lobe.alpha, settings.fog),
                    hide_emitters: settings.hide_emitters,
                    shear: settings.shear,
                    through_slab: None,
                }),
                factor: lobe.factor,
                corners,
            })
        })
        .collect()
}

/// `faces` with every glass slab frosted under `settings` (section 3,
/// "frosted glass", figure 3): with `frosted_alpha` α > 0 and samples, a
/// slab face becomes a glossy image of sheared slab views. A rough entry
/// face tilts the ray inside by `(1 − 1/η) m` for a facet slope `m` and the
/// smooth exit face multiplies the angle by `η` (small angles, normal
/// incidence): the ray leaves with its slope moved by `(η − 1) m`, so the
/// shears are [`shear_slopes`] of `α (η − 1)/2`, `η = 1/(1 − shift/t)`
/// from the slab's paraxial shift. Emitters stay visible behind the glass
/// (the direct pass adds no light through it); the fog is the paper's,
/// from the near face to `f_max`.
pub fn frosted(
    faces: Vec<SpecularFace>,
    scene: &Scene,
    settings: &GlossySettings,
) -> Vec<SpecularFace> {
    if settings.samples == 0 || !(settings.frosted_alpha > 0.0) {
        return faces;
    }
    faces
        .into_iter()
        .map(|face| match face.kind {
            SpecularKind::Slab { shift, thickness } if thickness > 0.0 && shift < thickness => {
                let eta = 1.0 / (1.0 - shift / thickness);
                let alpha = settings.frosted_alpha * (eta - 1.0) / 2.0;
                SpecularFace {
                    kind: SpecularKind::Glossy(GlossyImage {
                        alpha,
                        samples: settings.samples,
                        depth: settings.depth,
                        fog_distance: fog_distance(scene, alpha, settings.fog),
                        hide_emitters: false,
                        shear: ShearModel::Isotropic,
                        through_slab: Some((shift, thickness)),
                    }),
                    ..face
                }
            }
            _ => face,
        })
        .collect()
}

/// Which surfaces of `scene` make glossy images under `settings` (true at
/// their `SurfaceId`): the ones whose photon splats the renderer must drop.
pub fn imaged_surfaces(scene: &Scene, settings: &GlossySettings) -> Vec<bool> {
    let mut imaged = vec![false; scene.surfaces().len()];
    for face in glossy_faces(scene, settings) {
        imaged[face.surface as usize] = true;
    }
    imaged
}

/// One sheared image of a glossy image: sample `index` of the `count` this frame draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlossySample {
    /// The index of the face in the specular pass's faces.
    pub face: usize,
    /// Which sample.
    pub index: u32,
    /// Of how many drawn.
    pub count: u32,
    /// Its weight in the average (`1/count` for the paper's equal weights).
    pub weight: f32,
}

/// The per-face record of `glossy_image.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuGlossyFace {
    plane: [f32; 4],
    fog: [f32; 4],
    weight: [f32; 4],
}

/// The accumulation target of one recursion level.
#[derive(Debug)]
struct Accumulation {
    size: (u32, u32, wgpu::TextureFormat),
    view: wgpu::TextureView,
}

/// The GPU side of glossy images: fog, transfer into the accumulation
/// target of the outer level, and the resolve into the face.
#[derive(Debug)]
pub struct GlossyImagePass {
    fog: wgpu::RenderPipeline,
    transfer_first: wgpu::RenderPipeline,
    transfer_add: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    faces: wgpu::Buffer,
    /// Per face: whether its images are fogged.
    fogged: Vec<bool>,
    /// One accumulation target per outer recursion level, made on first use.
    accumulation: Mutex<Vec<Option<Accumulation>>>,
}

impl GlossyImagePass {
    /// Builds the pipelines for `faces` (the specular pass's, glossy or not) and HDR targets of `hdr_format`.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        faces: &[SpecularFace],
        fog_radiance: Vec3,
    ) -> Result<Self> {
        let mut records: Vec<GpuGlossyFace> = faces
            .iter()
            .map(|face| {
                let f_max = match face.kind {
                    SpecularKind::Glossy(g) => g.fog_distance,
                    _ => f32::INFINITY,
                };
                let inverse = if f_max.is_finite() { 1.0 / f_max } else { 0.0 };
                GpuGlossyFace {
                    plane: face.plane.to_vec4().to_array(),
                    fog: fog_radiance.extend(inverse).to_array(),
                    weight: face.factor.extend(0.0).to_array(),
                }
            })
            .collect();
        let fogged = records.iter().map(|r| r.fog[3] > 0.0).collect();
        if records.is_empty() {
            records.push(bytemuck::Zeroable::zeroed());
        }
        let depth_format = ctx.depth_format();
        ctx.checked("glossy image pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "glossy-image", &with_view(GLOSSY_IMAGE_WGSL));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("glossy-image"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Storage { read_only: true },
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("glossy-image"),
                bind_group_layouts: &[Some(ctx.view_layout()), Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = |label: &str,
                            vs: &str,
                            fs: &str,
                            depth_compare: wgpu::CompareFunction,
                            blend: Option<wgpu::BlendState>| {
                let scene = vs == "vs_main";
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers: if scene {
                            &[Some(GpuVertex::LAYOUT)]
                        } else {
                            &[]
                        },
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: depth_format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(depth_compare),
                        stencil: view_stencil(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: hdr_format,
                            blend,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            // dst * f + (1 - f) L_fog: src One, dst SrcAlpha; alpha kept.
            let fog_blend = wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::SrcAlpha,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::Zero,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
            };
            let equal = wgpu::CompareFunction::Equal;
            let always = wgpu::CompareFunction::Always;
            let fog = pipeline("glossy-fog", "vs_main", "fs_fog", equal, Some(fog_blend));
            // The sample's image times 1/N (the blend constant), replacing (sample 0) or added.
            let weighted = |dst_factor| wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::Constant,
                    dst_factor,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent::REPLACE,
            };
            let transfer_first = pipeline(
                "glossy-transfer-first",
                "vs_full",
                "fs_transfer",
                always,
                Some(weighted(wgpu::BlendFactor::Zero)),
            );
            let transfer_add = pipeline(
                "glossy-transfer-add",
                "vs_full",
                "fs_transfer",
                always,
                Some(weighted(wgpu::BlendFactor::One)),
            );
            let resolve = pipeline(
                "glossy-resolve",
                "vs_main",
                "fs_resolve",
                equal,
                Some(ADDITIVE),
            );
            let faces = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("glossy-faces"),
                contents: bytemuck::cast_slice(&records),
                usage: wgpu::BufferUsages::STORAGE,
            });
            Self {
                fog,
                transfer_first,
                transfer_add,
                resolve,
                layout,
                faces,
                fogged,
                accumulation: Mutex::new(Vec::new()),
            }
        })
    }

    /// The accumulation target of `level` for `targets` (made or remade on a size change).
    fn accumulation_view(
        &self,
        ctx: &GpuContext,
        targets: &RenderTargets,
        level: usize,
    ) -> wgpu::TextureView {
        let mut all = self.accumulation.lock().unwrap_or_else(|e| e.into_inner());
        if all.len() <= level {
            all.resize_with(level + 1, || None);
        }
        let size = (targets.width, targets.height, targets.hdr_format());
        if all[level].as_ref().is_none_or(|a| a.size != size) {
            let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("glossy-accumulation"),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: size.2,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            all[level] = Some(Accumulation { size, view });
        }
        all[level]
            .as_ref()
            .map(|a| a.view.clone())
            .unwrap_or_else(|| unreachable!("made above"))
    }

    fn bind_group(&self, ctx: &GpuContext, image: &wgpu::TextureView) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("glossy-image"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.faces.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(image),
                },
            ],
        })
    }

    /// After sample `sample` was drawn in the mask of `child` (level `k + 1`)
    /// inside the view `outer` (level `k`): the image fogged, then copied
    /// (sample 0) or added into the accumulation target of level `k`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_accumulate(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        child: ViewSlot,
        sample: GlossySample,
    ) {
        let face = sample.face as u32;
        let accumulation = self.accumulation_view(ctx, targets, outer.stencil_reference as usize);
        if self.fogged.get(sample.face).copied().unwrap_or(false) {
            let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "glossy-fog");
            pass.set_pipeline(&self.fog);
            views.bind(&mut pass, 0, child);
            // fs_fog reads no image; any texture but the HDR target it draws into.
            pass.set_bind_group(1, &self.bind_group(ctx, &accumulation), &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.draw(0..scene.vertex_count, face..face + 1);
        }
        let bind_group = self.bind_group(ctx, &targets.hdr.view);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("glossy-transfer"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &accumulation,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(if sample.index == 0 {
            &self.transfer_first
        } else {
            &self.transfer_add
        });
        views.bind(&mut pass, 0, child);
        pass.set_bind_group(1, &bind_group, &[]);
        let weight = f64::from(sample.weight);
        pass.set_blend_constant(wgpu::Color {
            r: weight,
            g: weight,
            b: weight,
            a: weight,
        });
        pass.draw(0..3, 0..1);
    }

    /// After the last sample, with the face restored in the view `outer`
    /// (level `k`, its image cleared): the accumulated average times `R`
    /// added on the face's pixels.
    pub fn encode_resolve(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        face: usize,
        indices: std::ops::Range<u32>,
    ) {
        let accumulation = self.accumulation_view(ctx, targets, outer.stencil_reference as usize);
        let bind_group = self.bind_group(ctx, &accumulation);
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "glossy-resolve");
        pass.set_pipeline(&self.resolve);
        views.bind(&mut pass, 0, outer);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        let face = face as u32;
        pass.draw_indexed(indices, 0, face..face + 1);
    }
}

impl crate::FrameGraph {
    /// [`crate::FrameGraph::with_specular`] with the glossy images of
    /// `glossy` too (section 3, "glossy marble"; [`SpecularPass::with_glossy`]).
    pub fn with_glossy_images(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &Scene,
        settings: SpecularSettings,
        glossy: &GlossySettings,
    ) -> Result<Self> {
        self.specular = Some(SpecularPass::with_glossy(
            ctx, hdr_format, scene, settings, glossy,
        )?);
        Ok(self)
    }

    /// [`crate::FrameGraph::view_tree`] for frame `s` of `n` accumulated
    /// ones: the glossy images' shears interleaved over the frames
    /// ([`crate::passes::specular::ViewTree::build_interleaved`]).
    pub fn view_tree_interleaved(
        &self,
        ctx: &GpuContext,
        camera: &lustre_geometry::Camera,
        s: u32,
        n: u32,
    ) -> Result<crate::passes::specular::ViewTree> {
        let root = crate::View::from_camera(camera);
        match &self.specular {
            Some(specular) => specular.view_tree_interleaved(root, ctx.clip_method(), Some((s, n))),
            None => Ok(crate::passes::specular::ViewTree::single(root)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shear_slopes_have_the_lobes_second_moment() {
        // E|Δ|² = 4α² for Δ = 2m, E|m|² = α² (module docs); stratified, so close at N = 256.
        let alpha = 0.05;
        let slopes = shear_slopes(alpha, 256);
        let second = slopes.iter().map(|s| s.length_squared()).sum::<f32>() / 256.0;
        assert!(
            (second / (4.0 * alpha * alpha) - 1.0).abs() < 0.05,
            "{second}"
        );
        let mean = slopes.iter().copied().sum::<Vec2>() / 256.0;
        assert!(mean.length() < 0.05 * alpha, "{mean}");
        assert_eq!(shear_slopes(alpha, 1), vec![Vec2::ZERO]);
    }

    #[test]
    fn lobes_map_to_alpha() {
        // Phong n = 198: α² = 2/200.
        assert!((phong_alpha(198.0) - 0.1).abs() < 1e-6);
        let floor = lustre_geometry::builtin::glosbox();
        let glossy: Vec<GlossyLobe> = floor
            .materials()
            .iter()
            .filter_map(|m| glossy_lobe(&m.model))
            .collect();
        // Gold (α 0.1, F0 of gold) and the floor's 0.3 of a rough mirror (α 0.05, F = 1).
        assert_eq!(glossy.len(), 2);
        assert!((glossy[0].alpha - 0.1).abs() < 1e-6);
        assert!(glossy[0].factor.x > 0.8 && glossy[0].factor.z < 0.5);
        assert!((glossy[1].alpha - 0.05).abs() < 1e-6);
        assert!((glossy[1].factor - Vec3::splat(0.3)).abs().max_element() < 1e-6);
        assert!(
            glossy_lobe(&MaterialModel::Diffuse {
                reflectance: Vec3::ONE
            })
            .is_none()
        );
    }

    #[test]
    fn microfacet_shears_are_the_isotropic_ones_at_normal_incidence_and_stretch_at_grazing() {
        let plane = lustre_geometry::Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
        let alpha = 0.02;
        let iso = shear_slopes(alpha, 64);
        let normal = microfacet_shears(alpha, 64, Vec3::new(0.0, 2.0, 0.0), &plane, Vec3::ZERO);
        for ((s, w), d) in normal.iter().zip(&iso) {
            // Δ = 2m to first order: the error is O(m²) relative.
            assert!((*s - *d).length() < 0.02 * d.length() + 1e-6, "{s} vs {d}");
            assert!((w - 1.0).abs() < 0.01, "{w}");
        }
        // At 70° incidence the in-plane spread grows by about 1/cos²70° ≈ 8.5.
        let theta = 70f32.to_radians();
        let eye = 2.0 * Vec3::new(0.0, theta.cos(), theta.sin());
        let (t, b) = crate::view::face_frame(&plane);
        let grazing = microfacet_shears(alpha, 64, eye, &plane, Vec3::ZERO);
        let along = |v: Vec2| (t * v.x + b * v.y).z;
        let across = |v: Vec2| (t * v.x + b * v.y).x;
        let rms = |f: &dyn Fn(Vec2) -> f32, set: &[Vec2]| {
            (set.iter().map(|v| f(*v).powi(2)).sum::<f32>() / set.len() as f32).sqrt()
        };
        let g: Vec<Vec2> = grazing.iter().map(|(s, _)| *s).collect();
        let stretch = rms(&along, &g) / rms(&along, &iso);
        let side = rms(&across, &g) / rms(&across, &iso);
        let expected = 1.0 / theta.cos().powi(2);
        assert!(
            (stretch / expected - 1.0).abs() < 0.1,
            "{stretch} vs {expected}"
        );
        assert!((side - 1.0).abs() < 0.1, "{side}");
    }

    #[test]
    fn nested_shears_permute_the_outer_ones() {
        use crate::passes::specular::nested_shear_index;
        for n in [1u32, 2, 3, 4, 16, 64, 100] {
            let mut seen: Vec<u32> = (0..n).map(|p| nested_shear_index(p, n)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..n).collect::<Vec<_>>(), "n = {n}");
        }
    }

    #[test]
    fn fog_is_linear_from_the_face_to_f_max() {
        assert_eq!(fog_factor(0.0, 2.0), 1.0);
        assert_eq!(fog_factor(1.0, 2.0), 0.5);
        assert_eq!(fog_factor(3.0, 2.0), 0.0);
        assert_eq!(fog_factor(3.0, f32::INFINITY), 1.0);
    }
}
