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
//! [`lustre_geometry::light::hammersley_centred`] strata). Other lobes map to an `α`
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

use glam::Vec3;
use lustre_geometry::Scene;
use lustre_geometry::SurfaceKind;
use wgpu::util::DeviceExt;

use crate::light_group::GlossyLights;
pub use crate::passes::glossy_lobe::{
    GlossyLobe, fog_factor, glossy_lobe, microfacet_shears, phong_alpha, shear_slopes,
};
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
    /// Which jittered lights each sheared view draws ([`crate::light_group`]).
    pub lights: GlossyLights,
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
            lights: GlossyLights::default(),
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
                    lights: settings.lights,
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
                        lights: settings.lights,
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
    /// The fog without its radiance (`fs_fog_dark`).
    fog_dark: wgpu::RenderPipeline,
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
            let fog_dark = pipeline(
                "glossy-fog-dark",
                "vs_main",
                "fs_fog_dark",
                equal,
                Some(fog_blend),
            );
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
                fog_dark,
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
    /// inside the view `outer` (level `k`): the image fogged (towards the
    /// fog radiance with `fog_radiance`, else towards black: the fog
    /// radiance is a constant term, drawn with the emitters), then copied
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
        fog_radiance: bool,
    ) {
        let face = sample.face as u32;
        let accumulation = self.accumulation_view(ctx, targets, outer.stencil_reference as usize);
        if self.fogged.get(sample.face).copied().unwrap_or(false) {
            let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "glossy-fog");
            pass.set_pipeline(if fog_radiance {
                &self.fog
            } else {
                &self.fog_dark
            });
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
        pass.set_blend_constant(crate::passes::redraw::uniform_constant(f64::from(
            sample.weight,
        )));
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
    #[test]
    fn nested_shears_permute_the_outer_ones() {
        use crate::passes::specular::nested_shear_index;
        for n in [1u32, 2, 3, 4, 16, 64, 100] {
            let mut seen: Vec<u32> = (0..n).map(|p| nested_shear_index(p, n)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..n).collect::<Vec<_>>(), "n = {n}");
        }
    }
}
