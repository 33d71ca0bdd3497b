//! "How it is reflected" on the GPU: the reflected image M convolved with the resampled kernel K over the pixels M covers, then modulated by R from the flipped 1D table, the term `(M * K) R` of equation 2 (Bastos et al. 1999, section 8.2). CPU twin: [`lustre_ibr::glossy`].
//!
//! A compute pass over the reflected image of
//! [`crate::passes::radiance_map`]: each covered pixel (reverse-Z depth
//! above zero) takes the weighted mean of the covered pixels under the
//! kernel's taps ([`lustre_ibr::glossy::pixel_kernel`], computed on the CPU
//! per reflector and frame, the paper's space-invariant kernel), times
//! `R(cos θ)` at its ray. Uncovered pixels are zero.

use bytemuck::{Pod, Zeroable};
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::reflectance_modulation::FlippedRadialReflectance;
use lustre_geometry::Plane;
use lustre_ibr::PinholeView;
use wgpu::util::DeviceExt;

use crate::passes::radiance_map::{GpuPinhole, ReflectedTargets, texture_2d};
use crate::{GpuContext, Result};

/// The pass's WGSL (`src/passes/glossy_reflection.wgsl`).
pub const GLOSSY_REFLECTION_WGSL: &str = include_str!("glossy_reflection.wgsl");

/// Format of the glossy term's texture.
pub const GLOSSY_TERM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `Params` in the WGSL.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GpuParams {
    pinhole: GpuPinhole,
    normal: [f32; 4],
    counts: [u32; 4],
    mask: [u32; 4],
    by_depth: [f32; 4],
}

/// How M is convolved with K.
#[derive(Debug, Clone, Copy)]
pub enum Convolution<'a> {
    /// The paper's space-invariant kernel: K resampled at pixel offsets ([`lustre_ibr::glossy::pixel_kernel`]).
    SpaceInvariant(&'a [(i32, i32, f32)]),
    /// K sized per pixel by its own depth (section 9; [`lustre_ibr::glossy::convolve_by_depth`]); `mean_ratio` for the pixels M leaves uncovered.
    ByDepth {
        /// The kernel texture.
        kernel: &'a KernelTexture,
        /// The mean `d/(e + d)` over M.
        mean_ratio: f32,
    },
}

/// The reflector's pixels that bound the convolution's domain: the frame's surface ids where they equal `surface`, M's pixel `p` reading the frame pixel at its centre, `p · scale + scale/2` ([`lustre_ibr::resolution::coarse_mask`]).
#[derive(Debug, Clone, Copy)]
pub struct SurfaceMask<'a> {
    /// The frame's surface-id texture.
    pub ids: &'a wgpu::Texture,
    /// The reflector's surface id.
    pub surface: u32,
    /// Frame pixels per pixel of M along each axis (1: the same grid).
    pub scale: u32,
}

/// The convolution and modulation pipeline.
#[derive(Debug)]
pub struct GlossyReflectionPass {
    pipeline: wgpu::ComputePipeline,
}

