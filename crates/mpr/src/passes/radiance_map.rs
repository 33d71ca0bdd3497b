//! Radiance-map reprojection on the GPU: the selected maps of a reflector drawn into its reflected view as depth-tested boxes of equation 3's size, the mirror-like image M (Bastos et al. 1999, section 8.1.3). CPU twin: [`lustre_ibr::reprojection`].
//!
//! The maps' texels are uploaded once ([`RadianceMapBuffers`]) as world
//! points with radiance. Per frame the CPU does what the paper does on the
//! host: selection, view-frustum culling of quadtree nodes and equation 3
//! at each leaf's representative point ([`lustre_ibr::leaf_draws`]); the
//! leaves go to the GPU with their first instance, and one instanced draw
//! covers every texel they take (a vertex shader finds its leaf by binary
//! search). The boxes are drawn in the CPU twin's order, so the depth test
//! keeps the same point where two are equally near. Only the per-node
//! point size is drawn here (the paper's hierarchy); the per-point variant
//! is the CPU's.

use bytemuck::{Pod, Zeroable};
use lustre_ibr::{PinholeView, ReflectorMaps, leaf_draws};
use wgpu::util::DeviceExt;

use crate::{GpuContext, MprError, Result};

/// The pass's WGSL (`src/passes/radiance_map.wgsl`).
pub const RADIANCE_MAP_WGSL: &str = include_str!("radiance_map.wgsl");

/// Format of the reflected image's radiance.
pub const REFLECTED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Format of the reflected image's depth.
pub const REFLECTED_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Near distance of the reverse-Z depth (depth = near / z).
pub const REFLECTED_NEAR: f32 = 1e-3;

/// One texel on the GPU: world point (w = 1 where it sees something) and radiance.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GpuTexel {
    point: [f32; 4],
    radiance: [f32; 4],
}

/// One leaf on the GPU (`Leaf` in the WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GpuLeaf {
    rect: [u32; 4],
    step_cols_offset: [u32; 4],
    size_width_first: [f32; 4],
}

/// A [`PinholeView`] on the GPU: eye and axes (w unused), then focal lengths and principal point; the leading fields of `View` here and `Params` in the glossy-reflection pass.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuPinhole {
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    focal_principal: [f32; 4],
}

impl GpuPinhole {
    /// The GPU layout of `view`.
    pub(crate) fn new(view: &PinholeView) -> Self {
        Self {
            eye: view.eye.extend(1.0).to_array(),
            right: view.right.extend(0.0).to_array(),
            up: view.up.extend(0.0).to_array(),
            forward: view.forward.extend(0.0).to_array(),
            focal_principal: [
                view.focal.x,
                view.focal.y,
                view.principal.x,
                view.principal.y,
            ],
        }
    }
}

/// The view on the GPU (`View` in the WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GpuView {
    pinhole: GpuPinhole,
    size_near_leaves: [f32; 4],
}

/// A `width × height` 2D texture of one mip level and sample.
pub(crate) fn texture_2d(
    ctx: &GpuContext,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// One reflector's radiance maps on the GPU: every texel's world point and radiance, map after map.
#[derive(Debug)]
pub struct RadianceMapBuffers {
    texels: wgpu::Buffer,
    /// Index of each map's first texel.
    offsets: Vec<u32>,
}

impl RadianceMapBuffers {
    /// Uploads the texels of `maps`.
    pub fn upload(ctx: &GpuContext, maps: &ReflectorMaps) -> Result<Self> {
        let mut texels = Vec::new();
        let mut offsets = Vec::with_capacity(maps.maps.len());
        for m in &maps.maps {
            offsets.push(texels.len() as u32);
            for j in 0..m.height {
                for i in 0..m.width {
                    let r = m.radiance_at(i, j);
                    texels.push(GpuTexel {
                        point: m
                            .world_point(i, j)
                            .map_or([0.0; 4], |p| p.extend(1.0).to_array()),
                        radiance: r.extend(1.0).to_array(),
                    });
                }
            }
        }
        if texels.is_empty() {
            texels.push(GpuTexel::zeroed());
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let bytes = (texels.len() * size_of::<GpuTexel>()) as u64;
        if bytes > limit {
            return Err(MprError::InvalidSetting {
                what: "radiance maps",
                message: format!(
                    "{bytes} bytes of texels exceed the device's storage binding limit of {limit}; use fewer or smaller maps"
                ),
            });
        }
        let texels = ctx.checked("radiance-map upload", || {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("radiance-map-texels"),
                    contents: bytemuck::cast_slice(&texels),
                    usage: wgpu::BufferUsages::STORAGE,
                })
        })?;
        Ok(Self { texels, offsets })
    }
}

