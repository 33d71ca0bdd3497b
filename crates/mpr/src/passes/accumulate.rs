//! The accumulation buffer of Diefenbach & Badler 1997, section 7
//! (antialiasing by jittered accumulation): each of `N` sub-pixel jittered
//! frames is added into [`RenderTargets::accumulation`] with weight `1/N`,
//! the blend constant, which averages them into the box-filtered image. The
//! sub-pixel pattern is [`lustre_geometry::light::hammersley_centred`];
//! [`FrameGraph::render_accumulated`](crate::FrameGraph::render_accumulated) drives it.

use crate::target::RenderTargets;
use crate::{GpuContext, MprError, Result};

/// The accumulation WGSL (`src/passes/accumulate.wgsl`), self-contained.
pub const ACCUMULATE_WGSL: &str = include_str!("accumulate.wgsl");

/// The pass adding one frame's HDR radiance, times `1/N`, into the accumulation target.
#[derive(Debug)]
pub struct AccumulatePass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl AccumulatePass {
    /// Builds the pipeline for HDR and accumulation targets of `hdr_format` (blendable).
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.is_blendable(hdr_format) {
            return Err(MprError::UnsupportedFormat {
                what: "accumulation target (additive blending)",
                format: hdr_format,
            });
        }
        ctx.checked("accumulation pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("accumulate"),
                source: wgpu::ShaderSource::Wgsl(ACCUMULATE_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("accumulate"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                }],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("accumulate"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let weighted = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Constant,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("accumulate"),
                layout: Some(&pipeline_layout),
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
                    targets: &[Some(wgpu::ColorTargetState {
                        format: hdr_format,
                        blend: Some(wgpu::BlendState {
                            color: weighted,
                            alpha: weighted,
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            Self { pipeline, layout }
        })
    }

    /// Records `accumulation += weight · hdr`; `first` clears the accumulation target before.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        weight: f32,
        first: bool,
    ) {
        self.encode_in(device, encoder, targets, weight, first, None);
    }

    /// [`AccumulatePass::encode`] over the pixels `[x, y, w, h]` of
    /// `scissor` only (the whole target with `None`): a frame whose HDR
    /// target is zero elsewhere adds nothing there.
    pub fn encode_in(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        weight: f32,
        first: bool,
        scissor: Option<[u32; 4]>,
    ) {
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("accumulate"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&targets.hdr.view),
            }],
        });
        let load = if first {
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
        } else {
            wgpu::LoadOp::Load
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("accumulate"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.accumulation.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_blend_constant(crate::passes::redraw::uniform_constant(f64::from(weight)));
        if let Some([x, y, w, h]) = scissor {
            pass.set_scissor_rect(x, y, w, h);
        }
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