impl GlossyReflectionPass {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        ctx.checked("glossy-reflection pass creation", || {
            let module = ctx
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("glossy-reflection"),
                    source: wgpu::ShaderSource::Wgsl(GLOSSY_REFLECTION_WGSL.into()),
                });
            let pipeline = ctx
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("glossy-reflection"),
                    layout: None,
                    module: &module,
                    entry_point: Some("cs_main"),
                    compilation_options: Default::default(),
                    cache: None,
                });
            Self { pipeline }
        })
    }

    /// A `width × height` texture for the term.
    pub fn output(ctx: &GpuContext, width: u32, height: u32) -> Result<wgpu::Texture> {
        ctx.checked("glossy-term texture", || {
            texture_2d(
                ctx,
                "glossy-term",
                width,
                height,
                GLOSSY_TERM_FORMAT,
                wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        })
    }

    /// Records `(M * K) R` of `m` (seen by `view`, reflector in `plane`) convolved as `convolution` says and modulated by `table` into `output`; with `mask` over the domain of [`lustre_ibr::glossy::convolve_in`], else over the pixels M covers.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        m: &ReflectedTargets,
        view: &PinholeView,
        plane: &Plane,
        convolution: Convolution<'_>,
        table: &FlippedRadialReflectance,
        mask: Option<SurfaceMask<'_>>,
        output: &wgpu::Texture,
    ) -> Result<()> {
        let (taps, by_depth, kernel_weights): (&[(i32, i32, f32)], _, &[f32]) = match convolution {
            Convolution::SpaceInvariant(taps) => (taps, [0.0; 4], &[]),
            Convolution::ByDepth { kernel, mean_ratio } => (
                &[],
                [
                    view.focal.y * kernel.half_angle.tan(),
                    mean_ratio,
                    crate::passes::radiance_map::REFLECTED_NEAR,
                    kernel.size as f32,
                ],
                &kernel.weights,
            ),
        };
        let params = GpuParams {
            pinhole: GpuPinhole::new(view),
            normal: plane.normal.extend(-plane.offset).to_array(),
            counts: [
                view.width,
                view.height,
                taps.len() as u32,
                table.values.len() as u32,
            ],
            mask: [
                mask.map_or(0, |m| m.surface),
                u32::from(mask.is_some()),
                u32::from(matches!(convolution, Convolution::ByDepth { .. })),
                mask.map_or(1, |m| m.scale.max(1)),
            ],
            by_depth,
        };
        let mut gpu_kernel = kernel_weights.to_vec();
        if gpu_kernel.is_empty() {
            gpu_kernel.push(0.0);
        }
        let mut gpu_taps: Vec<[f32; 4]> = taps
            .iter()
            .map(|&(dx, dy, w)| [dx as f32, dy as f32, w, 0.0])
            .collect();
        if gpu_taps.is_empty() {
            gpu_taps.push([0.0; 4]);
        }
        let mut gpu_table: Vec<[f32; 4]> = table
            .values
            .iter()
            .map(|v| v.extend(0.0).to_array())
            .collect();
        if gpu_table.is_empty() {
            gpu_table.push([0.0; 4]);
        }
        let bind_group = ctx.checked("glossy-reflection buffers", || {
            let device = &ctx.device;
            let buffer = |label, contents: &[u8], usage| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage,
                })
            };
            let params = buffer(
                "glossy-reflection-params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            );
            let taps = buffer(
                "glossy-reflection-taps",
                bytemuck::cast_slice(&gpu_taps),
                wgpu::BufferUsages::STORAGE,
            );
            let table = buffer(
                "glossy-reflection-table",
                bytemuck::cast_slice(&gpu_table),
                wgpu::BufferUsages::STORAGE,
            );
            let kernel = buffer(
                "glossy-reflection-kernel",
                bytemuck::cast_slice(&gpu_kernel),
                wgpu::BufferUsages::STORAGE,
            );
            let color = m.color.create_view(&Default::default());
            let depth = m.depth.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            });
            let out = output.create_view(&Default::default());
            let stand_in;
            let ids = match mask {
                Some(mask) => mask.ids.create_view(&Default::default()),
                None => {
                    stand_in = texture_2d(
                        ctx,
                        "glossy-reflection-no-mask",
                        1,
                        1,
                        crate::target::SURFACE_ID_FORMAT,
                        wgpu::TextureUsages::TEXTURE_BINDING,
                    );
                    stand_in.create_view(&Default::default())
                }
            };
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("glossy-reflection"),
                layout: &self.pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&color),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&depth),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: taps.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: table.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&out),
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: wgpu::BindingResource::TextureView(&ids),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: kernel.as_entire_binding(),
                    },
                ],
            })
        })?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("glossy-reflection"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(view.width.div_ceil(8), view.height.div_ceil(8), 1);
        Ok(())
    }
}
