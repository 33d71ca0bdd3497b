//! The beam pass of Duvenhage, Bouatouch & Kourie (2010), sections 3.1 and
//! 4.3: the scene redrawn over the depth pre-pass, and per fragment every
//! specular, glossy and shadow beam of a [`BeamSet`] that may hold it
//! evaluated and its light added, `L += f_r(-d, wo) E` (equation 1; section
//! 4.2, figures 11 and 12 for glossy beams). The beams live in a storage
//! buffer (the paper packs them into a texture, eight texels a beam); the
//! fragment visits all of them, the paper's linear traversal, or only those
//! whose slab boxes in the beam hierarchy hold it ([`Traversal`], the
//! hierarchy the paper leaves to future work, section 5.2). A beam is cut
//! into up to 64 slab boxes and a point may lie in several; the GPU counts
//! a beam only from the box whose flux-plane range `[lo, hi)` holds the
//! point ([`lustre_beams::BeamSlab`]), where the CPU sorts and
//! de-duplicates. CPU twin: [`beam_pixels_cpu`], lustre-beams'
//! [`lustre_beams::Beam::arrival`] through the same BRDFs.
//!
//! Four choices here are for the software driver, not the paper. The pass's
//! settings are a read-only storage buffer, not a uniform block: lavapipe
//! (Mesa 22.3) folds uniform values that steer a fragment shader's loops and
//! branches into the shader and compiles it anew whenever a bind group
//! changes, and it kept doing so for this shader (most likely because the
//! linear traversal's loop over the beam count unrolls, which its test of
//! whether inlining paid reads as a gain): the pass is drawn once per view,
//! so a `glosbox` frame of 112 views spent about 10 s compiling. And the fragment
//! stage calls the beam evaluation from one place for both traversals,
//! since every call is inlined. And the shader is compiled without the
//! planar facets' volume (equation 5 and the split points) when no beam
//! takes it ([`beams_wgsl_with`]): llvmpipe runs the code of a branch that
//! no lane takes under an empty mask, and dropping the facets' code took
//! the beam pass of a 640 × 480 `glosbox` walkthrough frame from 1.25 to
//! 0.88 s. And the traversal counts a beam as found only where it may
//! light the fragment (in front of its generator plane, inside its
//! support: `beam_supports`, the tests `Beam::arrival` starts with), so
//! that a block of fragments none of which a candidate beam lights skips
//! its evaluation: llvmpipe runs a loop's body as often as its busiest lane
//! needs but every branch inside it, so before, each candidate whose box
//! held some lane cost the whole evaluation (the same frame's beam pass
//! 0.96 → 0.52 s). The image is the same bit for bit.

use lustre_beams::{Beam, BeamSet, GlossyVolume, Scatter, SplitPoint};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, Camera, Rgb, Scene};
use wgpu::util::DeviceExt;

