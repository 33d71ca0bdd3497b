//! Omnidirectional shadow maps for point lights (Stürzlinger & Bastos 1997,
//! section 2.2.1: "construct a shadow map for each light source", after
//! Segal et al. 1992; a cube map per point light), with its CPU twin.
//!
//! Each [`ShadowCube`] is an `R32Float` cube texture (6 faces of
//! `size`×`size`) holding per texel the Euclidean distance from the light to
//! the nearest surface along the texel's direction, [`NO_OCCLUDER`] where
//! there is none. A face is drawn with a 90° perspective from the light
//! (matrix [`face_view_projection`]) and a reverse-Z `Depth32Float` buffer
//! picks the nearest surface. Distances rather than a depth cube: the lookup
//! then compares the receiver's own distance `|P − L|` with the stored one,
//! the same quantity on every face, and the bias ([`ShadowSettings::bias`])
//! is a length in metres. Faces follow the cube-map face selection of
//! Vulkan, D3D and Metal (+X, −X, +Y, −Y, +Z, −Z; [`cube_texel_direction`]),
//! so `textureSample(cube, P − L)` reads the texel that saw `P`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use lustre_geometry::{Bvh, Ray};

use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::shaders::SHADOW_WGSL;
use crate::target::{REVERSE_Z_CLEAR, REVERSE_Z_COMPARE, check_size};
use crate::{GpuContext, MprError, Result};

/// Format of the cube faces: one distance in metres per texel.
pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Depth format used while drawing a face (reverse Z, like the camera's).
pub const SHADOW_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Stored distance of a texel that sees no surface: every receiver is nearer.
pub const NO_OCCLUDER: f32 = f32::MAX;

/// Shadow-map resolution, near plane and the slope-scaled bias of the lookup (section 2.2.1).
///
/// With nearest sampling, a receiver at distance `d` whose normal makes the
/// angle `θ` with the direction to the light is compared with the distance
/// stored at a texel centre up to half a texel diagonal away, at most
/// `√2/2 · 2/size` radians on a 90° face; along a plane that changes the
/// distance by about `d · δ · tan θ`. The bias is therefore
/// `d (constant_bias + slope_bias · (2/size) · min(tan θ, max_slope))`:
/// `slope_bias` ≥ `√2/2` covers the texel, `constant_bias` the rounding of
/// two independently interpolated distances. Beyond `max_slope` (θ above
/// 89.4° by default, where `cos θ < 0.01`) self-shadowing speckle may remain;
/// light leaking through an occluder nearer than the bias is the price paid
/// everywhere else.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSettings {
    /// Side of each cube face in texels.
    pub size: u32,
    /// Distance from the light of the near plane in m; nearer surfaces cast no shadow.
    pub near: f32,
    /// Bias relative to the receiver's distance (rounding of the stored and computed distances).
    pub constant_bias: f32,
    /// Slope term, in texel angles (`2/size` rad) per unit `tan θ`.
    pub slope_bias: f32,
    /// Largest `tan θ` the slope term follows.
    pub max_slope: f32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            size: 512,
            near: 1e-3,
            constant_bias: 5e-4,
            slope_bias: 1.0,
            max_slope: 100.0,
        }
    }
}

impl ShadowSettings {
    /// Checks the size against the device and the lengths and factors for being finite and positive.
    pub fn validate(&self, ctx: &GpuContext) -> Result<()> {
        check_size(ctx, "shadow cube face", self.size, self.size)?;
        for (name, value) in [
            ("near", self.near),
            ("constant_bias", self.constant_bias),
            ("slope_bias", self.slope_bias),
            ("max_slope", self.max_slope),
        ] {
            if !(value.is_finite() && value >= 0.0) || (name == "near" && value == 0.0) {
                return Err(MprError::InvalidSetting {
                    what: "shadow settings",
                    message: format!("{name} = {value} is not finite and positive"),
                });
            }
        }
        Ok(())
    }

    /// Angle subtended by one texel at a face's centre, `2/size` rad (the largest on the face).
    pub fn texel_angle(&self) -> f32 {
        2.0 / self.size as f32
    }

    /// The bias in m for a receiver at distance `distance` lit at `cos θ = cos_i` (> 0), as `direct.wgsl` computes it.
    pub fn bias(&self, distance: f32, cos_i: f32) -> f32 {
        let tan_i = (1.0 - cos_i * cos_i).max(0.0).sqrt() / cos_i;
        distance
            * (self.constant_bias
                + self.slope_bias * self.texel_angle() * tan_i.min(self.max_slope))
    }
}

