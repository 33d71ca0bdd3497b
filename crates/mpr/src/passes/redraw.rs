//! The render pass shared by the passes that redraw the scene over the depth
//! pre-pass (Diefenbach & Badler 1997, section 7.2): load and add into the
//! HDR target, test against the pre-pass's depth without writing it.

use crate::target::RenderTargets;

/// Begins a pass that adds into `targets.hdr` with `targets.depth` attached read-only.
pub fn begin_over_depth<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    targets: &RenderTargets,
    label: &str,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &targets.hdr.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth.view,
            depth_ops: None,
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
