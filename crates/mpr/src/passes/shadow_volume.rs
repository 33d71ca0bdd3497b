//! Shadow volumes on the GPU (Diefenbach & Badler 1997, section 4.1), counted
//! with the depth-fail rule against the depth pre-pass, in the stencil split
//! of section 7.3: the view's valid area (stencil == the view's reference,
//! below [`SHAD_MIN`]) is set to [`SHAD_ZERO`], every volume of a light adds
//! its count there, and the lit area is then `stencil == SHAD_ZERO`; the
//! area is given back to the view's reference after the light's passes.
//!
//! The volumes are drawn under a [`crate::View`] (group 0, clipped like every
//! scene pass in a virtual view); the light positions they are extruded from
//! (possibly jittered, the pivot approximation of section 4.4) sit in one
//! [`VolumeLights`] buffer at dynamic offsets (group 1), so all the lights
//! of a frame fit one submission. Order per view and light, inside one
//! render pass ([`ShadowVolumePass::begin_pass`]):
//! [`ShadowVolumePass::record_begin`], [`ShadowVolumePass::record_volumes`],
//! the lit redraw with stencil reference [`SHAD_ZERO`] (compare `Equal`,
//! e.g. `DirectPass::record_light_under_stencil`), and
//! [`ShadowVolumePass::record_end`]. [`crate::passes::shadowed_direct`]
//! runs this per light in a frame.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use lustre_geometry::shadow_volume::{ShadowVolume, VolumeVertex};
use wgpu::util::DeviceExt;

use crate::passes::redraw::scene_module;
use crate::shaders::with_view;
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The shadow-volume pass's own WGSL (`src/passes/shadow_volume.wgsl`),
/// compiled after the view block ([`with_view`]).
pub const SHADOW_VOLUME_WGSL: &str = include_str!("shadow_volume.wgsl");

/// Depth bias of the volumes: four units of the depth format's resolution
/// farther (negative with reverse Z), no slope term. The front cap lies on the occluder's own lit
/// triangles, which the depth pass drew with another vertex shader; where
/// the two round differently by an ulp, the cap's depth fail (counted, as
/// the CPU twin counts it) flickered into a pass, drawing specks of shadow on
/// lit occluders (seen on an NVIDIA H100, not on lavapipe). Pushed back, the
/// cap always fails there; the shift of shadow boundaries on receivers is
/// far below a pixel.
pub const VOLUME_DEPTH_BIAS: wgpu::DepthBiasState = wgpu::DepthBiasState {
    constant: -4,
    slope_scale: 0.0,
    clamp: 0.0,
};

/// The stencil "zero" of the plus-minus count: three quarters of the 8-bit
/// range (section 7.3); a pixel is lit where its stencil equals it.
pub const SHAD_ZERO: u32 = 192;
/// The smallest stencil value of the shadow half (section 7.3): the shadow
/// passes touch only pixels at or above it; the view references (specular
/// recursion levels) live below it.
pub const SHAD_MIN: u32 = 128;

/// One light's block of group 1 (`VolumeLight` in `shadow_volume.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct VolumeLight {
    /// The light position the far vertices are extruded from (xyz; w unused):
    /// the light the volumes were built for, or a jittered one (the pivot
    /// approximation of section 4.4).
    pub position: [f32; 4],
    /// Column-major affine map applied after the extrusion: the identity for
    /// a real light's shadows, the transforms of the specular faces a virtual
    /// light's shadow or light volume passes after it is cast (section 4.3).
    pub transform: [[f32; 4]; 4],
}

impl VolumeLight {
    /// The block of volumes extruded from `position`, then moved by `transform`.
    pub fn new(position: Vec3, transform: glam::Affine3A) -> Self {
        Self {
            position: position.extend(1.0).to_array(),
            transform: glam::Mat4::from(transform).to_cols_array_2d(),
        }
    }
}

/// The light positions of the shadow-volume passes (section 4.4), one
/// [`VolumeLight`] block per light in one uniform buffer read at dynamic
/// offsets (group 1), so every light of a frame fits one submission.
#[derive(Debug)]
pub struct VolumeLights {
    buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    stride: u64,
    capacity: usize,
    offsets: Vec<u32>,
}

