//! Tone map: linear HDR radiance to display values, k·L then clamp or
//! Reinhard (Reinhard et al. 2002, eq. 3) then the sRGB OETF, 8 bits per
//! channel (the display step after Diefenbach & Badler 1997, section 7.2's
//! light accumulation), with its CPU twin.

use bytemuck::{Pod, Zeroable};

use crate::shaders::TONEMAP_WGSL;
use crate::{GpuContext, MprError, Result};

/// How exposed radiance x = k·L becomes a display value c in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToneOperator {
    /// c = min(x, 1): exact below 1, clips highlights.
    Clamp,
    /// c = x / (1 + x) per channel (Reinhard et al. 2002, eq. 3, L_white = ∞): never clips.
    #[default]
    Reinhard,
}

/// Tone-map settings: exposure k (m² sr / W) and operator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tonemap {
    /// Scale from radiance to display units; finite and ≥ 0.
    pub exposure: f32,
    /// The operator applied after exposure.
    pub operator: ToneOperator,
}

impl Default for Tonemap {
    fn default() -> Self {
        Self {
            exposure: 1.0,
            operator: ToneOperator::Reinhard,
        }
    }
}

impl Tonemap {
    /// Checks the exposure is finite and not negative.
    pub fn validate(&self) -> Result<()> {
        if !(self.exposure >= 0.0) || !self.exposure.is_finite() {
            return Err(MprError::InvalidSetting {
                what: "tone map exposure",
                message: format!("{} is not a finite value >= 0", self.exposure),
            });
        }
        Ok(())
    }

    /// One channel, as `color.wgsl` computes it: c in [0, 1] (before sRGB).
    pub fn display_linear(&self, radiance: f32) -> f32 {
        let x = radiance * self.exposure;
        let x = if x > 0.0 { x.min(f32::MAX) } else { 0.0 };
        match self.operator {
            ToneOperator::Clamp => x.min(1.0),
            ToneOperator::Reinhard => (x / (1.0 + x)).min(1.0),
        }
    }

    /// CPU counterpart of [`TonemapPass`] for one pixel: sRGB-encoded 8-bit RGBA, alpha 255.
    pub fn map_pixel(&self, rgba: [f32; 4]) -> [u8; 4] {
        let q = |l: f32| (srgb_encode(self.display_linear(l)) * 255.0).round() as u8;
        [q(rgba[0]), q(rgba[1]), q(rgba[2]), 255]
    }

    /// CPU counterpart of [`TonemapPass`] for an image.
    pub fn map_image(&self, hdr: &[[f32; 4]]) -> Vec<[u8; 4]> {
        hdr.iter().map(|&p| self.map_pixel(p)).collect()
    }
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1), c in [0, 1].
pub fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The tone-map pass's uniform block (`TonemapUniforms` in `tonemap.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct TonemapUniforms {
    /// Exposure k.
    pub exposure: f32,
    /// 0 = clamp, 1 = Reinhard.
    pub tone_operator: u32,
    /// 1 when the shader applies the sRGB OETF, 0 when the target format does.
    pub encode_srgb: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

/// The GPU tone-map pass for one output format.
#[derive(Debug)]
pub struct TonemapPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    output_format: wgpu::TextureFormat,
}

impl TonemapPass {
    /// Builds the pipeline writing `output_format`: a float-output colour
    /// format; an `*Srgb` format encodes in hardware, others in the shader.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self> {
        let float_output = matches!(
            output_format.sample_type(None, None),
            Some(wgpu::TextureSampleType::Float { .. })
        );
        if !float_output || output_format.is_depth_stencil_format() {
            return Err(MprError::UnsupportedFormat {
                what: "tone map output",
                format: output_format,
            });
        }
        ctx.checked("tone map pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("tonemap"),
                source: wgpu::ShaderSource::Wgsl(TONEMAP_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("tonemap"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: wgpu::BufferSize::new(
                                size_of::<TonemapUniforms>() as u64
                            ),
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("tonemap"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("tonemap"),
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
                        format: output_format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tonemap-uniforms"),
                size: size_of::<TonemapUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            Self {
                pipeline,
                layout,
                uniforms,
                output_format,
            }
        })
    }

    /// The output format the pipeline was built for.
    pub fn output_format(&self) -> wgpu::TextureFormat {
        self.output_format
    }

    /// Writes the settings for the next [`TonemapPass::encode`]; fails on an invalid exposure.
    pub fn prepare(&self, queue: &wgpu::Queue, settings: &Tonemap) -> Result<()> {
        settings.validate()?;
        let uniforms = TonemapUniforms {
            exposure: settings.exposure,
            tone_operator: match settings.operator {
                ToneOperator::Clamp => 0,
                ToneOperator::Reinhard => 1,
            },
            encode_srgb: u32::from(!self.output_format.is_srgb()),
            pad: 0,
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        Ok(())
    }

    /// Records the pass: every pixel of `output` from the same pixel of `hdr` (same size).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        hdr: &wgpu::TextureView,
        output: &wgpu::TextureView,
    ) {
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(hdr),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tonemap"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: output,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operators_map_known_values() {
        let clamp = Tonemap {
            exposure: 2.0,
            operator: ToneOperator::Clamp,
        };
        assert_eq!(clamp.display_linear(0.25), 0.5);
        assert_eq!(clamp.display_linear(10.0), 1.0);
        let reinhard = Tonemap::default();
        assert_eq!(reinhard.display_linear(1.0), 0.5);
        assert_eq!(reinhard.display_linear(f32::INFINITY), 1.0);
        assert_eq!(reinhard.display_linear(f32::NAN), 0.0);
        assert_eq!(reinhard.display_linear(-3.0), 0.0);
        assert_eq!(reinhard.map_pixel([0.0, 1.0, 1e9, 7.0]), [0, 188, 255, 255]);
    }

    #[test]
    fn srgb_encode_is_continuous_and_ends_at_one() {
        let below = srgb_encode(0.003_130_8);
        let above = srgb_encode(0.003_130_9);
        assert!((below - above).abs() < 1e-5);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn invalid_exposure_is_an_error() {
        for exposure in [-1.0, f32::NAN, f32::INFINITY] {
            let t = Tonemap {
                exposure,
                ..Tonemap::default()
            };
            assert!(t.validate().is_err(), "{exposure}");
        }
    }
}
