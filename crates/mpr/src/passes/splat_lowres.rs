//! Splats at a lower resolution, upsampled along surface ids and depth
//! (beyond Stürzlinger & Bastos 1997: their splat pass of section 2.2 is
//! fill-bound, each splat covering about `(2 + √2)² h² / 2` of the image
//! plane). The splats of a view are drawn into a target `f` times smaller per
//! axis, each low-resolution pixel `i` sampling the point the full-resolution
//! pixel `f i + f/2` sees and restricted to its surface (the guide,
//! [`guides_cpu`]), and added to the full-resolution HDR target by
//! a joint bilateral upsampling (Kopf, Cohen, Lischinski & Uyttendaele 2007,
//! "Joint bilateral upsampling"; [`upsample_cpu`]) guided by the
//! full-resolution surface ids and depth: bilinear weights times a depth
//! term, never across surface ids. The splat image within one surface is a
//! sum of kernels of support `h`, smooth at that scale, so sampling it every
//! `f` pixels loses little where `h` covers several low-resolution pixels
//! ([`SplatResolution::auto`]). The pass is drawn by
//! [`crate::passes::splat::SplatPass::encode_at`]; `splat_lowres.wgsl` holds
//! the GPU stages.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use lustre_geometry::Camera;

use crate::target::{NO_SURFACE, RenderTargets, SURFACE_ID_FORMAT, Target};
use crate::{GpuContext, Result};

/// The low-resolution WGSL (`src/passes/splat_lowres.wgsl`), self-contained.
pub const SPLAT_LOWRES_WGSL: &str = include_str!("splat_lowres.wgsl");

/// The relative depth difference at which a low-resolution sample's weight
/// falls to `1/e` (`tau` in `splat_lowres.wgsl`): loose enough for a plane
/// seen at a grazing angle over a few pixels, tight for a surface behind a fold of itself.
pub const DEPTH_TAU: f32 = 0.1;

/// The format of the low-resolution depth guide.
pub const LOW_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// The smallest projected kernel radius, in low-resolution pixels, that
/// [`SplatResolution::auto`] accepts for most splats: two samples per
/// radius, Nyquist's rate for a field whose narrowest features (single
/// kernels) are a radius wide. On glosbox (1M photons, 256², BENCHMARKS.md
/// "Splat frames at lower resolution") the error against the reference did not rise at this rate.
pub const AUTO_MIN_RADIUS: f32 = 2.0;

/// The share of splats whose projected radius [`SplatResolution::auto`] checks (the smallest this share may be below [`AUTO_MIN_RADIUS`]).
pub const AUTO_QUANTILE: f32 = 0.05;

/// The resolution the splats of the camera's view are accumulated at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SplatResolution {
    /// The full resolution of the frame: the splat pass as it was, bit for bit.
    #[default]
    Full,
    /// Half the width and height (a quarter of the fill).
    Half,
    /// A quarter of the width and height (a sixteenth of the fill).
    Quarter,
    /// An eighth of the width and height (a sixty-fourth of the fill).
    Eighth,
}

impl SplatResolution {
    /// The reduction factor `f` per axis.
    pub fn factor(self) -> u32 {
        match self {
            Self::Full => 1,
            Self::Half => 2,
            Self::Quarter => 4,
            Self::Eighth => 8,
        }
    }

    /// The coarsest resolution at which all but [`AUTO_QUANTILE`] of the
    /// splats `supports` (`[x, y, z, h]`: centre and support, as
    /// [`crate::passes::splat::SplatBuffers::supports`]), seen through
    /// `camera` in a `height`-pixel-high image, have a projected kernel
    /// radius `h · focal / distance` of at least [`AUTO_MIN_RADIUS`]
    /// low-resolution pixels; [`SplatResolution::Full`] when there are no splats.
    pub fn auto(supports: &[[f32; 4]], camera: &Camera, height: u32) -> Self {
        let Some(small) = radius_quantile(supports, camera, height, AUTO_QUANTILE) else {
            return Self::Full;
        };
        [Self::Eighth, Self::Quarter, Self::Half]
            .into_iter()
            .find(|r| small >= AUTO_MIN_RADIUS * r.factor() as f32)
            .unwrap_or(Self::Full)
    }