use crate::diffuse_map::{DiffuseMaps, WHITE_LAYER};
use crate::material::{GlossyModel, scene_materials};
use crate::passes::direct::{check_layers, cpu_brdfs, primary_hits};
use crate::passes::redraw::{ScenePipeline, additive_target, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::{switched_off, with_diffuse_maps, with_materials, with_view};
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The beam pass's own WGSL (`src/passes/beams.wgsl`); compiled after the material and view modules ([`beams_wgsl`]).
pub const BEAMS_WGSL: &str = include_str!("beams.wgsl");

/// The beam pass as compiled: [`BEAMS_WGSL`] after the view block, the diffuse map lookups and the material module.
pub fn beams_wgsl() -> String {
    with_materials(&with_diffuse_maps(&with_view(BEAMS_WGSL)))
}

/// The line of `beams.wgsl` that keeps the planar facets' volume (equation 5) in the shader.
const FACET_VOLUMES_ON: &str = "const FACET_VOLUMES: bool = true;";

/// [`beams_wgsl`] with the planar facets' volume (section 4.2.2, equation 5
/// and its split points) compiled in or, with `facets` false, only the
/// integrated Gaussian: the same values for beams of
/// [`GlossyVolume::Integrated`], and a shader llvmpipe runs faster since it
/// executes a branch no lane takes (module docs).
pub fn beams_wgsl_with(facets: bool) -> Result<String> {
    let source = beams_wgsl();
    // Built either way, so that a renamed switch fails for both.
    let off = switched_off(source.clone(), FACET_VOLUMES_ON, "beam pass", "beams.wgsl")?;
    Ok(if facets { source } else { off })
}

/// Whether any glossy beam of `beams` takes the planar facets' volume.
fn uses_facets(beams: &BeamSet) -> bool {
    beams
        .beams()
        .iter()
        .any(|b| b.distribution.is_some() && b.volume == GlossyVolume::Facets)
}

/// How a fragment finds the beams that may hold it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Traversal {
    /// Every beam, in order: the paper's linear traversal (section 4.3).
    Linear,
    /// The beams whose slab boxes in [`lustre_beams::BeamHierarchy`] hold the fragment (section 5.2, future work); fragments outside the scene's box fall back to the linear traversal.
    #[default]
    Hierarchy,
}

/// One beam as the shader reads it (`GpuBeam` in `beams.wgsl`), std430.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBeam {
    /// Ray origins `A_W, B_W, C_W` (w unused).
    pub vertices: [[f32; 4]; 3],
    /// Unit ray directions (w unused).
    pub directions: [[f32; 4]; 3],
    /// The directions bounding a glossy beam's support ([`Beam::support_directions`]).
    pub support: [[f32; 4]; 3],
    /// The scatterer's vertex normals on the light's side.
    pub normals: [[f32; 4]; 3],
    /// `Φ_s` (RGB, negative for shadow beams) and σ² (0 for a specular beam).
    pub flux: [f32; 4],
    /// Generator plane: unit normal and offset.
    pub generator: [f32; 4],
    /// Average wavefront normal and, for refracted beams, η.
    pub wavefront: [f32; 4],
    /// The light's position (w unused).
    pub light: [f32; 4],
    /// 0 reflect, 1 refract, 2 straight ([`Scatter`]).
    pub scatter: u32,
    /// 0 domain, 1 paper, 2 rescattered ([`SplitPoint`]).
    pub split: u32,
    /// 0 the paper's facets, 1 the integrated Gaussian ([`GlossyVolume`]).
    pub volume: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

fn vec4(v: glam::Vec3) -> [f32; 4] {
    [v.x, v.y, v.z, 0.0]
}

impl GpuBeam {
    /// The GPU form of a beam.
    pub fn new(beam: &Beam) -> Self {
        let (scatter, eta) = match beam.scatter {
            Scatter::Reflect => (0, 1.0),
            Scatter::Refract { eta } => (1, eta),
            Scatter::Straight => (2, 1.0),
        };
        Self {
            vertices: beam.vertices.map(vec4),
            directions: beam.directions.map(vec4),
            support: beam.support_directions.map(vec4),
            normals: beam.normals.map(vec4),
            flux: [
                beam.flux.x,
                beam.flux.y,
                beam.flux.z,
                beam.distribution.map_or(0.0, |d| d.variance),
            ],
            generator: [
                beam.generator_normal.x,
                beam.generator_normal.y,
                beam.generator_normal.z,
                beam.generator_offset,
            ],
            wavefront: [
                beam.wavefront_normal.x,
                beam.wavefront_normal.y,
                beam.wavefront_normal.z,
                eta,
            ],
            light: vec4(beam.light_position),
            scatter,
            split: match beam.split_point {
                SplitPoint::Domain => 0,
                SplitPoint::Paper => 1,
                SplitPoint::Rescattered => 2,
            },
            volume: match beam.volume {
                GlossyVolume::Facets => 0,
                GlossyVolume::Integrated => 1,
            },
            pad: 0,
        }
    }
}

