//! The splat pass (Stürzlinger & Bastos 1997, sections 2.2 and 3.2): every
//! photon hit drawn as a textured triangle on its surface's plane, coloured
//! by its power times the BRDF towards the viewer and added into the HDR
//! target. Splats are restricted to the visible part of their own surface in
//! one of two ways ([`Restriction`]): a surface-id test in one draw, or the
//! paper's per-surface stencil mask built from the depth buffer. The CPU
//! counterpart is [`splat_pass_cpu`], built on
//! [`SplatEstimator::radiance_splatted`]. [`SplatPass::encode_at`] draws the
//! camera view's splats at a lower resolution instead
//! ([`crate::passes::splat_lowres`]).

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use bytemuck::{Pod, Zeroable};
use glam::Vec2;
use lustre_geometry::{Bvh, Camera, Scene, SurfaceId};
use lustre_photon::{
    Kernel, KernelMass, Splat, SplatEstimator, SurfaceParam, SurfaceParams, UvMap,
};

use crate::diffuse_map::DiffuseMaps;
use crate::kernel_texture::{KERNEL_TEXTURE_SIZE, kernel_texture};
use crate::material::{GlossyModel, GpuMaterial, scene_materials};
use crate::passes::direct::check_layers;
use crate::passes::redraw::{scene_module, view_stencil};
use crate::passes::splat_lowres::{LowResTargets, SplatLowRes, SplatResolution};
use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::shaders::{DEPTH_WGSL, with_diffuse_maps, with_materials, with_view};
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The splat WGSL (`src/passes/splat.wgsl`), without the material prefix.
pub const SPLAT_WGSL: &str = include_str!("splat.wgsl");

/// The splat pass as compiled: [`SPLAT_WGSL`] after the view, the diffuse maps and the materials.
pub fn splat_wgsl() -> String {
    with_materials(&with_diffuse_maps(&with_view(SPLAT_WGSL)))
}

/// How each splat is limited to the visible part of its own surface (section 2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Restriction {
    /// One draw of every splat; the fragment compares the splat's surface with the depth pre-pass's surface id.
    #[default]
    SurfaceId,
    /// The paper's method: per surface, a stencil mask from the surface's triangles with an equal-depth test, then its splats with a stencil test.
    Stencil,
}

/// How the kernel texture is read per pixel (section 3.2: "Mip-mapping is used for filtering of small triangles").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KernelFiltering {
    /// Trilinear mip-mapping with 16× anisotropic filtering: the kernel averaged over each pixel's footprint, as the paper filters small splats.
    #[default]
    MipMapped,
    /// The kernel evaluated exactly at the pixel centre, as the CPU estimator does (the formula, no texture: cheaper than a fetch on a software rasteriser).
    PixelCentre,
}

/// One splat as the GPU reads it (instance attributes of `vs_splat`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuSplat {
    /// Photon position `x_p` in m.
    pub position: [f32; 3],
    /// Scene `SurfaceId`.
    pub surface: u32,
    /// Unit incoming direction `wi`.
    pub incoming: [f32; 3],
    /// Kernel support `h` in m (equation 3).
    pub h: f32,
    /// Photon power `φ` in W (equation 1).
    pub power: [f32; 3],
    /// Index of the texture mapping of the photon's triangle in [`SplatBuffers`]' table ([`GpuUvMap`]), by which the splat reads its surface's diffuse map; [`NO_UV_MAP`] on a surface without one.
    pub uv_map: u32,
    /// Unit surface normal at `x_p` (winding side; flipped to the eye in the shader).
    pub normal: [f32; 3],
    /// Padding.
    pub pad: f32,
}

/// Marks a splat without a texture mapping in [`GpuSplat::uv_map`].
pub const NO_UV_MAP: u32 = u32::MAX;

/// A triangle's texture mapping over its plane (lustre-photon's [`UvMap`]), as `splat.wgsl` reads it (`UvMap`): `uv(x) = (u0, v0) + (du · (x − origin), dv · (x − origin))`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuUvMap {
    /// The triangle's corner 0 in m.
    pub origin: [f32; 3],
    /// `u` at `origin`.
    pub u0: f32,
    /// Gradient of `u` (per m).
    pub du: [f32; 3],
    /// `v` at `origin`.
    pub v0: f32,
    /// Gradient of `v` (per m).
    pub dv: [f32; 3],
    /// Padding.
    pub pad: f32,
}

impl GpuUvMap {
    /// The GPU form of a mapping.
    pub fn new(m: &UvMap) -> Self {
        Self {
            origin: m.origin.to_array(),
            u0: m.uv.x,
            du: m.du.to_array(),
            v0: m.uv.y,
            dv: m.dv.to_array(),
            pad: 0.0,
        }
    }
}

