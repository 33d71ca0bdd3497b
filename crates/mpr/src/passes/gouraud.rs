//! The Gouraud pass of García Hernández, Ureña & Lastra (2003), section 2.4:
//! the outgoing radiance `L_r = ρ/π E` (equation 2.2) known at mesh vertices,
//! interpolated perspective-correctly inside each triangle and added into the
//! HDR target after an equal-depth redraw of the scene. The per-corner
//! radiance is a vertex buffer parallel to [`SceneBuffers::vertices`],
//! rewritten cheaply every frame ([`GouraudPass::set_radiance`]) as the
//! quasi-static method of section 2.4.2 updates it. CPU twin:
//! [`gouraud_pass_cpu`]; conversion from per-vertex irradiance:
//! [`corner_radiance`].

use glam::Vec2;
use lustre_density::{VertexIrradiance, diffuse_radiance};
use lustre_geometry::material::MaterialModel;
use lustre_geometry::{Bvh, Camera, Rgb, Scene};

use crate::passes::redraw::{ScenePipeline, additive_target, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::with_view;
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The Gouraud pass's own WGSL (`src/passes/gouraud.wgsl`); compiled after the view block.
pub const GOURAUD_WGSL: &str = include_str!("gouraud.wgsl");

/// Layout of the per-corner radiance buffer: `@location(4) vec3f`, one per [`crate::GpuVertex`] (section 2.4, one value per vertex).
pub const RADIANCE_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<[f32; 3]>() as wgpu::BufferAddress,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![4 => Float32x3],
};

/// The GPU Gouraud pass (section 2.4) for one scene's triangle corners.
#[derive(Debug)]
pub struct GouraudPass {
    pipeline: wgpu::RenderPipeline,
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
        let corners = scene.vertex_count;
        ctx.checked("gouraud pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "gouraud", &with_view(GOURAUD_WGSL));
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "gouraud",
                    module: &module,
                    layouts: &[],
                    extra_vertex_buffers: &[RADIANCE_LAYOUT],
                    target: additive_target(hdr_format),
                    depth_compare: wgpu::CompareFunction::Equal,
                    depth_write: false,
                },
            );
            // A zero-sized vertex buffer cannot be bound; an empty scene keeps one unused corner.
            let radiance = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gouraud-radiance"),
                size: (corners.max(1) as usize * size_of::<[f32; 3]>()) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            Self {
                pipeline,
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

    /// Records the pass after the depth pre-pass: adds the interpolated vertex radiance on the front side of every visible triangle. Fails when `scene` has another corner count than the pass was built for.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
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
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return Ok(());
        }
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