/// A node of the beam hierarchy (`BeamNode` in `beams.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBeamNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Leaf: first item; inner: right child.
    pub link: u32,
    /// Box maximum.
    pub max: [f32; 3],
    /// Items of a leaf, 0 for an inner node.
    pub count: u32,
}

/// A slab box of a beam (`BeamItem` in `beams.wgsl`): its beam and its flux-plane range.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBeamItem {
    /// Index of the beam.
    pub beam: u32,
    /// Padding.
    pub pad: u32,
    /// Lower end of the range of `n_F · P` (`-f32::MAX` for the first slab).
    pub lo: f32,
    /// Upper end, exclusive (`f32::MAX` for the last slab).
    pub hi: f32,
}

/// The pass's settings (`BeamSettings` in `beams.wgsl`), read from a storage buffer (see the module notes).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuBeamSettings {
    bounds_min: [f32; 3],
    hierarchy: u32,
    bounds_max: [f32; 3],
    beam_count: u32,
    node_count: u32,
    pad: [u32; 3],
}

/// A [`BeamSet`] flattened for the GPU: beams, hierarchy nodes and items.
#[derive(Debug, Clone, PartialEq)]
pub struct GpuBeams {
    /// The beams in [`BeamSet::beams`] order.
    pub beams: Vec<GpuBeam>,
    /// The hierarchy's nodes ([`lustre_beams::BeamHierarchy::nodes`]).
    pub nodes: Vec<GpuBeamNode>,
    /// The hierarchy's items, each its beam and slab range.
    pub items: Vec<GpuBeamItem>,
}

impl GpuBeams {
    /// Flattens `set`.
    pub fn new(set: &BeamSet) -> Self {
        let beams = set.beams().iter().map(GpuBeam::new).collect();
        let nodes = set
            .hierarchy()
            .nodes()
            .into_iter()
            .map(|n| GpuBeamNode {
                min: n.bounds.min.to_array(),
                link: n.link,
                max: n.bounds.max.to_array(),
                count: n.count,
            })
            .collect();
        let finite = |x: f32| x.clamp(-f32::MAX, f32::MAX);
        let items = set
            .hierarchy()
            .items()
            .iter()
            .map(|&i| {
                let (beam, [lo, hi]) = set.item(i);
                GpuBeamItem {
                    beam,
                    pad: 0,
                    lo: finite(lo),
                    hi: finite(hi),
                }
            })
            .collect();
        Self {
            beams,
            nodes,
            items,
        }
    }

    /// Bytes the three buffers take.
    pub fn byte_size(&self) -> usize {
        self.beams.len() * size_of::<GpuBeam>()
            + self.nodes.len() * size_of::<GpuBeamNode>()
            + self.items.len() * size_of::<GpuBeamItem>()
    }
}

/// A storage buffer of `data`, one zeroed element where `data` is empty (a zero-sized binding is invalid).
fn storage<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let zero = [T::zeroed()];
    let contents: &[T] = if data.is_empty() { &zero } else { data };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(contents),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// The GPU beam pass (sections 3.1, 4.3) with its beams, materials and traversal.
#[derive(Debug)]
pub struct BeamPass {
    pipeline: wgpu::RenderPipeline,
    hdr_format: wgpu::TextureFormat,
    /// Whether `pipeline` holds the planar facets' volume ([`beams_wgsl_with`]).
    facets: bool,
    layout: wgpu::BindGroupLayout,
    materials: wgpu::Buffer,
    /// The receivers' diffuse maps (bindings 5 and 6).
    maps: DiffuseMaps,
    bind_group: wgpu::BindGroup,
    beam_count: usize,
    byte_size: usize,
    traversal: Traversal,
}

