//! Shadow volumes on the GPU (Diefenbach & Badler 1997, section 4.1), counted
//! with the depth-fail rule against the depth pre-pass, in the stencil split
//! of section 7.3: the view's valid area (stencil == the view's reference,
//! below [`SHAD_MIN`]) is set to [`SHAD_ZERO`], every volume of a light adds
//! its count there, and the lit area is then `stencil == SHAD_ZERO`; the
//! area is given back to the view's reference after the light's passes.
//!
//! Order per light: [`ShadowVolumePass::prepare`] (camera, light position,
//! jittered for the pivot approximation of section 4.4), then
//! [`ShadowVolumePass::encode_begin`], [`ShadowVolumePass::encode_volumes`],
//! the lit redraw with stencil reference [`SHAD_ZERO`] (compare `Equal`),
//! and [`ShadowVolumePass::encode_end`]. The uniform block is written by
//! `prepare` with `queue.write_buffer`, so one light per submission.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use lustre_geometry::Camera;
use lustre_geometry::shadow_volume::{ShadowVolume, VolumeVertex};
use wgpu::util::DeviceExt;

use crate::target::RenderTargets;
use crate::{GpuContext, MprError, Result};

/// The shadow-volume WGSL (`src/passes/shadow_volume.wgsl`), self-contained.
pub const SHADOW_VOLUME_WGSL: &str = include_str!("shadow_volume.wgsl");

/// The stencil "zero" of the plus-minus count: three quarters of the 8-bit
/// range (section 7.3); a pixel is lit where its stencil equals it.
pub const SHAD_ZERO: u32 = 192;
/// The smallest stencil value of the shadow half (section 7.3): the shadow
/// passes touch only pixels at or above it; the view references (specular
/// recursion levels) live below it.
pub const SHAD_MIN: u32 = 128;

/// The uniform block (`VolumeUniforms` in `shadow_volume.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct VolumeUniforms {
    /// Column-major world-to-clip matrix (reverse Z, infinite far plane).
    pub view_projection: [[f32; 4]; 4],
    /// The light position of the pass (xyz; w unused), jittered for section 4.4.
    pub light: [f32; 4],
}

/// The volumes of one light uploaded as one non-indexed triangle list of
/// [`VolumeVertex::gpu`] vertices (section 4.3: stored, re-uploaded only
/// when [`lustre_geometry::shadow_volume::ShadowVolumeSet::refresh`] rebuilt some).
#[derive(Debug)]
pub struct ShadowVolumeBuffers {
    /// Vertex buffer (`Float32x4`).
    pub vertices: wgpu::Buffer,
    /// Number of vertices.
    pub vertex_count: u32,
}

impl ShadowVolumeBuffers {
    /// Uploads the volumes (section 4.1). Fails on more than 2³² vertices.
    pub fn upload<'a>(
        ctx: &GpuContext,
        volumes: impl IntoIterator<Item = &'a ShadowVolume>,
    ) -> Result<Self> {
        let data: Vec<[f32; 4]> = volumes
            .into_iter()
            .flat_map(ShadowVolume::gpu_vertices)
            .collect();
        let vertex_count = u32::try_from(data.len()).map_err(|_| MprError::InvalidSetting {
            what: "shadow volumes",
            message: format!("{} vertices do not fit a u32", data.len()),
        })?;
        // A buffer of zero bytes cannot be bound; one unused vertex stands in.
        let bytes: &[u8] = if data.is_empty() {
            &[0; VolumeVertex::GPU_SIZE]
        } else {
            bytemuck::cast_slice(&data)
        };
        let vertices = ctx.checked("shadow volume upload", || {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("shadow-volumes"),
                    contents: bytes,
                    usage: wgpu::BufferUsages::VERTEX,
                })
        })?;
        Ok(Self {
            vertices,
            vertex_count,
        })
    }
}

