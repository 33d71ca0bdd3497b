//! The emission pass: light-source surfaces seen directly show their emitted
//! radiance `Le` (one-sided, as Mitsuba's area emitter), added into the HDR
//! target after an equal-depth redraw of the scene. CPU twin:
//! [`emission_pass_cpu`].

use glam::Vec2;
use lustre_geometry::{Bvh, Camera, Scene};
use wgpu::util::DeviceExt;

use crate::passes::redraw::{ScenePipeline, additive_target, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::with_view;
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, Result};

/// The emission pass's own WGSL (`src/passes/emission.wgsl`); compiled after the view block.
pub const EMISSION_WGSL: &str = include_str!("emission.wgsl");

/// The GPU emission pass for one scene's materials.
#[derive(Debug)]
pub struct EmissionPass {
    pipeline: wgpu::RenderPipeline,
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
        ctx.checked("emission pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "emission", &with_view(EMISSION_WGSL));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("emission"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                }],
            });
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "emission",
                    module: &module,
                    layouts: &[&layout],
                    extra_vertex_buffers: &[],
                    target: additive_target(hdr_format),
                    depth_compare: wgpu::CompareFunction::Equal,
                    depth_write: false,
                },
            );
            let emission = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("emission-materials"),
                contents: bytemuck::cast_slice(&emission),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("emission"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: emission.as_entire_binding(),
                }],
            });
            Self {
                pipeline,
                bind_group,
                emissive,
            }
        })
    }

    /// Records the pass after the depth pre-pass: adds `Le` where an emitter is visible from its emitting side.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) {
        if !self.emissive || scene.vertex_count == 0 {
            return;
        }
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "emission");
        pass.set_pipeline(&self.pipeline);
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return;
        }
        pass.set_bind_group(1, &self.bind_group, &[]);
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