impl BeamPass {
    /// Builds the pipeline for HDR targets of `hdr_format` (blendable) and uploads `beams` with `scene`'s materials (flattened with `glossy`) and diffuse `maps` ([`DiffuseMaps::upload`] of `scene`, or [`DiffuseMaps::white`]), drawn with `traversal`.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &Scene,
        glossy: GlossyModel,
        maps: &DiffuseMaps,
        beams: &BeamSet,
        traversal: Traversal,
    ) -> Result<Self> {
        if !ctx.is_blendable(hdr_format) {
            return Err(MprError::UnsupportedFormat {
                what: "beam pass HDR target (additive blending)",
                format: hdr_format,
            });
        }
        // `storage` binds one zeroed material for a scene without any.
        // Each material's map layer is the scene's; white maps read none.
        let mut materials = scene_materials(scene, glossy)?;
        if !maps.is_textured() {
            for m in &mut materials {
                m.diffuse_map[0] = WHITE_LAYER;
            }
        }
        check_layers(&materials, maps)?;
        let facets = uses_facets(beams);
        let (pipeline, layout, materials) = ctx.checked_result("beam pass creation", || {
            let device = &ctx.device;
            let read_only = |binding: u32| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let maps_entries = DiffuseMaps::layout_entries(5, wgpu::ShaderStages::FRAGMENT);
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("beams"),
                entries: &[
                    read_only(0),
                    read_only(1),
                    read_only(2),
                    read_only(3),
                    read_only(4),
                    maps_entries[0],
                    maps_entries[1],
                ],
            });
            let pipeline = Self::pipeline(ctx, hdr_format, &layout, facets)?;
            let materials = storage(ctx, "beam-materials", &materials);
            Ok((pipeline, layout, materials))
        })?;
        let (bind_group, byte_size) =
            Self::upload(ctx, &layout, &materials, maps, beams, traversal)?;
        Ok(Self {
            pipeline,
            hdr_format,
            facets,
            layout,
            materials,
            maps: maps.clone(),
            bind_group,
            beam_count: beams.beams().len(),
            byte_size,
            traversal,
        })
    }

    /// The pass's pipeline, compiled with or without the planar facets' volume ([`beams_wgsl_with`]).
    fn pipeline(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        layout: &wgpu::BindGroupLayout,
        facets: bool,
    ) -> Result<wgpu::RenderPipeline> {
        let module = scene_module(ctx, "beams", &beams_wgsl_with(facets)?);
        Ok(scene_pipeline(
            ctx,
            &ScenePipeline {
                label: "beams",
                module: &module,
                layouts: &[layout],
                extra_vertex_buffers: &[],
                target: additive_target(hdr_format),
                depth_compare: wgpu::CompareFunction::Equal,
                depth_write: false,
            },
        ))
    }

    fn upload(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        materials: &wgpu::Buffer,
        maps: &DiffuseMaps,
        beams: &BeamSet,
        traversal: Traversal,
    ) -> Result<(wgpu::BindGroup, usize)> {
        let flat = GpuBeams::new(beams);
        let count = |n: usize, what: &str| {
            u32::try_from(n).map_err(|_| MprError::InvalidSetting {
                what: "beam pass",
                message: format!("{n} {what}: more than the GPU indexes"),
            })
        };
        let bounds = beams.bounds();
        let settings = GpuBeamSettings {
            bounds_min: bounds.min.to_array(),
            hierarchy: u32::from(traversal == Traversal::Hierarchy),
            bounds_max: bounds.max.to_array(),
            beam_count: count(flat.beams.len(), "beams")?,
            node_count: count(flat.nodes.len(), "hierarchy nodes")?,
            pad: [0; 3],
        };
        ctx.checked("beam upload", || {
            let beam_buffer = storage(ctx, "beams", &flat.beams);
            let node_buffer = storage(ctx, "beam-nodes", &flat.nodes);
            let item_buffer = storage(ctx, "beam-items", &flat.items);
            let settings_buffer =
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("beam-settings"),
                        contents: bytemuck::bytes_of(&settings),
                        usage: wgpu::BufferUsages::STORAGE,
                    });
            let [map_view, map_sampler] = maps.entries(5);
            let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("beams"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: materials.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: beam_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: node_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: item_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: settings_buffer.as_entire_binding(),
                    },
                    map_view,
                    map_sampler,
                ],
            });
            (bind_group, flat.byte_size())
        })
    }

    /// Replaces the beams (the scatterers or lights moved: beams are rebuilt on the CPU every frame, section 4.3), keeping the traversal.
    pub fn set_beams(&mut self, ctx: &GpuContext, beams: &BeamSet) -> Result<()> {
        let facets = uses_facets(beams);
        if facets != self.facets {
            self.pipeline = ctx.checked_result("beam pass pipeline", || {
                Self::pipeline(ctx, self.hdr_format, &self.layout, facets)
            })?;
            self.facets = facets;
        }
        let (bind_group, byte_size) = Self::upload(
            ctx,
            &self.layout,
            &self.materials,
            &self.maps,
            beams,
            self.traversal,
        )?;
        self.bind_group = bind_group;
        self.byte_size = byte_size;
        self.beam_count = beams.beams().len();
        Ok(())
    }

    /// Beams uploaded.
    pub fn beam_count(&self) -> usize {
        self.beam_count
    }

    /// Bytes of the beams, nodes and items on the GPU.
    pub fn byte_size(&self) -> usize {
        self.byte_size
    }

    /// The traversal the fragments use.
    pub fn traversal(&self) -> Traversal {
        self.traversal
    }

    /// Records the pass after the depth pre-pass: the beams' light added on every visible surface under the view of `slot`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) {
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "beams");
        if scene.vertex_count == 0 || self.beam_count == 0 {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return;
        }
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.draw(0..scene.vertex_count, 0..1);
    }
}