/// The three axes of cube face `face` (0..6: +X, −X, +Y, −Y, +Z, −Z): `sc`, `tc`, `ma` of the
/// cube-map face selection, so that a direction `d` has face coordinates `(d·sc, d·tc) / d·ma`.
pub fn cube_face_axes(face: usize) -> [Vec3; 3] {
    match face {
        0 => [Vec3::NEG_Z, Vec3::NEG_Y, Vec3::X],
        1 => [Vec3::Z, Vec3::NEG_Y, Vec3::NEG_X],
        2 => [Vec3::X, Vec3::Z, Vec3::Y],
        3 => [Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y],
        4 => [Vec3::X, Vec3::NEG_Y, Vec3::Z],
        _ => [Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z],
    }
}

/// World-to-clip matrix of cube face `face` seen from `light`: clip = `(sc·d, −tc·d, near, ma·d)`
/// with `d = P − light`, a 90° reverse-Z perspective with an infinite far plane
/// (NDC y is up and texture rows go down, hence `−tc`).
pub fn face_view_projection(face: usize, light: Vec3, near: f32) -> Mat4 {
    let [sc, tc, ma] = cube_face_axes(face);
    let row = |a: Vec3| a.extend(-a.dot(light));
    Mat4::from_cols(row(sc), row(-tc), Vec4::new(0.0, 0.0, 0.0, near), row(ma)).transpose()
}

/// Unit direction through the centre of texel `(x, y)` (row 0 at the top) of face `face` of a `size`² cube.
pub fn cube_texel_direction(face: usize, x: u32, y: u32, size: u32) -> Vec3 {
    let [sc, tc, ma] = cube_face_axes(face);
    let s = 2.0 * (x as f32 + 0.5) / size as f32 - 1.0;
    let t = 2.0 * (y as f32 + 0.5) / size as f32 - 1.0;
    (ma + s * sc + t * tc).normalize()
}

/// CPU counterpart of [`ShadowPass`]: per face, per texel (row 0 at the top),
/// the distance to the closest hit along [`cube_texel_direction`] beyond `near`
/// along the face axis, [`NO_OCCLUDER`] where the ray escapes.
pub fn shadow_cube_cpu(bvh: &Bvh, light: Vec3, size: u32, near: f32) -> [Vec<f32>; 6] {
    std::array::from_fn(|face| {
        let rays: Vec<Ray> = (0..size)
            .flat_map(|y| (0..size).map(move |x| (x, y)))
            .map(|(x, y)| {
                let dir = cube_texel_direction(face, x, y, size);
                // The near plane is at `near` along the face axis.
                let t_min = near / dir.dot(cube_face_axes(face)[2]);
                Ray::segment(light, dir, t_min, f32::INFINITY)
            })
            .collect();
        bvh.closest_hits(&rays)
            .into_iter()
            .map(|h| h.map_or(NO_OCCLUDER, |h| h.t))
            .collect()
    })
}

/// The shadow pass's uniform block for one face (`ShadowFace` in `shadow.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct ShadowFace {
    /// Column-major [`face_view_projection`].
    pub view_projection: [[f32; 4]; 4],
    /// Light position (xyz) and near distance (w).
    pub light: [f32; 4],
}

/// One light's distance cube, its per-face uniforms and the depth buffer its faces are drawn with.
#[derive(Debug)]
pub struct ShadowCube {
    /// The `R32Float` cube texture (6 array layers, +X, −X, +Y, −Y, +Z, −Z).
    pub texture: wgpu::Texture,
    /// A cube view of it, for sampling by direction.
    pub view: wgpu::TextureView,
    face_views: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
    uniforms: wgpu::Buffer,
    stride: u32,
    bind_group: wgpu::BindGroup,
    size: u32,
}

impl ShadowCube {
    /// Side of a face in texels.
    pub fn size(&self) -> u32 {
        self.size
    }
}