/// A vertex attribute at a byte offset (the padded fields of [`GpuSplat`] rule out `vertex_attr_array!`).
const fn attribute(
    format: wgpu::VertexFormat,
    offset: u64,
    location: u32,
) -> wgpu::VertexAttribute {
    wgpu::VertexAttribute {
        format,
        offset,
        shader_location: location,
    }
}

impl GpuSplat {
    /// Instance layout: locations 0-6 (position, surface, incoming, h, power, normal, uv_map) at the struct's offsets.
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: size_of::<GpuSplat>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &[
            attribute(wgpu::VertexFormat::Float32x3, 0, 0),
            attribute(wgpu::VertexFormat::Uint32, 12, 1),
            attribute(wgpu::VertexFormat::Float32x3, 16, 2),
            attribute(wgpu::VertexFormat::Float32, 28, 3),
            attribute(wgpu::VertexFormat::Float32x3, 32, 4),
            attribute(wgpu::VertexFormat::Float32x3, 48, 5),
            attribute(wgpu::VertexFormat::Uint32, 44, 6),
        ],
    };

    /// The GPU form of a splat, its texture mapping at `uv_map` ([`NO_UV_MAP`] for none).
    pub fn new(s: &Splat, uv_map: u32) -> Self {
        Self {
            position: s.position.to_array(),
            surface: s.surface,
            incoming: s.incoming.to_array(),
            h: s.h,
            power: s.power.to_array(),
            uv_map,
            normal: s.normal.to_array(),
            pad: 0.0,
        }
    }
}

/// Marks a surface without a kernel-mass grid in [`GpuMassGrid::offset`]: its estimate is not divided (`M = 1`).
pub const NO_MASS_GRID: u32 = u32::MAX;

/// The record of a surface without a kernel-mass grid.
const NO_GRID: GpuMassGrid = GpuMassGrid {
    origin: [0.0; 3],
    offset: NO_MASS_GRID,
    u_axis: [0.0; 3],
    columns: 0,
    v_axis: [0.0; 3],
    rows: 0,
    min: [0.0; 2],
    spacing: [0.0; 2],
};

/// One surface's grid of the kernel's mass on the surface (lustre-photon's [`KernelMass`], the paper's future work on polygon edges), as `splat.wgsl` reads it (`MassGrid`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuMassGrid {
    /// Origin of the surface's `(u, v)` frame in m.
    pub origin: [f32; 3],
    /// Index of sample `(0, 0)` in the values buffer, or [`NO_MASS_GRID`].
    pub offset: u32,
    /// Unit `u` axis.
    pub u_axis: [f32; 3],
    /// Samples along `u`.
    pub columns: u32,
    /// Unit `v` axis.
    pub v_axis: [f32; 3],
    /// Samples along `v`.
    pub rows: u32,
    /// `(u, v)` of sample `(0, 0)` in m.
    pub min: [f32; 2],
    /// Sample spacing along `u` and `v` in m.
    pub spacing: [f32; 2],
}

/// The per-surface records and the concatenated values of `mass`'s grids (every surface [`NO_MASS_GRID`] without `mass`, a single such record without `params`); never empty, for binding.
pub fn gpu_mass_grids(
    params: Option<&SurfaceParams>,
    mass: Option<&KernelMass>,
) -> (Vec<GpuMassGrid>, Vec<f32>) {
    let params = params.map_or(&[][..], SurfaceParams::all);
    let mut records = Vec::with_capacity(params.len().max(1));
    let mut values = Vec::new();
    for (id, param) in params.iter().enumerate() {
        let grid = mass.and_then(|m| m.grid(id as u32));
        let record = match (param, grid) {
            (SurfaceParam::Planar(frame), Some(g)) => {
                let offset = values.len() as u32;
                values.extend_from_slice(&g.values);
                GpuMassGrid {
                    origin: frame.origin.to_array(),
                    offset,
                    u_axis: frame.u_axis.to_array(),
                    columns: g.columns,
                    v_axis: frame.v_axis.to_array(),
                    rows: g.rows,
                    min: g.min.to_array(),
                    spacing: g.spacing.to_array(),
                }
            }
            _ => NO_GRID,
        };
        records.push(record);
    }
    if records.is_empty() {
        records.push(NO_GRID);
    }
    if values.is_empty() {
        values.push(1.0);
    }
    (records, values)
}

