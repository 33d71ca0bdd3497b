//! The Gouraud pass of García Hernández, Ureña & Lastra (2003), section 2.4:
//! the outgoing radiance `L_r = ρ/π E` (equation 2.2) known at mesh vertices,
//! interpolated perspective-correctly inside each triangle and added into the
//! HDR target after an equal-depth redraw of the scene. The per-corner
//! radiance is a vertex buffer parallel to [`SceneBuffers::vertices`],
//! rewritten cheaply every frame ([`GouraudPass::set_radiance`]) as the
//! quasi-static method of section 2.4.2 updates it. CPU twin:
//! [`gouraud_pass_cpu`]; conversion from per-vertex irradiance:
//! [`corner_radiance`].

use bytemuck::{Pod, Zeroable};
use glam::Vec2;
use lustre_density::{VertexIrradiance, diffuse_radiance};
use lustre_geometry::material::MaterialModel;
use lustre_geometry::{Bvh, Camera, Rgb, Scene};

use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::target::RenderTargets;
use crate::{GpuContext, MprError, Result};

/// The Gouraud WGSL (`src/passes/gouraud.wgsl`), self-contained.
pub const GOURAUD_WGSL: &str = include_str!("gouraud.wgsl");

/// Layout of the per-corner radiance buffer: `@location(4) vec3f`, one per [`GpuVertex`] (section 2.4, one value per vertex).
pub const RADIANCE_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<[f32; 3]>() as wgpu::BufferAddress,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![4 => Float32x3],
};

/// The pass's uniform block (`GouraudCamera` in `gouraud.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GouraudCamera {
    /// Column-major world-to-clip matrix.
    pub view_projection: [[f32; 4]; 4],
    /// Camera position (w unused).
    pub position: [f32; 4],
}

/// The GPU Gouraud pass (section 2.4) for one scene's triangle corners.
#[derive(Debug)]
pub struct GouraudPass {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// Outgoing radiance per triangle corner (`[f32; 3]`), parallel to [`SceneBuffers::vertices`].
    radiance: wgpu::Buffer,
    /// Corners the radiance buffer holds: the scene's `vertex_count`.
    corners: u32,
}

impl GouraudPass {
    /// Builds the pipeline for HDR targets of `hdr_format` and a zero radiance buffer with one value per corner of `scene`.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &SceneBuffers,
    ) -> Result<Self> {
        let depth_format = ctx.depth_format();
        let corners = scene.vertex_count;
        ctx.checked("gouraud pass creation", || {
            let device = &ctx.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("gouraud"),
                source: wgpu::ShaderSource::Wgsl(GOURAUD_WGSL.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gouraud"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<GouraudCamera>() as u64),
                    },
                    count: None,
                }],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gouraud"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("gouraud"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(GpuVertex::LAYOUT), Some(RADIANCE_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: depth_format,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Equal),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: hdr_format,
                        blend: Some(wgpu::BlendState {
                            color: wgpu::BlendComponent {
                                src_factor: wgpu::BlendFactor::One,
                                dst_factor: wgpu::BlendFactor::One,
                                operation: wgpu::BlendOperation::Add,
                            },
                            alpha: wgpu::BlendComponent::OVER,
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gouraud-camera"),
                size: size_of::<GouraudCamera>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            // A zero-sized vertex buffer cannot be bound; an empty scene keeps one unused corner.
            let radiance = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gouraud-radiance"),
                size: (corners.max(1) as usize * size_of::<[f32; 3]>()) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("gouraud"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniforms.as_entire_binding(),
                }],
            });
            Self {
                pipeline,
                uniforms,
                bind_group,
                radiance,
                corners,
            }
        })
    }

    /// Triangle corners the pass holds a radiance for (three per scene triangle).
    pub fn corners(&self) -> u32 {
        self.corners
    }

    /// Replaces the per-corner outgoing radiance (W/(m² sr), RGB), in scene triangle-corner order ([`corner_radiance`]); one buffer write, cheap enough for every frame (section 2.4.2). Fails unless there is one value per corner.
    pub fn set_radiance(&self, queue: &wgpu::Queue, radiance: &[[f32; 3]]) -> Result<()> {
        if radiance.len() != self.corners as usize {
            return Err(MprError::InvalidSetting {
                what: "gouraud radiance",
                message: format!(
                    "{} values given for {} triangle corners",
                    radiance.len(),
                    self.corners
                ),
            });
        }
        if !radiance.is_empty() {
            queue.write_buffer(&self.radiance, 0, bytemuck::cast_slice(radiance));
        }
        Ok(())
    }

    /// Writes the camera for the next [`GouraudPass::encode`].
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera) {
        let uniforms = GouraudCamera {
            view_projection: camera.view_projection().to_cols_array_2d(),
            position: camera.position.extend(1.0).to_array(),
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Records the pass after the depth pre-pass: adds the interpolated vertex radiance on the front side of every visible triangle. Fails when `scene` has another corner count than the pass was built for.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
    ) -> Result<()> {
        if scene.vertex_count != self.corners {
            return Err(MprError::InvalidSetting {
                what: "gouraud pass",
                message: format!(
                    "built for {} triangle corners, asked to draw {}",
                    self.corners, scene.vertex_count
                ),
            });
        }
        if scene.vertex_count == 0 {
            return Ok(());
        }
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "gouraud");
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_vertex_buffer(1, self.radiance.slice(..));
        pass.draw(0..scene.vertex_count, 0..1);
        Ok(())
    }
}

