//! The emission pass: light-source surfaces seen directly show their emitted
//! radiance `Le` (one-sided, as Mitsuba's area emitter), added into the HDR
//! target after an equal-depth redraw of the scene. CPU twin:
//! [`emission_pass_cpu`].

use bytemuck::{Pod, Zeroable};
use glam::Vec2;
use lustre_geometry::{Bvh, Camera, Scene};
use wgpu::util::DeviceExt;

use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::target::RenderTargets;
use crate::{GpuContext, Result};

/// The emission WGSL (`src/passes/emission.wgsl`), self-contained.
pub const EMISSION_WGSL: &str = include_str!("emission.wgsl");

/// The pass's uniform block (`EmissionCamera` in `emission.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct EmissionCamera {
    /// Column-major world-to-clip matrix.
    pub view_projection: [[f32; 4]; 4],
    /// Camera position (w unused).
    pub position: [f32; 4],
}

/// The GPU emission pass for one scene's materials.
#[derive(Debug)]
pub struct EmissionPass {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// Whether any material emits (otherwise [`EmissionPass::encode`] records nothing).
    emissive: bool,
}

impl EmissionPass {
    /// Builds the pipeline for HDR targets of `hdr_format` with the emission of `scene`'s materials.
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat, scene: &Scene) -> Result<Self> {
        let mut emission: Vec<[f32; 4]> = scene
            .materials()
            .iter()
            .map(|m| m.emission.extend(0.0).to_array())
            .collect();
        let emissive = scene.materials().iter().any(|m| m.is_emissive());
        if emission.is_empty() {
            emission.push([0.0; 4]);
        }
        let depth_format = ctx.depth_format();
        ctx.checked("emission pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("emission"),
                source: wgpu::ShaderSource::Wgsl(EMISSION_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("emission"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: wgpu::BufferSize::new(
                                size_of::<EmissionCamera>() as u64
                            ),
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Storage { read_only: true },
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("emission"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("emission"),
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
                    format: depth_format,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Equal),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: hdr_format,
                        blend: Some(wgpu::BlendState {
                            color: wgpu::BlendComponent {
                                src_factor: wgpu::BlendFactor::One,
                                dst_factor: wgpu::BlendFactor::One,
                                operation: wgpu::BlendOperation::Add,
                            },
                            alpha: wgpu::BlendComponent::OVER,
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("emission-camera"),
                size: size_of::<EmissionCamera>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let emission = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("emission-materials"),
                contents: bytemuck::cast_slice(&emission),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("emission"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniforms.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: emission.as_entire_binding(),
                    },
                ],
            });
            Self {
                pipeline,
                uniforms,
                bind_group,
                emissive,
            }
        })
    }

    /// Writes the camera for the next [`EmissionPass::encode`].
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera) {
        let uniforms = EmissionCamera {
            view_projection: camera.view_projection().to_cols_array_2d(),
            position: camera.position.extend(1.0).to_array(),
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Records the pass after the depth pre-pass: adds `Le` where an emitter is visible from its emitting side.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
    ) {
        if !self.emissive || scene.vertex_count == 0 {
            return;
        }
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "emission");
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.draw(0..scene.vertex_count, 0..1);
    }
}

/// CPU counterpart of [`EmissionPass`]: per pixel centre, the emission of the
/// hit triangle's material when the camera is on the side its shading normal
/// points to; zero elsewhere. Row 0 is the top.
pub fn emission_pass_cpu(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<[f32; 3]> {
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    bvh.closest_hits(&rays)
        .iter()
        .map(|hit| {
            hit.map_or([0.0; 3], |h| {
                let material = &scene.materials()[h.material as usize];
                if (camera.position - h.position).dot(h.shading_normal) > 0.0 {
                    material.emission.to_array()
                } else {
                    [0.0; 3]
                }
            })
        })
        .collect()
}