/// The splats of a photon map on the GPU, grouped by surface, with the materials they are shaded with (the precomputed triangles of section 2.2).
#[derive(Debug)]
pub struct SplatBuffers {
    /// Instance buffers, each with the global instance range it holds (split to stay under the device's buffer size limit).
    chunks: Vec<(wgpu::Buffer, Range<u32>)>,
    /// Instance range of each surface, by `SurfaceId`.
    pub surface_ranges: Vec<Range<u32>>,
    materials: wgpu::Buffer,
    surface_materials: wgpu::Buffer,
    /// [`GpuMassGrid`] by `SurfaceId` (every one [`NO_MASS_GRID`] unless built from an estimator with normalised edges).
    mass_grids: wgpu::Buffer,
    /// The grids' values, concatenated.
    mass_values: wgpu::Buffer,
    /// The scene's diffuse maps, read where each splat lands (only the white layer when no splat reads them).
    maps: DiffuseMaps,
    /// The splats' texture mappings ([`GpuUvMap`], each distinct one once; one unused record when none).
    uv_maps: wgpu::Buffer,
    /// Number of splats.
    pub count: u32,
    /// Each uploaded splat's centre and support `h`, `[x, y, z, h]`, for choosing the splat resolution ([`SplatResolution::auto`]).
    pub supports: Vec<[f32; 4]>,
}

impl SplatBuffers {
    /// Number of instance buffers the splats are split into.
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }
}