/// The pipelines of the shadow-volume passes (sections 4.1 and 7.3).
#[derive(Debug)]
pub struct ShadowVolumePass {
    /// Inverts the view's area (stencil == r < 128 becomes 255 − r ≥ 128).
    mark: wgpu::RenderPipeline,
    /// Replaces stencil >= SHAD_MIN by the reference (SHAD_ZERO at the begin, r at the end).
    replace_high: wgpu::RenderPipeline,
    /// The volumes, counter-clockwise front faces (a plain view).
    volumes_ccw: wgpu::RenderPipeline,
    /// The volumes, clockwise front faces (a mirrored view).
    volumes_cw: wgpu::RenderPipeline,
    /// Writes 1 where stencil == SHAD_ZERO (tests and debugging).
    mask: wgpu::RenderPipeline,
    mask_format: wgpu::TextureFormat,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

fn face(
    compare: wgpu::CompareFunction,
    depth_fail_op: wgpu::StencilOperation,
    pass_op: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op,
        pass_op,
    }
}

fn stencil(front: wgpu::StencilFaceState, back: wgpu::StencilFaceState) -> wgpu::StencilState {
    wgpu::StencilState {
        front,
        back,
        read_mask: 0xff,
        write_mask: 0xff,
    }
}

impl ShadowVolumePass {
    /// Builds the pipelines; `mask_format` is the colour format of
    /// [`ShadowVolumePass::encode_lit_mask`]. Fails when the depth target has
    /// no stencil ([`GpuContext::has_stencil`]).
    pub fn new(ctx: &GpuContext, mask_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.has_stencil() {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: "the device has no Depth32FloatStencil8 target".into(),
            });
        }
        ctx.checked("shadow volume pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shadow-volume"),
                source: wgpu::ShaderSource::Wgsl(SHADOW_VOLUME_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadow-volume"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<VolumeUniforms>() as u64),
                    },
                    count: None,
                }],
            });
            let volume_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadow-volume"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let empty_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadow-volume-fullscreen"),
                bind_group_layouts: &[],
                immediate_size: 0,
            });
            let vertex_layout = wgpu::VertexBufferLayout {
                array_stride: VolumeVertex::GPU_SIZE as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x4],
            };
            let pipeline = |label: &str,
                            volume: bool,
                            front_face: wgpu::FrontFace,
                            depth_compare: wgpu::CompareFunction,
                            stencil: wgpu::StencilState,
                            mask: bool| {
                let buffers = [Some(vertex_layout.clone())];
                let targets = [Some(wgpu::ColorTargetState {
                    format: mask_format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(if volume {
                        &volume_layout
                    } else {
                        &empty_layout
                    }),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(if volume { "vs_volume" } else { "vs_fullscreen" }),
                        compilation_options: Default::default(),
                        buffers: if volume { &buffers } else { &[] },
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        front_face,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: ctx.depth_format(),
                        depth_write_enabled: Some(false),
                        depth_compare: Some(depth_compare),
                        stencil,
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: mask.then(|| wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_mask"),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            use wgpu::CompareFunction as C;
            use wgpu::StencilOperation as S;
            let both = |f| stencil(f, f);
            let mark = pipeline(
                "shadow-volume-mark",
                false,
                wgpu::FrontFace::Ccw,
                C::Always,
                both(face(C::Equal, S::Keep, S::Invert)),
                false,
            );
            // `reference <= stored`: only the shadow half.
            let replace_high = pipeline(
                "shadow-volume-replace",
                false,
                wgpu::FrontFace::Ccw,
                C::Always,
                both(face(C::LessEqual, S::Keep, S::Replace)),
                false,
            );
            // Z-fail: a face behind the visible surface (depth test Greater
            // fails; equal depth, the caster's own lit face, fails too)
            // counts, back faces +1, front faces −1.
            let zfail = stencil(
                face(C::LessEqual, S::DecrementWrap, S::Keep),
                face(C::LessEqual, S::IncrementWrap, S::Keep),
            );
            let volumes_ccw = pipeline(
                "shadow-volume-ccw",
                true,
                wgpu::FrontFace::Ccw,
                C::Greater,
                zfail.clone(),
                false,
            );
            let volumes_cw = pipeline(
                "shadow-volume-cw",
                true,
                wgpu::FrontFace::Cw,
                C::Greater,
                zfail,
                false,
            );
            let mask = pipeline(
                "shadow-volume-mask",
                false,
                wgpu::FrontFace::Ccw,
                C::Always,
                both(face(C::Equal, S::Keep, S::Keep)),
                true,
            );
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow-volume-uniforms"),
                size: size_of::<VolumeUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow-volume"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniforms.as_entire_binding(),
                }],
            });
            Self {
                mark,
                replace_high,
                volumes_ccw,
                volumes_cw,
                mask,
                mask_format,
                uniforms,
                bind_group,
            }
        })
    }

    /// Writes the camera's view-projection and the light position the far
    /// vertices are extruded from (the central light, or a jittered one: the
    /// pivot approximation of section 4.4).
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera, light: Vec3) {
        let uniforms = VolumeUniforms {
            view_projection: camera.view_projection().to_cols_array_2d(),
            light: light.extend(1.0).to_array(),
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    fn stencil_pass<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        label: &str,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    fn check_reference(view_reference: u32) -> Result<()> {
        if view_reference >= SHAD_MIN {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!(
                    "view stencil reference {view_reference} is not below SHAD_MIN = {SHAD_MIN}"
                ),
            });
        }
        Ok(())
    }

    /// Sets the view's area (stencil == `view_reference`, which must be below
    /// [`SHAD_MIN`]) to [`SHAD_ZERO`] (section 7.3): the area is inverted to
    /// `255 − r ≥ 128`, then every stencil `>= SHAD_MIN` is replaced; this
    /// assumes nothing outside the area is at or above [`SHAD_MIN`], which
    /// [`ShadowVolumePass::encode_end`] restores.
    pub fn encode_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        view_reference: u32,
    ) -> Result<()> {
        Self::check_reference(view_reference)?;
        let mut pass = Self::stencil_pass(encoder, targets, "shadow-volume-begin");
        pass.set_pipeline(&self.mark);
        pass.set_stencil_reference(view_reference);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&self.replace_high);
        pass.set_stencil_reference(SHAD_ZERO);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Counts the volumes into the stencil with the depth-fail rule (section
    /// 4.1): depth test `Greater` (reverse Z) without writes, back faces
    /// increment and front faces decrement (wrapping) where the depth test
    /// fails, only where stencil `>= SHAD_MIN`. `mirrored` swaps which
    /// winding is front (a view with a negative-determinant view matrix).
    pub fn encode_volumes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        volumes: &ShadowVolumeBuffers,
        mirrored: bool,
    ) {
        if volumes.vertex_count == 0 {
            return;
        }
        let mut pass = Self::stencil_pass(encoder, targets, "shadow-volume-count");
        pass.set_pipeline(if mirrored {
            &self.volumes_cw
        } else {
            &self.volumes_ccw
        });
        pass.set_stencil_reference(SHAD_MIN);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, volumes.vertices.slice(..));
        pass.draw(0..volumes.vertex_count, 0..1);
    }

    /// Gives the shadow half back to the view: every stencil `>= SHAD_MIN`
    /// becomes `view_reference` again (section 7.3).
    pub fn encode_end(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        view_reference: u32,
    ) -> Result<()> {
        Self::check_reference(view_reference)?;
        let mut pass = Self::stencil_pass(encoder, targets, "shadow-volume-end");
        pass.set_pipeline(&self.replace_high);
        pass.set_stencil_reference(view_reference);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Writes 1 into `mask` (of the format given to [`ShadowVolumePass::new`],
    /// cleared to 0 first) where the stencil equals [`SHAD_ZERO`]: the lit
    /// area between [`ShadowVolumePass::encode_volumes`] and
    /// [`ShadowVolumePass::encode_end`] (section 4.1).
    pub fn encode_lit_mask(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        mask: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow-volume-mask"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: mask,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.mask);
        pass.set_stencil_reference(SHAD_ZERO);
        pass.draw(0..3, 0..1);
    }

    /// The colour format of [`ShadowVolumePass::encode_lit_mask`].
    pub fn mask_format(&self) -> wgpu::TextureFormat {
        self.mask_format
    }
}