/// The radiance the beams add at a surface point: `Σ f_r(-d, wo) E` over the beams that light it ([`BeamSet::for_each_arrival`]), in the frame of the shading normal `n` flipped to the viewer's side; `shift` is the receiver's diffuse map at the point ([`lustre_geometry::Material::diffuse_shift`]), added to `f_r` where both directions lie above the surface.
pub fn beam_radiance_cpu(
    beams: &BeamSet,
    brdf: &dyn lustre_brdf::Brdf,
    shift: Option<Rgb>,
    p: glam::Vec3,
    n: glam::Vec3,
    wo: glam::Vec3,
    traversal: Traversal,
) -> Rgb {
    let frame = Frame::from_normal(n);
    let wo_local = frame.to_local(wo);
    let mut radiance = Rgb::ZERO;
    beams.for_each_arrival(p, n, traversal == Traversal::Hierarchy, |_, e, d| {
        let wi_local = frame.to_local(-d);
        let mut f = brdf.eval(wi_local, wo_local);
        if let Some(shift) = shift
            && wi_local.z > 0.0
            && wo_local.z > 0.0
        {
            f += shift;
        }
        radiance += f * e;
    });
    radiance
}

/// CPU counterpart of [`BeamPass`]: through each pixel centre the closest hit, and there [`beam_radiance_cpu`] with the material's BRDF (row 0 at the top; zero on a miss).
pub fn beam_pixels_cpu(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    glossy: GlossyModel,
    beams: &BeamSet,
    traversal: Traversal,
) -> Result<Vec<[f32; 3]>> {
    let brdfs = cpu_brdfs(scene, glossy)?;
    let (rays, hits) = primary_hits(bvh, camera, width, height);
    Ok(rays
        .iter()
        .zip(hits)
        .map(|(ray, hit)| {
            let Some(hit) = hit else {
                return [0.0; 3];
            };
            let wo = -ray.direction;
            let n = if hit.shading_normal.dot(wo) < 0.0 {
                -hit.shading_normal
            } else {
                hit.shading_normal
            };
            beam_radiance_cpu(
                beams,
                brdfs[hit.material as usize].as_ref(),
                scene.materials()[hit.material as usize].diffuse_shift(hit.uv),
                hit.position,
                n,
                wo,
                traversal,
            )
            .to_array()
        })
        .collect())
}