impl SplatBuffers {
    /// Uploads the splats of `estimator` (all its selected photons), shading with `glossy`.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        estimator: &SplatEstimator,
        glossy: GlossyModel,
    ) -> Result<Self> {
        Self::upload(
            ctx,
            scene,
            &estimator.splats(),
            glossy,
            1 << 27,
            &[],
            Some(estimator),
            None,
        )
    }

    /// Uploads the splats of `estimator` for the surfaces whose Lambertian lobes another pass renders where `textured` (by `SurfaceId`) is true, such as the precomputed diffuse textures of section 2.2.1: a purely Lambertian such surface gets no splats, any other keeps its splats shaded without its Lambertian lobes ([`GpuMaterial::without_lambert`]). Surfaces beyond `textured` are splatted whole.
    pub fn new_excluding(
        ctx: &GpuContext,
        scene: &Scene,
        estimator: &SplatEstimator,
        glossy: GlossyModel,
        textured: &[bool],
    ) -> Result<Self> {
        let splats = estimator.splats();
        Self::upload(
            ctx,
            scene,
            &splats,
            glossy,
            1 << 27,
            textured,
            Some(estimator),
            None,
        )
    }

    /// [`SplatBuffers::new_excluding`] without any splat on the surfaces
    /// where `imaged` is true: the glossy faces whose glossy lobe a glossy
    /// image carries (Diefenbach & Badler 1997, section 3;
    /// [`crate::passes::glossy_image`]). Their Lambertian lobe must be in
    /// `textured`: an imaged surface with a Lambertian lobe outside it is an error.
    /// `maps` are the scene's diffuse maps as another pass uploaded them
    /// ([`DiffuseMaps::upload`] of `scene`), shared instead of uploaded again
    /// (once per batch of a streamed photon file).
    pub fn new_excluding_imaged(
        ctx: &GpuContext,
        scene: &Scene,
        estimator: &SplatEstimator,
        glossy: GlossyModel,
        textured: &[bool],
        imaged: &[bool],
        maps: &DiffuseMaps,
    ) -> Result<Self> {
        let is = |flags: &[bool], s: u32| flags.get(s as usize).copied().unwrap_or(false);
        for (id, surface) in scene.surfaces().iter().enumerate() {
            let id = id as u32;
            let lambert = scene
                .materials()
                .get(surface.material as usize)
                .is_some_and(|m| m.model.diffuse_reflectance().max_element() > 0.0);
            if is(imaged, id) && lambert && !is(textured, id) {
                return Err(MprError::InvalidSetting {
                    what: "splats",
                    message: format!(
                        "surface {id} of `{}` makes a glossy image but its Lambertian lobe is \
                         not in the diffuse textures",
                        scene.name
                    ),
                });
            }
        }
        let splats: Vec<Splat> = estimator
            .splats()
            .into_iter()
            .filter(|s| !is(imaged, s.surface))
            .collect();
        Self::upload(
            ctx,
            scene,
            &splats,
            glossy,
            1 << 27,
            textured,
            Some(estimator),
            Some(maps),
        )
    }

    /// Uploads `splats` (any order; they are grouped by surface here) in buffers of at most 128 MiB, with truncated kernels at polygon edges (no kernel-mass grids).
    pub fn from_splats(
        ctx: &GpuContext,
        scene: &Scene,
        splats: &[Splat],
        glossy: GlossyModel,
    ) -> Result<Self> {
        Self::from_splats_chunked(ctx, scene, splats, glossy, 1 << 27)
    }

    /// [`SplatBuffers::from_splats`] with instance buffers of at most `max_chunk_bytes` (and the device's limit).
    pub fn from_splats_chunked(
        ctx: &GpuContext,
        scene: &Scene,
        splats: &[Splat],
        glossy: GlossyModel,
        max_chunk_bytes: u64,
    ) -> Result<Self> {
        Self::upload(ctx, scene, splats, glossy, max_chunk_bytes, &[], None, None)
    }

    /// [`SplatBuffers::from_splats_chunked`] for the surfaces whose Lambertian lobes another pass renders where `textured` is true ([`SplatBuffers::new_excluding`]), with the kernel-mass grids of `estimator` (none without one), reading the scene's diffuse maps from `maps` where given (uploaded here where a splat needs them otherwise).
    fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        splats: &[Splat],
        glossy: GlossyModel,
        max_chunk_bytes: u64,
        textured: &[bool],
        estimator: Option<&SplatEstimator>,
        maps: Option<&DiffuseMaps>,
    ) -> Result<Self> {
        let mut materials = scene_materials(scene, glossy)?;
        // A textured surface whose every lobe is Lambertian gets no splats; any other textured one is shaded without its Lambertian lobes.
        let textured_as = |surface: SurfaceId, diffuse: bool| {
            textured.get(surface as usize).copied().unwrap_or(false)
                && scene
                    .surfaces()
                    .get(surface as usize)
                    .and_then(|s| materials.get(s.material as usize))
                    .is_some_and(|m| m.is_diffuse() == diffuse)
        };
        let without_lambert: Vec<bool> = (0..scene.surfaces().len() as SurfaceId)
            .map(|s| textured_as(s, false))
            .collect();
        let excluded: Vec<bool> = (0..scene.surfaces().len() as SurfaceId)
            .map(|s| textured_as(s, true))
            .collect();
        let surfaces = scene.surfaces().len();
        let mut by_surface: Vec<Vec<GpuSplat>> = vec![Vec::new(); surfaces];
        // Each distinct texture mapping once (a triangle's photons share its mapping).
        let mut uv_maps: Vec<GpuUvMap> = Vec::new();
        let mut uv_map_index: std::collections::HashMap<[u32; 12], u32> =
            std::collections::HashMap::new();
        for s in splats {
            let list =
                by_surface
                    .get_mut(s.surface as usize)
                    .ok_or_else(|| MprError::InvalidSetting {
                        what: "splats",
                        message: format!("surface {} is not in scene `{}`", s.surface, scene.name),
                    })?;
            if s.h > 0.0 && s.power.is_finite() && !excluded[s.surface as usize] {
                let uv_map = s.uv_map.map_or(NO_UV_MAP, |m| {
                    let record = GpuUvMap::new(&m);
                    *uv_map_index
                        .entry(bytemuck::cast(record))
                        .or_insert_with(|| {
                            uv_maps.push(record);
                            (uv_maps.len() - 1) as u32
                        })
                });
                list.push(GpuSplat::new(s, uv_map));
            }
        }
        let mut instances = Vec::with_capacity(splats.len());
        let mut surface_ranges = Vec::with_capacity(surfaces);
        for list in by_surface {
            let start = instances.len() as u32;
            instances.extend(list);
            surface_ranges.push(start..instances.len() as u32);
        }
        let count = instances.len() as u32;
        let supports = instances
            .iter()
            .map(|s| [s.position[0], s.position[1], s.position[2], s.h])
            .collect();
        if instances.is_empty() {
            instances.push(GpuSplat::zeroed());
        }
        if materials.is_empty() {
            materials.push(GpuMaterial::zeroed());
        }
        // Each material a surface needs without its Lambertian lobes, once, after the scene's own.
        let mut variants: Vec<Option<u32>> = vec![None; materials.len()];
        let mut surface_materials = Vec::with_capacity(scene.surfaces().len().max(1));
        for (id, surface) in scene.surfaces().iter().enumerate() {
            let m = surface.material as usize;
            if without_lambert.get(id).copied().unwrap_or(false) && m < variants.len() {
                let index = *variants[m].get_or_insert_with(|| {
                    materials.push(materials[m].without_lambert());
                    (materials.len() - 1) as u32
                });
                surface_materials.push(index);
            } else {
                surface_materials.push(surface.material);
            }
        }
        if surface_materials.is_empty() {
            surface_materials.push(0);
        }
        // The maps only where a splat reads them (a textured scene's batches whose splats all lie on untextured surfaces bind the white layer alone).
        let maps = if uv_maps.is_empty() {
            uv_maps.push(GpuUvMap::zeroed());
            DiffuseMaps::white(ctx)?
        } else if let Some(maps) = maps {
            check_layers(&materials, maps)?;
            maps.clone()
        } else {
            DiffuseMaps::upload(ctx, scene)?
        };
        use wgpu::util::DeviceExt;
        let buffer = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            ctx.checked("splat upload", || {
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage,
                    })
            })
        };
        let (mass_records, mass_values) = gpu_mass_grids(
            estimator.map(SplatEstimator::params),
            estimator.and_then(SplatEstimator::kernel_mass),
        );
        let limit = ctx.device.limits().max_buffer_size.min(max_chunk_bytes);
        let per_chunk = (limit / size_of::<GpuSplat>() as u64).max(1) as usize;
        let mut chunks = Vec::with_capacity(instances.len().div_ceil(per_chunk));
        for (i, part) in instances.chunks(per_chunk).enumerate() {
            let start = (i * per_chunk) as u32;
            chunks.push((
                buffer(
                    "splat-instances",
                    bytemuck::cast_slice(part),
                    wgpu::BufferUsages::VERTEX,
                )?,
                start..start + part.len() as u32,
            ));
        }
        Ok(Self {
            chunks,
            materials: buffer(
                "splat-materials",
                bytemuck::cast_slice(&materials),
                wgpu::BufferUsages::STORAGE,
            )?,
            surface_materials: buffer(
                "splat-surface-materials",
                bytemuck::cast_slice(&surface_materials),
                wgpu::BufferUsages::STORAGE,
            )?,
            mass_grids: buffer(
                "splat-mass-grids",
                bytemuck::cast_slice(&mass_records),
                wgpu::BufferUsages::STORAGE,
            )?,
            mass_values: buffer(
                "splat-mass-values",
                bytemuck::cast_slice(&mass_values),
                wgpu::BufferUsages::STORAGE,
            )?,
            maps,
            uv_maps: buffer(
                "splat-uv-maps",
                bytemuck::cast_slice(&uv_maps),
                wgpu::BufferUsages::STORAGE,
            )?,
            surface_ranges,
            count,
            supports,
        })
    }
}