    /// The low-resolution size for a `width`×`height` frame: `⌈width/f⌉`×`⌈height/f⌉`.
    pub fn low_size(self, width: u32, height: u32) -> (u32, u32) {
        let f = self.factor();
        (width.div_ceil(f), height.div_ceil(f))
    }
}

/// The `quantile` of the splats' projected kernel radii in pixels (`supports` and the view as in [`SplatResolution::auto`]); `None` without splats.
pub fn radius_quantile(
    supports: &[[f32; 4]],
    camera: &Camera,
    height: u32,
    quantile: f32,
) -> Option<f32> {
    let mut radii: Vec<f32> = supports
        .iter()
        .filter(|s| s[3] > 0.0)
        .map(|s| {
            let distance = Vec3::new(s[0], s[1], s[2]).distance(camera.position);
            projected_radius(s[3], distance, camera, height)
        })
        .collect();
    if radii.is_empty() {
        return None;
    }
    let k = ((radii.len() as f32 * quantile) as usize).min(radii.len() - 1);
    let (_, &mut small, _) = radii.select_nth_unstable_by(k, f32::total_cmp);
    Some(small)
}

/// The radius in pixels of a kernel of support `h` at `distance` from `camera` in a `height`-pixel-high image (seen face on).
pub fn projected_radius(h: f32, distance: f32, camera: &Camera, height: u32) -> f32 {
    let focal = 0.5 * height as f32 / (0.5 * camera.fov_y_degrees.to_radians()).tan();
    h * focal / distance.max(1e-6)
}

/// The uniform block of `splat_lowres.wgsl` (`LowResParams`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
struct LowResParams {
    full_size: [u32; 2],
    low_size: [u32; 2],
    factor: f32,
    depth_tau: f32,
    pad: [f32; 2],
}

/// One view's low-resolution targets: the splat radiance (HDR format), the surface-id guide and the depth guide.
#[derive(Debug)]
pub struct LowResTargets {
    /// The resolution.
    pub resolution: SplatResolution,
    /// Low-resolution width.
    pub width: u32,
    /// Low-resolution height.
    pub height: u32,
    /// The splats' radiance at low resolution, in the frame's HDR format.
    pub radiance: Target,
    /// The surface id at each low-resolution pixel's centre ([`SURFACE_ID_FORMAT`]).
    pub ids: Target,
    /// The depth there ([`LOW_DEPTH_FORMAT`]).
    pub depth: Target,
}

impl LowResTargets {
    /// Targets for `targets` reduced by `resolution` (not [`SplatResolution::Full`]).
    pub fn new(ctx: &GpuContext, targets: &RenderTargets, resolution: SplatResolution) -> Self {
        let (width, height) = resolution.low_size(targets.width, targets.height);
        let texture = |label, format| Target::new(ctx, label, width, height, format);
        Self {
            resolution,
            width,
            height,
            radiance: texture("splat-lowres-radiance", targets.hdr_format()),
            ids: texture("splat-lowres-ids", SURFACE_ID_FORMAT),
            depth: texture("splat-lowres-depth", LOW_DEPTH_FORMAT),
        }
    }
}

/// The guide and upsampling pipelines of `splat_lowres.wgsl`.
#[derive(Debug)]
pub struct SplatLowRes {
    /// Bindings 0-2 (parameters, full-resolution ids and depth).
    guide_layout: wgpu::BindGroupLayout,
    /// Bindings 0-5 (also the low-resolution guides and radiance).
    layout: wgpu::BindGroupLayout,
    guide: wgpu::RenderPipeline,
    upsample: wgpu::RenderPipeline,
}

