//! The blending pass of Bastos et al. 1999 (section 8.2, the colour plates'
//! `k_s (M * K) R + k_d D`): the reflector's view-dependent term, computed
//! over its reflected image by [`crate::passes::glossy_reflection`], times
//! `k_s` and added into the HDR target at the pixels where the reflector is
//! the visible surface. The surface-id target plays the paper's stencil
//! mask; `k_d D` is already in the frame (direct light and diffuse textures).
//! A term on a grid `scale` times coarser than the frame (the reflected
//! image's resolution chosen from the glossiness, [`lustre_ibr::resolution`])
//! is read bilinearly over its valid pixels ([`lustre_ibr::resolution::upsample`]).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::passes::redraw::additive_target;
use crate::target::RenderTargets;
use crate::{GpuContext, MprError, Result};

/// The pass's WGSL (`src/passes/reflector_blend.wgsl`), self-contained.
pub const REFLECTOR_BLEND_WGSL: &str = include_str!("reflector_blend.wgsl");

/// `Params` in the WGSL.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GpuParams {
    ks: [f32; 4],
    surface: [u32; 4],
}

/// The additive blend of `k_s (M * K) R` inside a reflector's pixels.
#[derive(Debug)]
pub struct ReflectorBlendPass {
    pipeline: wgpu::RenderPipeline,
}

impl ReflectorBlendPass {
    /// Builds the pipeline for an HDR target of `hdr_format` (blendable).
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.is_blendable(hdr_format) {
            return Err(MprError::UnsupportedFormat {
                what: "reflector blend (additive blending)",
                format: hdr_format,
            });
        }
        ctx.checked("reflector-blend pass creation", || {
            let module = ctx
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("reflector-blend"),
                    source: wgpu::ShaderSource::Wgsl(REFLECTOR_BLEND_WGSL.into()),
                });
            let pipeline = ctx
                .device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("reflector-blend"),
                    layout: None,
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_main"),
                        compilation_options: Default::default(),
                        targets: &[Some(additive_target(hdr_format))],
                    }),
                    multiview_mask: None,
                    cache: None,
                });
            Self { pipeline }
        })
    }

    /// Records `hdr += ks · term` at the pixels of `targets` whose surface id is `surface`; `term` is the glossy term's texture on a grid `scale` times coarser than the targets (1: their size), alpha 1 where it holds a value.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        term: &wgpu::Texture,
        surface: u32,
        ks: Vec3,
        scale: u32,
    ) -> Result<()> {
        let size = term.size();
        let scale = scale.max(1);
        if (size.width, size.height)
            != (
                targets.width.div_ceil(scale),
                targets.height.div_ceil(scale),
            )
        {
            return Err(MprError::InvalidSetting {
                what: "reflector blend",
                message: format!(
                    "the glossy term is {}x{}, the frame {}x{} at {scale} pixels per term pixel",
                    size.width, size.height, targets.width, targets.height
                ),
            });
        }
        let params = GpuParams {
            ks: ks.extend(0.0).to_array(),
            surface: [surface, scale, 0, 0],
        };
        let bind_group = ctx.checked("reflector-blend bindings", || {
            let device = &ctx.device;
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reflector-blend-params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let term = term.create_view(&Default::default());
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("reflector-blend"),
                layout: &self.pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&term),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&targets.surface_id.view),
                    },
                ],
            })
        })?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("reflector-blend"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.hdr.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}