/// The splat pass's uniform block (`SplatUniforms` in `splat.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SplatUniforms {
    /// `x`: unused (the filtering is the pipeline's, see [`SplatPass::prepare`]); `y`: 1 for [`Kernel::Gaussian`], 0 for Silverman's.
    pub options: [u32; 4],
    /// `xy`: the NDC shift of the low-resolution splats (`vs_splat_low`), written by [`SplatPass::encode_at`]; `zw` unused.
    pub low_res_offset: [f32; 4],
}

/// The splat pipelines of one [`KernelFiltering`]: each restriction's fragment
/// stage is compiled per filtering, not switched by a uniform (`splat.wgsl`
/// says why: llvmpipe runs both sides of a uniform branch).
#[derive(Debug)]
struct FilteringPipelines {
    splat_id: wgpu::RenderPipeline,
    /// The surface-id restriction into a low-resolution target, without depth or stencil ([`SplatPass::encode_at`]).
    splat_low: wgpu::RenderPipeline,
    splat_stencil: Option<wgpu::RenderPipeline>,
}

/// The GPU splat pass: pipelines of both restriction methods and both kernel filterings, the kernel texture and the uniforms.
#[derive(Debug)]
pub struct SplatPass {
    layout: wgpu::BindGroupLayout,
    centre: FilteringPipelines,
    mip_mapped: FilteringPipelines,
    /// The filtering of the last [`SplatPass::prepare`]: true for [`KernelFiltering::MipMapped`].
    mip_mapped_prepared: AtomicBool,
    /// The guide and upsampling of low-resolution splats.
    lowres: SplatLowRes,
    mask: Option<wgpu::RenderPipeline>,
    uniforms: wgpu::Buffer,
    kernel_view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    kernel: Kernel,
}

/// Additive blending: `dst + src` on colour and alpha (section 3.2, "hardware blending functions set up to add").
const ADD: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

/// Stencil state that writes the reference wherever depth and stencil tests pass.
fn stencil_replace() -> wgpu::StencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Replace,
    };
    wgpu::StencilState {
        front: face,
        back: face,
        read_mask: 0xff,
        write_mask: 0xff,
    }
}