impl SplatLowRes {
    /// Builds the pipelines for an HDR target of `hdr_format` (the upsampled splats are added into it).
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat) -> Result<Self> {
        ctx.checked("low-resolution splat pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("splat-lowres"),
                source: wgpu::ShaderSource::Wgsl(SPLAT_LOWRES_WGSL.into()),
            });
            let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            };
            let float = wgpu::TextureSampleType::Float { filterable: false };
            let entries = [
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<LowResParams>() as u64),
                    },
                    count: None,
                },
                texture(1, wgpu::TextureSampleType::Uint),
                texture(2, wgpu::TextureSampleType::Depth),
                texture(3, wgpu::TextureSampleType::Uint),
                texture(4, float),
                texture(5, float),
            ];
            let guide_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("splat-lowres-guide"),
                entries: &entries[..3],
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("splat-lowres"),
                entries: &entries,
            });
            let pipeline = |label,
                            entry,
                            layout: &wgpu::BindGroupLayout,
                            targets: &[Option<wgpu::ColorTargetState>]| {
                let pipeline_layout =
                    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some(label),
                        bind_group_layouts: &[Some(layout)],
                        immediate_size: 0,
                    });
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
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
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let replace = |format| {
                Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })
            };
            let guide = pipeline(
                "splat-lowres-guide",
                "fs_guide",
                &guide_layout,
                &[replace(SURFACE_ID_FORMAT), replace(LOW_DEPTH_FORMAT)],
            );
            let add = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let upsample = pipeline(
                "splat-lowres-upsample",
                "fs_upsample",
                &layout,
                &[Some(wgpu::ColorTargetState {
                    format: hdr_format,
                    blend: Some(wgpu::BlendState {
                        color: add,
                        alpha: add,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            );
            Self {
                guide_layout,
                layout,
                guide,
                upsample,
            }
        })
    }

    /// The bind group of the guide (`upsample` false: bindings 0-2) or of the upsampling (bindings 0-5) over `targets` and `low`.
    fn bind_group(
        &self,
        device: &wgpu::Device,
        targets: &RenderTargets,
        low: &LowResTargets,
        upsample: bool,
    ) -> wgpu::BindGroup {
        use wgpu::util::DeviceExt;
        let params = LowResParams {
            full_size: [targets.width, targets.height],
            low_size: [low.width, low.height],
            factor: low.resolution.factor() as f32,
            depth_tau: DEPTH_TAU,
            pad: [0.0; 2],
        };
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("splat-lowres-params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let depth_view = targets
            .depth
            .texture
            .create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            });
        let entries = [
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&targets.surface_id.view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&depth_view),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(&low.ids.view),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::TextureView(&low.depth.view),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::TextureView(&low.radiance.view),
            },
        ];
        let (layout, entries) = if upsample {
            (&self.layout, &entries[..])
        } else {
            (&self.guide_layout, &entries[..3])
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat-lowres"),
            layout,
            entries,
        })
    }

    /// Records the guide: `low.ids` and `low.depth` from the surface-id and
    /// depth targets of `targets` (after the view's depth pass).
    pub fn encode_guides(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        low: &LowResTargets,
    ) {
        let bind_group = self.bind_group(device, targets, low, false);
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("splat-lowres-guide"),
            color_attachments: &[attachment(&low.ids.view), attachment(&low.depth.view)],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.guide);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Records the upsampling: the splat radiance of `low` added into
    /// `targets.hdr` within `scissor` (`[x, y, width, height]`).
    pub fn encode_upsample(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        low: &LowResTargets,
        scissor: [u32; 4],
    ) {
        let bind_group = self.bind_group(device, targets, low, true);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("splat-lowres-upsample"),
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
        let [x, y, w, h] = scissor;
        if w == 0 || h == 0 {
            return;
        }
        pass.set_scissor_rect(x, y, w, h);
        pass.set_pipeline(&self.upsample);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// CPU counterpart of the guide (`fs_guide`): for each low-resolution pixel
/// of a `width`×`height` frame reduced by `resolution`, the surface id and
/// depth of the full-resolution pixel `f i + f/2` (per axis), [`NO_SURFACE`] and
/// 0 for a partial last row or column. Row 0 is the top.
pub fn guides_cpu(
    ids: &[u32],
    depth: &[f32],
    width: u32,
    height: u32,
    resolution: SplatResolution,
) -> (Vec<u32>, Vec<f32>) {
    let f = resolution.factor() as f32;
    let (lw, lh) = resolution.low_size(width, height);
    let mut low_ids = Vec::with_capacity((lw * lh) as usize);
    let mut low_depth = Vec::with_capacity((lw * lh) as usize);
    for y in 0..lh {
        for x in 0..lw {
            let (cx, cy) = ((x as f32 + 0.5) * f, (y as f32 + 0.5) * f);
            if cx >= width as f32 || cy >= height as f32 {
                low_ids.push(NO_SURFACE);
                low_depth.push(0.0);
            } else {
                let i = (cy as u32 * width + cx as u32) as usize;
                low_ids.push(ids[i]);
                low_depth.push(depth[i]);
            }
        }
    }
    (low_ids, low_depth)
}

/// The depth term of a low-resolution sample at depth `low` for a pixel at depth `d`.
fn depth_weight(d: f32, low: f32) -> f32 {
    let x = (low - d).abs() / d.max(1e-30) / DEPTH_TAU;
    (-x * x).exp()
}

/// CPU counterpart of the upsampling (`fs_upsample`): for each pixel of a
/// `width`×`height` frame with surface ids `ids` and depth `depth`, the
/// joint bilateral estimate from the low-resolution `radiance` with guides
/// `low_ids` and `low_depth` ([`guides_cpu`]), or `None` where the pixel sees
/// no surface or no sample of its own surface lies near it (nothing is added
/// there). Row 0 is the top.
pub fn upsample_cpu(
    radiance: &[[f32; 3]],
    low_ids: &[u32],
    low_depth: &[f32],
    ids: &[u32],
    depth: &[f32],
    width: u32,
    height: u32,
    resolution: SplatResolution,
) -> Vec<Option<[f32; 3]>> {
    let f = resolution.factor() as f32;
    let (lw, lh) = resolution.low_size(width, height);
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as usize;
            let id = ids[i];
            if id == NO_SURFACE {
                out.push(None);
                continue;
            }
            let d = depth[i];
            let u = [(x as f32 + 0.5) / f - 0.5, (y as f32 + 0.5) / f - 0.5];
            let base = [u[0].floor() as i64, u[1].floor() as i64];
            let t = [u[0] - u[0].floor(), u[1] - u[1].floor()];
            let sample = |sx: i64, sy: i64| -> Option<usize> {
                if sx < 0 || sy < 0 || sx >= i64::from(lw) || sy >= i64::from(lh) {
                    return None;
                }
                let s = (sy * i64::from(lw) + sx) as usize;
                (low_ids[s] == id).then_some(s)
            };
            let mut sum = [0.0f32; 3];
            let mut weight = 0.0f32;
            let add = |s: usize, w: f32, sum: &mut [f32; 3], weight: &mut f32| {
                for (c, v) in sum.iter_mut().enumerate() {
                    *v += w * radiance[s][c];
                }
                *weight += w;
            };
            for j in 0..2 {
                for k in 0..2 {
                    if let Some(s) = sample(base[0] + k, base[1] + j) {
                        let wx = if k == 1 { t[0] } else { 1.0 - t[0] };
                        let wy = if j == 1 { t[1] } else { 1.0 - t[1] };
                        let w = wx * wy * depth_weight(d, low_depth[s]);
                        add(s, w, &mut sum, &mut weight);
                    }
                }
            }
            if weight <= 0.0 {
                for j in -1..3 {
                    for k in -1..3 {
                        if let Some(s) = sample(base[0] + k, base[1] + j) {
                            let r = [(base[0] + k) as f32 - u[0], (base[1] + j) as f32 - u[1]];
                            let w =
                                depth_weight(d, low_depth[s]) / (1.0 + r[0] * r[0] + r[1] * r[1]);
                            add(s, w, &mut sum, &mut weight);
                        }
                    }
                }
            }
            out.push((weight > 0.0).then(|| sum.map(|v| v / weight)));
        }
    }
    out
}
