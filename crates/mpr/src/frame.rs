//! The frame graph (DESIGN.md "Data flow", step 3; Diefenbach & Badler 1997,
//! section 7): one command encoder per frame runs the passes in order (clear
//! HDR, depth pre-pass, photon splats, tone map) into any `TextureView`.

use lustre_geometry::Camera;

use crate::passes::depth::DepthPass;
use crate::passes::splat::{KernelFiltering, Restriction, SplatBuffers, SplatPass};
use crate::passes::tonemap::{Tonemap, TonemapPass};
use crate::scene_buffers::SceneBuffers;
use crate::target::RenderTargets;
use crate::{GpuContext, Result};

/// What one frame reads and writes.
#[derive(Debug, Clone, Copy)]
pub struct FrameInputs<'a> {
    /// The scene's triangles on the GPU.
    pub scene: &'a SceneBuffers,
    /// The viewpoint (its aspect should match the targets').
    pub camera: &'a Camera,
    /// Exposure and tone operator.
    pub tonemap: &'a Tonemap,
    /// HDR, depth and surface-id targets.
    pub targets: &'a RenderTargets,
    /// Where the tone-mapped image goes: a window surface, a capture texture, a test texture.
    pub output: &'a wgpu::TextureView,
    /// Photon splats to add (Stürzlinger & Bastos 1997, section 2.2), if any.
    pub splats: Option<SplatInputs<'a>>,
}

/// What the splat pass of a frame reads.
#[derive(Debug, Clone, Copy)]
pub struct SplatInputs<'a> {
    /// The splats and their materials.
    pub buffers: &'a SplatBuffers,
    /// How splats are limited to their visible surface.
    pub restriction: Restriction,
    /// How the kernel texture is filtered.
    pub filtering: KernelFiltering,
}

/// The passes of a frame, in the order they run.
#[derive(Debug)]
pub struct FrameGraph {
    /// The depth pre-pass.
    pub depth: DepthPass,
    /// The splat pass, built on first use (it needs the kernel).
    pub splat: Option<SplatPass>,
    /// The final tone map.
    pub tonemap: TonemapPass,
}

impl FrameGraph {
    /// Builds every pass; `output_format` is the format of the views [`FrameGraph::render`] will be given.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self> {
        Ok(Self {
            depth: DepthPass::new(ctx)?,
            splat: None,
            tonemap: TonemapPass::new(ctx, output_format)?,
        })
    }

    /// Adds the splat pass for HDR targets of `hdr_format` with the kernel `kernel`.
    pub fn with_splats(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        kernel: lustre_photon::Kernel,
    ) -> Result<Self> {
        self.splat = Some(SplatPass::new(ctx, hdr_format, kernel)?);
        Ok(self)
    }

    /// Records and submits one frame in one command encoder: clear HDR to
    /// black (passes add light into it), depth pre-pass, splats, tone map to `output`.
    pub fn render(&self, ctx: &GpuContext, frame: &FrameInputs<'_>) -> Result<()> {
        self.depth.prepare(&ctx.queue, frame.camera);
        self.tonemap.prepare(&ctx.queue, frame.tonemap)?;
        let splat = match (&frame.splats, &self.splat) {
            (Some(inputs), Some(pass)) => {
                pass.prepare(&ctx.queue, frame.camera, inputs.filtering);
                Some((inputs, pass))
            }
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "splats were given but the frame graph has no splat pass \
                              (FrameGraph::with_splats)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        ctx.checked_result("frame", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
            clear_hdr(&mut encoder, frame.targets);
            self.depth.encode(&mut encoder, frame.scene, frame.targets);
            if let Some((inputs, pass)) = splat {
                pass.encode(
                    &ctx.device,
                    &mut encoder,
                    frame.scene,
                    inputs.buffers,
                    frame.targets,
                    inputs.restriction,
                )?;
            }
            self.tonemap.encode(
                &ctx.device,
                &mut encoder,
                &frame.targets.hdr.view,
                frame.output,
            );
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })
    }
}

/// Clears the HDR target to zero radiance, the start of light accumulation (section 7.2).
pub fn clear_hdr(encoder: &mut wgpu::CommandEncoder, targets: &RenderTargets) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear-hdr"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &targets.hdr.view,
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
}
