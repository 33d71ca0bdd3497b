//! What every scene pass shares (Diefenbach & Badler 1997, sections 7.1 and
//! 7.2): the render pass that adds into the HDR target over the depth
//! pre-pass, additive blending, the stencil test against the view's
//! reference, the shader module specialised for the device's clipping, and
//! the pipeline whose group 0 is the view ([`crate::view`]).

use crate::GpuContext;
use crate::scene_buffers::GpuVertex;
use crate::target::RenderTargets;

/// Additive blending `dst + src` on colour (light accumulation, section 7.2); alpha keeps `OVER`.
pub const ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent::OVER,
};

/// A stencil state that passes where the stencil equals the reference and
/// applies `pass_op` where depth and stencil tests pass (both faces); a
/// `Keep` state has no write mask.
pub fn stencil_equal(pass_op: wgpu::StencilOperation) -> wgpu::StencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Equal,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op,
    };
    wgpu::StencilState {
        front: face,
        back: face,
        read_mask: 0xff,
        write_mask: if pass_op == wgpu::StencilOperation::Keep {
            0
        } else {
            0xff
        },
    }
}

/// The stencil test of a pass drawn under a view: pass where the stencil equals
/// the view's reference (its recursion level, section 7.3), never write it.
pub fn view_stencil() -> wgpu::StencilState {
    stencil_equal(wgpu::StencilOperation::Keep)
}

/// A scene pass's shader module: `source` (its complete WGSL, view block
/// included) specialised for the device's user clip distances.
pub fn scene_module(ctx: &GpuContext, label: &str, source: &str) -> wgpu::ShaderModule {
    ctx.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(ctx.scene_wgsl(source).into()),
        })
}

/// What differs between the pipelines that draw the scene under a view.
#[derive(Debug)]
pub struct ScenePipeline<'a> {
    /// Debug label.
    pub label: &'a str,
    /// The module ([`scene_module`]) with `vs_main` and `fs_main`.
    pub module: &'a wgpu::ShaderModule,
    /// The pass's own bind group layouts, groups 1 and up (group 0 is the view).
    pub layouts: &'a [&'a wgpu::BindGroupLayout],
    /// Vertex buffers after the scene's [`GpuVertex::LAYOUT`] at slot 0.
    pub extra_vertex_buffers: &'a [wgpu::VertexBufferLayout<'a>],
    /// The one colour target.
    pub target: wgpu::ColorTargetState,
    /// Depth test (`Equal` for redraws over the pre-pass).
    pub depth_compare: wgpu::CompareFunction,
    /// Whether the pass writes depth.
    pub depth_write: bool,
}

/// A triangle-list pipeline over the scene's vertices, cull none, under the
/// view's stencil test ([`view_stencil`]), group 0 the view.
pub fn scene_pipeline(ctx: &GpuContext, desc: &ScenePipeline<'_>) -> wgpu::RenderPipeline {
    let device = &ctx.device;
    let mut layouts = vec![Some(ctx.view_layout())];
    layouts.extend(desc.layouts.iter().map(|l| Some(*l)));
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(desc.label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    let mut buffers = vec![Some(GpuVertex::LAYOUT)];
    buffers.extend(desc.extra_vertex_buffers.iter().cloned().map(Some));
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(desc.label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: desc.module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: ctx.depth_format(),
            depth_write_enabled: Some(desc.depth_write),
            depth_compare: Some(desc.depth_compare),
            stencil: view_stencil(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: desc.module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(desc.target.clone())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// An additive colour target of `format` (section 7.2).
pub fn additive_target(format: wgpu::TextureFormat) -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format,
        blend: Some(ADDITIVE),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// Additive blending weighted by the blend constant, `dst + C · src` on
/// colour (a group of jittered lights standing for all of them,
/// [`crate::light_group`]); alpha keeps `OVER`. Every pass drawn with it sets
/// its constant ([`crate::light_group::LightGroup::blend_constant`]).
pub const WEIGHTED_ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Constant,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent::OVER,
};

/// The blend constant `(w, w, w, w)`: one weight for every channel.
pub fn uniform_constant(w: f64) -> wgpu::Color {
    wgpu::Color {
        r: w,
        g: w,
        b: w,
        a: w,
    }
}

/// [`additive_target`] weighted by the blend constant ([`WEIGHTED_ADDITIVE`]).
pub fn weighted_additive_target(format: wgpu::TextureFormat) -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format,
        blend: Some(WEIGHTED_ADDITIVE),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// Begins a pass that adds into `targets.hdr` with `targets.depth` attached
/// read-only (depth and stencil loaded, neither written).
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
