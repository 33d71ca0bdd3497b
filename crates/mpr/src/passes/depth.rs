//! The depth pre-pass (Diefenbach & Badler 1997, section 7.2: later passes
//! redraw with an equal-depth test, so visibility is fixed here): reverse-Z
//! depth and a surface id per pixel, with its CPU twin by ray casting.

use glam::{Vec2, Vec3};
use lustre_geometry::{Bvh, Camera};

use crate::passes::redraw::{ScenePipeline, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::{DEPTH_WGSL, with_view};
use crate::target::{
    NO_SURFACE, REVERSE_Z_CLEAR, REVERSE_Z_COMPARE, RenderTargets, SURFACE_ID_FORMAT,
};
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, Result};

/// The GPU depth pre-pass.
#[derive(Debug)]
pub struct DepthPass {
    pipeline: wgpu::RenderPipeline,
}

impl DepthPass {
    /// Builds the pipeline (cull none, depth test [`REVERSE_Z_COMPARE`] with
    /// writes, the view's stencil test, R32Uint surface ids).
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        ctx.checked("depth pass creation", || {
            let module = scene_module(ctx, "depth", &with_view(DEPTH_WGSL));
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "depth",
                    module: &module,
                    layouts: &[],
                    extra_vertex_buffers: &[],
                    target: wgpu::ColorTargetState {
                        format: SURFACE_ID_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    },
                    depth_compare: REVERSE_Z_COMPARE,
                    depth_write: true,
                },
            );
            Self { pipeline }
        })
    }

    /// Records the pass for the view in `slot`. With `clear` (the camera's own
    /// view) it first clears depth to [`REVERSE_Z_CLEAR`], ids to
    /// [`NO_SURFACE`] and the stencil to 0; a virtual view loads them and draws
    /// only where the stencil holds its reference, over depth the specular
    /// mask reset ([`crate::passes::specular`]).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
        clear: bool,
    ) {
        let (id_load, depth_load, stencil_load) = if clear {
            (
                wgpu::LoadOp::Clear(wgpu::Color {
                    r: f64::from(NO_SURFACE),
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                }),
                wgpu::LoadOp::Clear(REVERSE_Z_CLEAR),
                wgpu::LoadOp::Clear(0),
            )
        } else {
            (wgpu::LoadOp::Load, wgpu::LoadOp::Load, wgpu::LoadOp::Load)
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &targets.surface_id.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: id_load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: depth_load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: stencil_load,
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if scene.vertex_count > 0 {
            pass.set_pipeline(&self.pipeline);
            if !views.bind_in(&mut pass, 0, slot, targets) {
                return;
            }
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