impl SplatPass {
    /// Builds the pipelines for an HDR target of `hdr_format` and the kernel texture of `kernel` (64 × 64 with mips).
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat, kernel: Kernel) -> Result<Self> {
        let texture = kernel_texture(ctx, kernel, KERNEL_TEXTURE_SIZE)?;
        let depth_format = ctx.depth_format();
        let has_stencil = ctx.has_stencil();
        let lowres = SplatLowRes::new(ctx, hdr_format)?;
        ctx.checked("splat pass creation", || {
            let device = &ctx.device;
            let source = splat_wgsl();
            let module = scene_module(ctx, "splat", &source);
            // The depth pre-pass's shader for the per-surface stencil masks, under the same view.
            let depth_module = scene_module(ctx, "splat-mask-depth", &with_view(DEPTH_WGSL));
            let storage = |binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let fragment_storage = |binding| wgpu::BindGroupLayoutEntry {
                visibility: wgpu::ShaderStages::FRAGMENT,
                ..storage(binding)
            };
            let uniform_entry = wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(size_of::<SplatUniforms>() as u64),
                },
                count: None,
            };
            let [maps_array, maps_sampler] =
                DiffuseMaps::layout_entries(8, wgpu::ShaderStages::FRAGMENT);
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("splat"),
                entries: &[
                    uniform_entry,
                    storage(1),
                    storage(2),
                    wgpu::BindGroupLayoutEntry {
                        binding: 3,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: true },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 4,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 5,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Uint,
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    fragment_storage(6),
                    fragment_storage(7),
                    maps_array,
                    maps_sampler,
                    storage(10),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("splat"),
                bind_group_layouts: &[Some(ctx.view_layout()), Some(&layout)],
                immediate_size: 0,
            });
            let mask_pipeline_layout =
                device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("splat-mask"),
                    bind_group_layouts: &[Some(ctx.view_layout())],
                    immediate_size: 0,
                });
            let splat_pipeline_with =
                |vertex: &str, entry: &str, depth_stencil: Option<wgpu::DepthStencilState>| {
                    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some(vertex),
                            compilation_options: Default::default(),
                            buffers: &[Some(GpuSplat::LAYOUT)],
                        },
                        primitive: wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleList,
                            cull_mode: None,
                            ..Default::default()
                        },
                        depth_stencil,
                        multisample: wgpu::MultisampleState::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some(entry),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format: hdr_format,
                                blend: Some(ADD),
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                };
            let splat_pipeline = |entry: &str, depth_stencil: Option<wgpu::DepthStencilState>| {
                splat_pipeline_with("vs_splat", entry, depth_stencil)
            };
            // Both restrictions under the view's stencil test (only the view's
            // pixels); the surface-id one also at low resolution, against the
            // low-resolution surface-id guide.
            let under_view_stencil = || {
                Some(wgpu::DepthStencilState {
                    format: depth_format,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: view_stencil(),
                    bias: wgpu::DepthBiasState::default(),
                })
            };
            let filtering_pipelines = |id_entry: &str, stencil_entry: &str| FilteringPipelines {
                splat_id: splat_pipeline(id_entry, under_view_stencil()),
                splat_low: splat_pipeline_with("vs_splat_low", id_entry, None),
                splat_stencil: has_stencil
                    .then(|| splat_pipeline(stencil_entry, under_view_stencil())),
            };
            let centre = filtering_pipelines("fs_splat_id", "fs_splat_stencil");
            let mip_mapped = filtering_pipelines("fs_splat_id_mip", "fs_splat_stencil_mip");
            let mask = if has_stencil {
                let mask = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("splat-mask"),
                    layout: Some(&mask_pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &depth_module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[Some(GpuVertex::LAYOUT)],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: depth_format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(wgpu::CompareFunction::Equal),
                        stencil: stencil_replace(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_mask"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: hdr_format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::empty(),
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                Some(mask)
            } else {
                None
            };
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat-uniforms"),
                size: size_of::<SplatUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("splat-kernel"),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                // Splats seen at grazing angles have long, thin footprints:
                // anisotropic filtering keeps them from blurring across the short axis.
                anisotropy_clamp: 16,
                ..Default::default()
            });
            Self {
                layout,
                centre,
                mip_mapped,
                mip_mapped_prepared: AtomicBool::new(false),
                lowres,
                mask,
                uniforms,
                kernel_view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
                sampler,
                kernel,
            }
        })
    }

    /// Whether [`Restriction::Stencil`] is available (the device has a depth format with stencil).
    pub fn supports_stencil(&self) -> bool {
        self.mask.is_some()
    }

    /// Sets the kernel filtering for the next [`SplatPass::encode`] (the camera comes from the view).
    pub fn prepare(&self, queue: &wgpu::Queue, filtering: KernelFiltering) {
        self.mip_mapped_prepared
            .store(filtering == KernelFiltering::MipMapped, Ordering::Relaxed);
        let uniforms = SplatUniforms {
            options: [0, u32::from(self.kernel == Kernel::Gaussian), 0, 0],
            low_res_offset: [0.0; 4],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Records the pass after the view's depth pass: adds every splat into
    /// `targets.hdr` where the stencil holds the view's reference, restricted
    /// by `restriction`. [`Restriction::Stencil`] writes the stencil itself,
    /// so it is refused in a virtual view (stencil reference above 0).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        splats: &SplatBuffers,
        targets: &RenderTargets,
        restriction: Restriction,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        let bind_group = self.bind_group(device, splats, &targets.surface_id.view);
        let pipelines = self.prepared_pipelines();
        match restriction {
            Restriction::SurfaceId => {
                let mut pass = begin(encoder, targets, None);
                if splats.count > 0 {
                    pass.set_pipeline(&pipelines.splat_id);
                    views.bind(&mut pass, 0, slot);
                    pass.set_bind_group(1, &bind_group, &[]);
                    for range in visible_splats(scene, splats, targets, slot) {
                        draw_instances(&mut pass, splats, range);
                    }
                }
            }
            Restriction::Stencil => {
                let (Some(mask), Some(splat_stencil)) = (&self.mask, &pipelines.splat_stencil)
                else {
                    return Err(MprError::InvalidSetting {
                        what: "splat restriction",
                        message: "the device has no depth format with stencil \
                                  (Depth32FloatStencil8); use the surface-id restriction"
                            .into(),
                    });
                };
                if slot.stencil_reference != 0 {
                    return Err(MprError::InvalidSetting {
                        what: "splat restriction",
                        message: "per-surface stencil masks need the stencil the specular \
                                  images use; use the surface-id restriction with mirrors"
                            .into(),
                    });
                }
                // Stencil references 1..=255 name the surfaces of one render
                // pass; a new pass clears the stencil before they repeat.
                let surfaces: Vec<usize> = (0..splats.surface_ranges.len())
                    .filter(|&s| {
                        !splats.surface_ranges[s].is_empty()
                            && scene.surface_ranges.get(s).is_some_and(|r| !r.is_empty())
                    })
                    .collect();
                for (chunk_index, chunk) in surfaces.chunks(255).enumerate() {
                    let stencil_load = if chunk_index == 0 {
                        wgpu::LoadOp::Load
                    } else {
                        wgpu::LoadOp::Clear(0)
                    };
                    let mut pass = begin(encoder, targets, Some(stencil_load));
                    for (i, &s) in chunk.iter().enumerate() {
                        pass.set_pipeline(mask);
                        views.bind(&mut pass, 0, slot);
                        pass.set_stencil_reference(i as u32 + 1);
                        pass.set_vertex_buffer(0, scene.vertices.slice(..));
                        pass.set_index_buffer(
                            scene.surface_indices.slice(..),
                            wgpu::IndexFormat::Uint32,
                        );
                        pass.draw_indexed(scene.surface_ranges[s].clone(), 0, 0..1);
                        pass.set_pipeline(splat_stencil);
                        pass.set_bind_group(1, &bind_group, &[]);
                        draw_instances(&mut pass, splats, splats.surface_ranges[s].clone());
                    }
                }
            }
        }
        Ok(())
    }
    /// The pipelines of the filtering [`SplatPass::prepare`] set last.
    fn prepared_pipelines(&self) -> &FilteringPipelines {
        if self.mip_mapped_prepared.load(Ordering::Relaxed) {
            &self.mip_mapped
        } else {
            &self.centre
        }
    }

    /// The splat bind group over `splats`, restricting by the surface ids in `surface_ids`.
    fn bind_group(
        &self,
        device: &wgpu::Device,
        splats: &SplatBuffers,
        surface_ids: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: splats.materials.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: splats.surface_materials.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&self.kernel_view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::TextureView(surface_ids),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: splats.mass_grids.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: splats.mass_values.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 8,
                    resource: wgpu::BindingResource::TextureView(splats.maps.view()),
                },
                wgpu::BindGroupEntry {
                    binding: 9,
                    resource: wgpu::BindingResource::Sampler(splats.maps.sampler()),
                },
                wgpu::BindGroupEntry {
                    binding: 10,
                    resource: splats.uv_maps.as_entire_binding(),
                },
            ],
        })
    }

    /// [`SplatPass::encode`] at `resolution`: at [`SplatResolution::Full`],
    /// or in a virtual view (stencil reference above 0, whose splats are
    /// limited to its stencilled area), exactly [`SplatPass::encode`];
    /// otherwise the surface-id restriction drawn into [`LowResTargets`]
    /// against the low-resolution guide and upsampled into `targets.hdr`
    /// ([`crate::passes::splat_lowres`]), which [`Restriction::Stencil`]
    /// cannot do (an error). Returns the low-resolution targets when they were used.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_at(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        splats: &SplatBuffers,
        targets: &RenderTargets,
        restriction: Restriction,
        resolution: SplatResolution,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<Option<LowResTargets>> {
        if resolution == SplatResolution::Full || slot.stencil_reference != 0 {
            self.encode(
                &ctx.device,
                encoder,
                scene,
                splats,
                targets,
                restriction,
                views,
                slot,
            )?;
            return Ok(None);
        }
        if restriction != Restriction::SurfaceId {
            return Err(MprError::InvalidSetting {
                what: "splat resolution",
                message: "splats below full resolution are restricted by surface ids; \
                          use the surface-id restriction or the full resolution"
                    .into(),
            });
        }
        let device = &ctx.device;
        // The NDC shift of vs_splat_low (applied at submit, with prepare's options).
        let offset = [
            -1.0 / targets.width as f32,
            1.0 / targets.height as f32,
            0.0,
            0.0,
        ];
        ctx.queue.write_buffer(
            &self.uniforms,
            std::mem::offset_of!(SplatUniforms, low_res_offset) as u64,
            bytemuck::cast_slice(&offset),
        );
        let low = LowResTargets::new(ctx, targets, resolution);
        self.lowres.encode_guides(device, encoder, targets, &low);
        let bind_group = self.bind_group(device, splats, &low.ids.view);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("splat-lowres"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &low.radiance.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if splats.count > 0 {
                // The frame's NDC square onto width/f × height/f pixels and
                // shifted by half a full-resolution pixel (vs_splat_low), so the
                // low-resolution pixel centre i + 1/2 lies on the centre of full-resolution pixel f i + f/2.
                let f = resolution.factor() as f32;
                pass.set_viewport(
                    0.0,
                    0.0,
                    targets.width as f32 / f,
                    targets.height as f32 / f,
                    0.0,
                    1.0,
                );
                pass.set_pipeline(&self.prepared_pipelines().splat_low);
                views.bind(&mut pass, 0, slot);
                pass.set_bind_group(1, &bind_group, &[]);
                draw_instances(&mut pass, splats, 0..splats.count);
            }
        }
        self.lowres.encode_upsample(
            device,
            encoder,
            targets,
            &low,
            slot.scissor_in(targets.width, targets.height),
        );
        Ok(Some(low))
    }
}