impl VolumeLights {
    /// Room for `capacity` lights (grown by [`VolumeLights::write`]).
    pub fn new(ctx: &GpuContext, pass: &ShadowVolumePass, capacity: usize) -> Self {
        let alignment = u64::from(ctx.device.limits().min_uniform_buffer_offset_alignment);
        let stride = (size_of::<VolumeLight>() as u64).div_ceil(alignment) * alignment;
        let capacity = capacity.max(1);
        let (buffer, bind_group) = Self::allocate(ctx, pass, stride, capacity);
        Self {
            buffer,
            bind_group,
            stride,
            capacity,
            offsets: Vec::new(),
        }
    }

    fn allocate(
        ctx: &GpuContext,
        pass: &ShadowVolumePass,
        stride: u64,
        capacity: usize,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadow-volume-lights"),
            size: stride * capacity as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow-volume-lights"),
            layout: &pass.light_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(size_of::<VolumeLight>() as u64),
                }),
            }],
        });
        (buffer, bind_group)
    }

    /// Writes the light positions (applied at the next submit), light `i` at
    /// block `i`. Fails on a position that is not finite.
    pub fn write(
        &mut self,
        ctx: &GpuContext,
        pass: &ShadowVolumePass,
        lights: &[Vec3],
    ) -> Result<()> {
        let blocks: Vec<VolumeLight> = lights
            .iter()
            .map(|&l| VolumeLight::new(l, glam::Affine3A::IDENTITY))
            .collect();
        self.write_blocks(ctx, pass, &blocks)
    }

    /// Writes whole blocks (position and transform), block `i` at offset `i`.
    /// Fails on a position or transform that is not finite.
    pub fn write_blocks(
        &mut self,
        ctx: &GpuContext,
        pass: &ShadowVolumePass,
        lights: &[VolumeLight],
    ) -> Result<()> {
        if let Some(i) = lights.iter().position(|l| {
            !(l.position.iter().all(|v| v.is_finite())
                && l.transform.iter().flatten().all(|v| v.is_finite()))
        }) {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!("light #{i} position is not finite"),
            });
        }
        if lights.len() > self.capacity {
            let capacity = lights.len().next_power_of_two();
            let (buffer, bind_group) = Self::allocate(ctx, pass, self.stride, capacity);
            self.buffer = buffer;
            self.bind_group = bind_group;
            self.capacity = capacity;
        }
        let mut bytes = vec![0u8; self.stride as usize * lights.len()];
        self.offsets.clear();
        for (i, block) in lights.iter().enumerate() {
            let offset = i * self.stride as usize;
            bytes[offset..offset + size_of::<VolumeLight>()]
                .copy_from_slice(bytemuck::bytes_of(block));
            self.offsets
                .push(u32::try_from(offset).map_err(|_| MprError::InvalidSetting {
                    what: "shadow volumes",
                    message: format!("{} lights exceed a 4 GiB uniform buffer", lights.len()),
                })?);
        }
        if !bytes.is_empty() {
            ctx.queue.write_buffer(&self.buffer, 0, &bytes);
        }
        Ok(())
    }

    /// Number of lights written.
    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    /// Whether no light was written.
    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }
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
///
/// Every pipeline has one colour target of the format given to
/// [`ShadowVolumePass::new`] (the HDR target in a frame, so the stencil
/// passes, the lit redraw and the restore share one render pass;
/// [`ShadowVolumePass::begin_pass`]); only the lit-mask pipeline writes colour.
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
    color_format: wgpu::TextureFormat,
    light_layout: wgpu::BindGroupLayout,
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
    /// Builds the pipelines for render passes whose one colour attachment has
    /// `color_format` (the HDR format in a frame; the mask's format for
    /// [`ShadowVolumePass::record_lit_mask`]). Fails when the depth target has
    /// no stencil ([`GpuContext::has_stencil`]).
    pub fn new(ctx: &GpuContext, color_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.has_stencil() {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: "the device has no Depth32FloatStencil8 target".into(),
            });
        }
        ctx.checked("shadow volume pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "shadow-volume", &with_view(SHADOW_VOLUME_WGSL));
            let light_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadow-volume-light"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(size_of::<VolumeLight>() as u64),
                    },
                    count: None,
                }],
            });
            let volume_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadow-volume"),
                bind_group_layouts: &[Some(ctx.view_layout()), Some(&light_layout)],
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
                    format: color_format,
                    blend: None,
                    write_mask: if mask {
                        wgpu::ColorWrites::ALL
                    } else {
                        wgpu::ColorWrites::empty()
                    },
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
                        bias: if volume {
                            VOLUME_DEPTH_BIAS
                        } else {
                            wgpu::DepthBiasState::default()
                        },
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
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
            Self {
                mark,
                replace_high,
                volumes_ccw,
                volumes_cw,
                mask,
                color_format,
                light_layout,
            }
        })
    }

    /// Begins the render pass the shadow-volume passes of a light are
    /// recorded into (section 7.3): `color` loaded and stored (the HDR target
    /// in a frame), depth and stencil of `targets` loaded and stored.
    pub fn begin_pass<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        color: &wgpu::TextureView,
        label: &str,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
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
    /// [`ShadowVolumePass::record_end`] restores. Leaves the stencil reference
    /// at [`SHAD_ZERO`].
    pub fn record_begin(&self, pass: &mut wgpu::RenderPass<'_>, view_reference: u32) -> Result<()> {
        self.record_begin_at(pass, view_reference, SHAD_ZERO)
    }

    /// [`ShadowVolumePass::record_begin`] with the area set to `start`
    /// (`SHAD_ZERO + m` before `m` light volumes are counted inverted,
    /// section 4.2, so that only their intersection comes back to
    /// [`SHAD_ZERO`]). Fails unless `SHAD_ZERO <= start < 256`.
    pub fn record_begin_at(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        view_reference: u32,
        start: u32,
    ) -> Result<()> {
        Self::check_reference(view_reference)?;
        if !(SHAD_ZERO..256).contains(&start) {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!("stencil start {start} outside {SHAD_ZERO}..256"),
            });
        }
        pass.set_pipeline(&self.mark);
        pass.set_stencil_reference(view_reference);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&self.replace_high);
        pass.set_stencil_reference(start);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Counts the volumes of light `light` (its block in `lights`) into the
    /// stencil with the depth-fail rule (section 4.1), drawn through the view
    /// of `slot` (clipped by its clip plane): depth test `Greater` (reverse
    /// Z) without writes, back faces increment and front faces decrement
    /// (wrapping) where the depth test fails, only where stencil `>= SHAD_MIN`.
    /// The slot's `mirrored` ([`crate::View::is_mirrored`]) swaps which
    /// winding is front. Fails when `light` has no block in `lights`.
    #[allow(clippy::too_many_arguments)]
    pub fn record_volumes(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
        lights: &VolumeLights,
        light: usize,
        volumes: &ShadowVolumeBuffers,
    ) -> Result<()> {
        self.record_volumes_as(pass, views, slot, lights, light, volumes, slot.mirrored)
    }

    /// [`ShadowVolumePass::record_volumes`] with the front faces' winding
    /// given: clockwise counts a volume drawn through a mirroring transform
    /// (or view) as a plain one does, and counts a plain volume inverted
    /// (−1 inside: the light volumes of section 4.2).
    #[allow(clippy::too_many_arguments)]
    pub fn record_volumes_as(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
        lights: &VolumeLights,
        light: usize,
        volumes: &ShadowVolumeBuffers,
        clockwise: bool,
    ) -> Result<()> {
        let Some(&offset) = lights.offsets.get(light) else {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!(
                    "light #{light} has no position ({} written)",
                    lights.offsets.len()
                ),
            });
        };
        if volumes.vertex_count == 0 {
            return Ok(());
        }
        pass.set_pipeline(if clockwise {
            &self.volumes_cw
        } else {
            &self.volumes_ccw
        });
        views.bind(pass, 0, slot);
        pass.set_stencil_reference(SHAD_MIN);
        pass.set_bind_group(1, &lights.bind_group, &[offset]);
        pass.set_vertex_buffer(0, volumes.vertices.slice(..));
        pass.draw(0..volumes.vertex_count, 0..1);
        Ok(())
    }

    /// Gives the shadow half back to the view: every stencil `>= SHAD_MIN`
    /// becomes `view_reference` again (section 7.3).
    pub fn record_end(&self, pass: &mut wgpu::RenderPass<'_>, view_reference: u32) -> Result<()> {
        Self::check_reference(view_reference)?;
        pass.set_pipeline(&self.replace_high);
        pass.set_stencil_reference(view_reference);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Writes 1 into the pass's colour attachment (of the format given to
    /// [`ShadowVolumePass::new`]) where the stencil equals [`SHAD_ZERO`]: the
    /// lit area between [`ShadowVolumePass::record_volumes`] and
    /// [`ShadowVolumePass::record_end`] (section 4.1).
    pub fn record_lit_mask(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.mask);
        pass.set_stencil_reference(SHAD_ZERO);
        pass.draw(0..3, 0..1);
    }

    /// The colour format of the passes the pipelines are recorded into.
    pub fn color_format(&self) -> wgpu::TextureFormat {
        self.color_format
    }
}