/// The Lambertian reflectance `ρ` of a material model's diffuse part (section 2.4, equation 2.2 holds for diffuse surfaces): [`MaterialModel::diffuse_reflectance`].
pub fn diffuse_part(model: &MaterialModel) -> Rgb {
    model.diffuse_reflectance()
}

/// Outgoing radiance per scene triangle corner, `L_r = ρ/π E` (section 2.4, equation 2.2) with `ρ` the [`diffuse_part`] of the mesh's material and `E` the irradiance at the corner's vertex; in scene-wide triangle-id order, three corners per triangle as [`SceneBuffers`] lays them out. Fails unless `irradiance` has one value per vertex of every mesh.
pub fn corner_radiance(scene: &Scene, irradiance: &VertexIrradiance) -> Result<Vec<[f32; 3]>> {
    let mismatch = |message: String| MprError::InvalidSetting {
        what: "vertex irradiance",
        message,
    };
    if irradiance.len() != scene.meshes().len() {
        return Err(mismatch(format!(
            "{} meshes given for a scene of {}",
            irradiance.len(),
            scene.meshes().len()
        )));
    }
    let mut out = Vec::with_capacity(3 * scene.triangle_count());
    for (mesh, e) in scene.meshes().iter().zip(irradiance) {
        if e.len() != mesh.positions.len() {
            return Err(mismatch(format!(
                "mesh `{}`: {} values given for {} vertices",
                mesh.name,
                e.len(),
                mesh.positions.len()
            )));
        }
        let rho = diffuse_part(&scene.materials()[mesh.material as usize].model);
        // Mesh by mesh, triangle by triangle: the scene-wide triangle-id order of `Scene::world_triangles`.
        out.extend(
            mesh.indices
                .iter()
                .flat_map(|tri| tri.map(|v| diffuse_radiance(rho, e[v as usize]).to_array())),
        );
    }
    Ok(out)
}

/// CPU counterpart of [`GouraudPass`]: per pixel centre, the hit triangle's
/// corner radiance interpolated with the hit's barycentrics
/// (`(1 - u - v) L0 + u L1 + v L2`) when the camera is on the side its
/// shading normal points to; zero elsewhere. Row 0 is the top.
///
/// # Panics
///
/// Unless `corner_radiance` holds three values per triangle of `bvh`.
pub fn gouraud_pass_cpu(
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    corner_radiance: &[[f32; 3]],
) -> Vec<[f32; 3]> {
    assert_eq!(
        corner_radiance.len(),
        3 * bvh.len(),
        "gouraud_pass_cpu: one radiance per triangle corner"
    );
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    bvh.closest_hits(&rays)
        .iter()
        .map(|hit| {
            hit.map_or([0.0; 3], |h| {
                if !((camera.position - h.position).dot(h.shading_normal) > 0.0) {
                    return [0.0; 3];
                }
                let base = 3 * h.triangle as usize;
                let [l0, l1, l2] = [0, 1, 2].map(|i| Rgb::from_array(corner_radiance[base + i]));
                ((1.0 - h.u - h.v) * l0 + h.u * l1 + h.v * l2).to_array()
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    #[test]
    fn corner_radiance_is_rho_over_pi_times_the_vertex_irradiance_in_corner_order() {
        let scene = builtin("cornell").unwrap();
        // E = vertex index + 1 in every channel, so each corner names its vertex.
        let e: VertexIrradiance = scene
            .meshes()
            .iter()
            .map(|m| {
                (0..m.positions.len())
                    .map(|v| Rgb::splat(v as f32 + 1.0))
                    .collect()
            })
            .collect();
        let corners = corner_radiance(&scene, &e).unwrap();
        assert_eq!(corners.len(), 3 * scene.triangle_count());
        for id in 0..scene.triangle_count() as u32 {
            let (m, t) = scene.triangle_source(id);
            let mesh = &scene.meshes()[m as usize];
            let rho = diffuse_part(&scene.materials()[mesh.material as usize].model);
            for (c, &v) in mesh.indices[t as usize].iter().enumerate() {
                let expected = rho * (v as f32 + 1.0) / std::f32::consts::PI;
                let got = Rgb::from_array(corners[3 * id as usize + c]);
                assert!((got - expected).abs().max_element() <= 1e-6 * expected.max_element());
            }
        }
    }

    #[test]
    fn corner_radiance_refuses_a_mismatched_irradiance() {
        let scene = builtin("cornell").unwrap();
        assert!(corner_radiance(&scene, &Vec::new()).is_err());
        let mut e: VertexIrradiance = scene
            .meshes()
            .iter()
            .map(|m| vec![Rgb::ONE; m.positions.len()])
            .collect();
        e[0].pop();
        let err = corner_radiance(&scene, &e).unwrap_err().to_string();
        assert!(err.contains("floor"), "{err}");
    }

    #[test]
    fn diffuse_part_of_glosbox_floor_is_its_weighted_diffuse_side_and_gold_has_none() {
        let scene = builtin("glosbox").unwrap();
        let by_name = |n: &str| {
            let m = scene.materials().iter().find(|m| m.name == n).unwrap();
            diffuse_part(&m.model)
        };
        let white = by_name("white");
        assert!(white.min_element() > 0.5);
        assert!((by_name("glossy-floor") - 0.7 * white).abs().max_element() < 1e-6);
        assert_eq!(by_name("gold"), Rgb::ZERO);
    }
}
