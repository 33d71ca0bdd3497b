//! The depth pre-pass (Diefenbach & Badler 1997, section 7.2: later passes
//! redraw with an equal-depth test, so visibility is fixed here): reverse-Z
//! depth and a surface id per pixel, with its CPU twin by ray casting.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use lustre_geometry::{Bvh, Camera};

use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::shaders::DEPTH_WGSL;
use crate::target::{
    NO_SURFACE, REVERSE_Z_CLEAR, REVERSE_Z_COMPARE, RenderTargets, SURFACE_ID_FORMAT,
};
use crate::{GpuContext, Result};

/// The depth pass's uniform block (`DepthUniforms` in `depth.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct DepthUniforms {
    /// Column-major world-to-clip matrix ([`Camera::view_projection`]).
    pub view_projection: [[f32; 4]; 4],
}

/// The GPU depth pre-pass: pipeline and uniform buffer.
#[derive(Debug)]
pub struct DepthPass {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl DepthPass {
    /// Builds the pipeline (cull none, depth test [`REVERSE_Z_COMPARE`], R32Uint surface ids).
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        ctx.checked("depth pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("depth"),
                source: wgpu::ShaderSource::Wgsl(DEPTH_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("depth"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<DepthUniforms>() as u64),
                    },
                    count: None,
                }],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("depth"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("depth"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
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
                    format: ctx.depth_format(),
                    depth_write_enabled: Some(true),
                    depth_compare: Some(REVERSE_Z_COMPARE),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: SURFACE_ID_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("depth-uniforms"),
                size: size_of::<DepthUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("depth"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniforms.as_entire_binding(),
                }],
            });
            Self {
                pipeline,
                uniforms,
                bind_group,
            }
        })
    }

    /// Writes the camera's view-projection for the next [`DepthPass::encode`].
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera) {
        let uniforms = DepthUniforms {
            view_projection: camera.view_projection().to_cols_array_2d(),
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Records the pass: clears depth to [`REVERSE_Z_CLEAR`] and ids to
    /// [`NO_SURFACE`], then draws every scene triangle.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.surface_id.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: f64::from(NO_SURFACE),
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(REVERSE_Z_CLEAR),
                    store: wgpu::StoreOp::Store,
                }),
                // The stencilled passes start from a zero stencil.
                stencil_ops: targets.depth_format().has_stencil_aspect().then_some(
                    wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0),
                        store: wgpu::StoreOp::Store,
                    },
                ),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if scene.vertex_count > 0 {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.draw(0..scene.vertex_count, 0..1);
        }
    }
}

/// Reverse-Z depth of a world point seen by `camera`: z/w of `view_projection * (p, 1)`.
pub fn reverse_z_depth(camera: &Camera, p: Vec3) -> f32 {
    let clip = camera.view_projection() * p.extend(1.0);
    clip.z / clip.w
}

/// The CPU twin's output: per pixel (row 0 at the top) depth and surface id.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Reverse-Z depth ([`REVERSE_Z_CLEAR`] where the ray misses).
    pub depth: Vec<f32>,
    /// Surface id ([`NO_SURFACE`] where the ray misses).
    pub surface: Vec<u32>,
}

/// CPU counterpart of [`DepthPass`]: the closest hit of the primary ray
/// through each pixel centre ([`Camera::pixel_ndc`], [`Camera::primary_ray`]).
pub fn depth_pass_cpu(bvh: &Bvh, camera: &Camera, width: u32, height: u32) -> DepthImage {
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    let hits = bvh.closest_hits(&rays);
    let depth = hits
        .iter()
        .map(|h| h.map_or(REVERSE_Z_CLEAR, |h| reverse_z_depth(camera, h.position)))
        .collect();
    let surface = hits
        .iter()
        .map(|h| h.map_or(NO_SURFACE, |h| h.surface))
        .collect();
    DepthImage {
        width,
        height,
        depth,
        surface,
    }
}