/// The reflected image M's targets: radiance and depth.
#[derive(Debug, Clone)]
pub struct ReflectedTargets {
    /// Radiance ([`REFLECTED_FORMAT`]).
    pub color: wgpu::Texture,
    /// Reverse-Z depth ([`REFLECTED_DEPTH_FORMAT`]).
    pub depth: wgpu::Texture,
}

impl ReflectedTargets {
    /// Targets of `width × height` pixels.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self> {
        ctx.checked("reflected-image targets", || {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING;
            Self {
                color: texture_2d(
                    ctx,
                    "reflected-radiance",
                    width,
                    height,
                    REFLECTED_FORMAT,
                    usage,
                ),
                depth: texture_2d(
                    ctx,
                    "reflected-depth",
                    width,
                    height,
                    REFLECTED_DEPTH_FORMAT,
                    usage,
                ),
            }
        })
    }
}

/// The reprojection pipeline.
#[derive(Debug)]
pub struct RadianceMapPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl RadianceMapPass {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        ctx.checked("radiance-map pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("radiance-map"),
                source: wgpu::ShaderSource::Wgsl(RADIANCE_MAP_WGSL.into()),
            });
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
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("radiance-map"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::VERTEX,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                    storage(1),
                    storage(2),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("radiance-map"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("radiance-map"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: REFLECTED_DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Greater),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: REFLECTED_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            Self { pipeline, layout }
        })
    }

    /// Records the reprojection of maps `selected` (indices into `maps.maps`, e.g. [`lustre_ibr::select`]'s) into `view`, clearing `targets` first; returns the number of boxes drawn.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        maps: &ReflectorMaps,
        buffers: &RadianceMapBuffers,
        selected: &[usize],
        view: &PinholeView,
        targets: &ReflectedTargets,
    ) -> Result<u32> {
        let mut leaves = Vec::new();
        let mut instances = 0u32;
        for &k in selected {
            let (Some(map), Some(tree), Some(&offset)) =
                (maps.maps.get(k), maps.trees.get(k), buffers.offsets.get(k))
            else {
                return Err(MprError::InvalidSetting {
                    what: "radiance map selection",
                    message: format!("map {k} of {}", maps.maps.len()),
                });
            };
            for leaf in leaf_draws(map, tree, view) {
                let Some(size) = leaf.size else { continue };
                let drawn = leaf.drawn_size(size);
                leaves.push(GpuLeaf {
                    rect: [leaf.x, leaf.y, leaf.width, leaf.height],
                    step_cols_offset: [
                        leaf.step.x,
                        leaf.step.y,
                        leaf.width.div_ceil(leaf.step.x),
                        offset,
                    ],
                    size_width_first: [
                        drawn.x,
                        drawn.y,
                        f32::from_bits(map.width),
                        f32::from_bits(instances),
                    ],
                });
                instances += leaf.texels();
            }
        }
        let gpu_view = GpuView {
            pinhole: GpuPinhole::new(view),
            size_near_leaves: [
                view.width as f32,
                view.height as f32,
                REFLECTED_NEAR,
                leaves.len() as f32,
            ],
        };
        if leaves.is_empty() {
            leaves.push(GpuLeaf::zeroed());
        }
        let bind_group = ctx.checked("radiance-map frame buffers", || {
            let device = &ctx.device;
            let view_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("radiance-map-view"),
                contents: bytemuck::bytes_of(&gpu_view),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let leaf_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("radiance-map-leaves"),
                contents: bytemuck::cast_slice(&leaves),
                usage: wgpu::BufferUsages::STORAGE,
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("radiance-map"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: view_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: buffers.texels.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: leaf_buffer.as_entire_binding(),
                    },
                ],
            })
        })?;
        let color = targets.color.create_view(&Default::default());
        let depth = targets.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("radiance-map"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if instances > 0 {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..6, 0..instances);
        }
        Ok(instances)
    }
}