/// The GPU shadow pass: draws scene triangles into the faces of [`ShadowCube`]s.
#[derive(Debug)]
pub struct ShadowPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadowPass {
    /// Builds the pipeline (cull none, reverse-Z depth, `R32Float` distance).
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        ctx.checked("shadow pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shadow"),
                source: wgpu::ShaderSource::Wgsl(SHADOW_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadow"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(size_of::<ShadowFace>() as u64),
                    },
                    count: None,
                }],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadow"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(GpuVertex::LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: SHADOW_DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(REVERSE_Z_COMPARE),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: SHADOW_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            Self { pipeline, layout }
        })
    }

    /// A cube of `size`² faces with its depth buffer and face uniforms.
    pub fn create_cube(&self, ctx: &GpuContext, size: u32) -> Result<ShadowCube> {
        check_size(ctx, "shadow cube face", size, size)?;
        ctx.checked("shadow cube creation", || {
            let device = &ctx.device;
            let extent = |layers| wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: layers,
            };
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("shadow-cube"),
                size: extent(6),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: SHADOW_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some("shadow-cube"),
                dimension: Some(wgpu::TextureViewDimension::Cube),
                array_layer_count: Some(6),
                ..Default::default()
            });
            let face_views = (0..6)
                .map(|face| {
                    texture.create_view(&wgpu::TextureViewDescriptor {
                        label: Some("shadow-cube-face"),
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: face,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect();
            let depth = device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some("shadow-depth"),
                    size: extent(1),
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: SHADOW_DEPTH_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default());
            let align = device.limits().min_uniform_buffer_offset_alignment;
            let stride = (size_of::<ShadowFace>() as u32).div_ceil(align) * align;
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow-faces"),
                size: 6 * u64::from(stride),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &uniforms,
                        offset: 0,
                        size: wgpu::BufferSize::new(size_of::<ShadowFace>() as u64),
                    }),
                }],
            });
            ShadowCube {
                texture,
                view,
                face_views,
                depth,
                uniforms,
                stride,
                bind_group,
                size,
            }
        })
    }

    /// Writes the six face matrices of `cube` for a light at `light` with near plane `near`.
    pub fn prepare(&self, queue: &wgpu::Queue, cube: &ShadowCube, light: Vec3, near: f32) {
        let mut bytes = vec![0u8; 6 * cube.stride as usize];
        for face in 0..6 {
            let uniforms = ShadowFace {
                view_projection: face_view_projection(face, light, near).to_cols_array_2d(),
                light: light.extend(near).to_array(),
            };
            let start = face * cube.stride as usize;
            bytes[start..start + size_of::<ShadowFace>()]
                .copy_from_slice(bytemuck::bytes_of(&uniforms));
        }
        queue.write_buffer(&cube.uniforms, 0, &bytes);
    }

    /// Records six render passes, one per face: clear to [`NO_OCCLUDER`] and
    /// [`REVERSE_Z_CLEAR`], then draw every scene triangle.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        cube: &ShadowCube,
    ) {
        for (face, view) in cube.face_views.iter().enumerate() {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow-face"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: f64::from(NO_OCCLUDER),
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &cube.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(REVERSE_Z_CLEAR),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if scene.vertex_count > 0 {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &cube.bind_group, &[face as u32 * cube.stride]);
                pass.set_vertex_buffer(0, scene.vertices.slice(..));
                pass.draw(0..scene.vertex_count, 0..1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_face_matrix_maps_its_texel_directions_to_their_pixel_centres() {
        let light = Vec3::new(0.3, -0.2, 0.5);
        let size = 8;
        for face in 0..6 {
            let m = face_view_projection(face, light, 1e-3);
            for (x, y) in [(0, 0), (7, 0), (3, 5), (7, 7)] {
                let p = light + 2.0 * cube_texel_direction(face, x, y, size);
                let ndc = m.project_point3(p);
                let px = (ndc.x + 1.0) * 0.5 * size as f32;
                let py = (1.0 - ndc.y) * 0.5 * size as f32;
                assert!(
                    (px - (x as f32 + 0.5)).abs() < 1e-4 && (py - (y as f32 + 0.5)).abs() < 1e-4,
                    "face {face} texel ({x}, {y}) lands at ({px}, {py})"
                );
                assert!(ndc.z > 0.0 && ndc.z < 1.0, "reverse-Z depth {}", ndc.z);
            }
        }
    }

    #[test]
    fn texel_directions_select_their_own_face() {
        // The major axis of every texel direction is the face's axis (cube-map face selection).
        for face in 0..6 {
            let ma = cube_face_axes(face)[2];
            for (x, y) in [(0, 0), (15, 0), (0, 15), (15, 15), (8, 3)] {
                let d = cube_texel_direction(face, x, y, 16);
                let major = d.abs().max_element();
                assert!((d.dot(ma) - major).abs() < 1e-6, "face {face}: {d}");
            }
        }
    }

    #[test]
    fn bias_grows_with_the_slope_and_stops_at_the_cap() {
        let s = ShadowSettings::default();
        assert!((s.bias(2.0, 1.0) - 2.0 * s.constant_bias).abs() < 1e-7);
        let at_45 = s.bias(1.0, std::f32::consts::FRAC_1_SQRT_2);
        assert!((at_45 - (s.constant_bias + s.texel_angle())).abs() < 1e-6);
        assert_eq!(s.bias(1.0, 1e-6), s.bias(1.0, 1e-7));
    }
}