/// The instance ranges of the splats of the surfaces that may show in the
/// view's region ([`crate::view::surfaces_in_region`], the viewpoint culling
/// of Diefenbach & Badler 1997, section 8), adjacent ranges merged. Under the
/// surface-id restriction a splat adds only where its own surface is seen,
/// so the splats left out add nothing there: the sums are the same, without
/// the vertex work of every splat in every virtual view.
fn visible_splats(
    scene: &SceneBuffers,
    splats: &SplatBuffers,
    targets: &RenderTargets,
    slot: ViewSlot,
) -> Vec<Range<u32>> {
    let (width, height) = (targets.width, targets.height);
    let visible = crate::view::surfaces_in_region(
        &scene.surface_boxes,
        slot.view_projection,
        slot.scissor_in(width, height),
        width,
        height,
    );
    crate::view::surface_draw_ranges(&visible, &splats.surface_ranges)
}

/// Draws the splats of the global instance range `range`, chunk by chunk.
fn draw_instances(pass: &mut wgpu::RenderPass<'_>, splats: &SplatBuffers, range: Range<u32>) {
    for (buffer, held) in &splats.chunks {
        let (lo, hi) = (range.start.max(held.start), range.end.min(held.end));
        if lo < hi {
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..3, lo - held.start..hi - held.start);
        }
    }
}

