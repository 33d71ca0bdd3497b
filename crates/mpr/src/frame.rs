//! The frame graph (DESIGN.md "Data flow", step 3; Diefenbach & Badler 1997,
//! section 7): one command encoder per frame runs the passes in order (clear
//! HDR, depth pre-pass, emitters, Gouraud vertex radiance, direct light,
//! diffuse textures, photon splats, tone map) into
//! any `TextureView`. Shadow maps are rendered per light pose, not per frame
//! ([`FrameGraph::update_shadows`]).

use lustre_geometry::Camera;

use crate::passes::depth::DepthPass;
use crate::passes::diffuse_texture::{DiffuseTexturePass, DiffuseTextures};
use crate::passes::direct::{DirectLights, DirectPass};
use crate::passes::emission::EmissionPass;
use crate::passes::gouraud::GouraudPass;
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
    /// Point lights whose direct light to add with shadow maps (section 2.2.1), if any.
    pub direct: Option<&'a DirectLights>,
    /// Diffuse surfaces' precomputed photon radiance (section 2.2.1), if any.
    pub diffuse: Option<&'a DiffuseTextures>,
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
    /// The emitters' own radiance, when the graph was built for a scene ([`FrameGraph::with_emission`]).
    pub emission: Option<EmissionPass>,
    /// Per-vertex radiance with Gouraud interpolation (García et al. 2003, section 2.4; [`FrameGraph::with_gouraud`]).
    pub gouraud: Option<GouraudPass>,
    /// The direct light pass ([`FrameGraph::with_direct`]).
    pub direct: Option<DirectPass>,
    /// The precomputed diffuse textures' pass ([`FrameGraph::with_diffuse_textures`]).
    pub diffuse: Option<DiffuseTexturePass>,
    /// The splat pass ([`FrameGraph::with_splats`]).
    pub splat: Option<SplatPass>,
    /// The final tone map.
    pub tonemap: TonemapPass,
}

impl FrameGraph {
    /// Builds every pass; `output_format` is the format of the views [`FrameGraph::render`] will be given.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self> {
        Ok(Self {
            depth: DepthPass::new(ctx)?,
            emission: None,
            gouraud: None,
            direct: None,
            diffuse: None,
            splat: None,
            tonemap: TonemapPass::new(ctx, output_format)?,
        })
    }

    /// Adds the emission pass for `scene`'s emitters and HDR targets of `hdr_format`.
    pub fn with_emission(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &lustre_geometry::Scene,
    ) -> Result<Self> {
        self.emission = Some(EmissionPass::new(ctx, hdr_format, scene)?);
        Ok(self)
    }

    /// Adds the Gouraud pass for `scene`'s triangle corners and HDR targets of `hdr_format`; its radiance is zero until [`FrameGraph::set_gouraud_radiance`].
    pub fn with_gouraud(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &SceneBuffers,
    ) -> Result<Self> {
        self.gouraud = Some(GouraudPass::new(ctx, hdr_format, scene)?);
        Ok(self)
    }

    /// Replaces the Gouraud pass's per-corner radiance (section 2.4.2: once per frame of the quasi-static method).
    pub fn set_gouraud_radiance(&self, ctx: &GpuContext, radiance: &[[f32; 3]]) -> Result<()> {
        let Some(gouraud) = &self.gouraud else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "vertex radiance needs the Gouraud pass (FrameGraph::with_gouraud)".into(),
            });
        };
        gouraud.set_radiance(&ctx.queue, radiance)
    }

    /// Adds the direct light pass for HDR targets of `hdr_format`.
    pub fn with_direct(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        self.direct = Some(DirectPass::new(ctx, hdr_format)?);
        Ok(self)
    }

    /// Adds the pass drawing precomputed diffuse textures into HDR targets of `hdr_format`.
    pub fn with_diffuse_textures(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        self.diffuse = Some(DiffuseTexturePass::new(ctx, hdr_format)?);
        Ok(self)
    }

    /// Renders the shadow cube maps of `lights` for the scene's current pose (once per light or object move, not per frame).
    pub fn update_shadows(
        &self,
        ctx: &GpuContext,
        scene: &SceneBuffers,
        lights: &DirectLights,
    ) -> Result<()> {
        let Some(direct) = &self.direct else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "shadow maps need the direct pass (FrameGraph::with_direct)".into(),
            });
        };
        ctx.checked("shadow maps", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("shadows"),
                });
            direct.encode_shadows(&mut encoder, scene, lights);
            ctx.queue.submit([encoder.finish()]);
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
    /// black (passes add light into it), depth pre-pass, emitters, Gouraud
    /// vertex radiance, direct light, splats, tone map to `output`.
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
        let direct = match (frame.direct, &self.direct) {
            (Some(lights), Some(pass)) => {
                pass.prepare(&ctx.queue, frame.camera);
                Some((lights, pass))
            }
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "point lights were given but the frame graph has no direct pass \
                              (FrameGraph::with_direct)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        let diffuse = match (frame.diffuse, &self.diffuse) {
            (Some(textures), Some(pass)) => {
                pass.prepare(&ctx.queue, frame.camera);
                Some((textures, pass))
            }
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "diffuse textures were given but the frame graph has no pass for \
                              them (FrameGraph::with_diffuse_textures)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        if let Some(emission) = &self.emission {
            emission.prepare(&ctx.queue, frame.camera);
        }
        if let Some(gouraud) = &self.gouraud {
            gouraud.prepare(&ctx.queue, frame.camera);
        }
        ctx.checked_result("frame", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
            clear_hdr(&mut encoder, frame.targets);
            self.depth.encode(&mut encoder, frame.scene, frame.targets);
            if let Some(emission) = &self.emission {
                emission.encode(&mut encoder, frame.scene, frame.targets);
            }
            if let Some(gouraud) = &self.gouraud {
                gouraud.encode(&mut encoder, frame.scene, frame.targets)?;
            }
            if let Some((lights, pass)) = direct {
                pass.encode(&mut encoder, frame.scene, frame.targets, lights);
            }
            if let Some((textures, pass)) = diffuse {
                pass.encode(&mut encoder, frame.scene, frame.targets, textures);
            }
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