/// A render pass adding into the HDR target over the depth-stencil target: read only, or with `stencil` its stencil loaded so and written.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    targets: &RenderTargets,
    stencil: Option<wgpu::LoadOp<u32>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("splat"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &targets.hdr.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(match stencil {
            Some(load) => wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                }),
            },
            // Read only: the view's stencil test, nothing written.
            None => wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: None,
                stencil_ops: None,
            },
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// CPU counterpart of [`SplatPass`]: per pixel centre, the visible surface
/// point (BVH ray cast) and [`SplatEstimator::radiance_splatted`] towards the
/// camera position. Pixels that see no surface are zero. Row 0 is the top.
pub fn splat_pass_cpu(
    estimator: &SplatEstimator,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<[f32; 3]> {
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    let eye = camera.position;
    bvh.closest_hits(&rays)
        .iter()
        .map(|hit| {
            hit.map_or([0.0; 3], |h| {
                estimator
                    .radiance_splatted(h.surface, h.position, h.shading_normal, eye)
                    .to_array()
            })
        })
        .collect()
}

/// The surface seen at each pixel by the CPU ray cast ([`crate::NO_SURFACE`] where none), for masking comparisons.
pub fn visible_surfaces_cpu(bvh: &Bvh, camera: &Camera, width: u32, height: u32) -> Vec<u32> {
    crate::passes::depth::depth_pass_cpu(bvh, camera, width, height).surface
}
