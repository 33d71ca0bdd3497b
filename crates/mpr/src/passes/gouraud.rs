//! The Gouraud pass of García Hernández, Ureña & Lastra (2003), section 2.4:
//! the outgoing radiance `L_r = ρ/π E` (equation 2.2) known at mesh vertices,
//! interpolated perspective-correctly inside each triangle and added into the
//! HDR target after an equal-depth redraw of the scene. The per-corner
//! radiance is a vertex buffer parallel to [`SceneBuffers::vertices`],
//! rewritten cheaply every frame ([`GouraudPass::set_radiance`]) as the
//! quasi-static method of section 2.4.2 updates it. CPU twin:
//! [`gouraud_pass_cpu`]; conversion from per-vertex irradiance:
//! [`corner_radiance`].
//!
//! Diffuse maps: [`corner_radiance`] uses the untextured `ρ_d`, and the
//! fragment stage scales the interpolated radiance by the map at the
//! fragment's own texture coordinates ([`GouraudPass::set_diffuse_maps`],
//! [`corner_layers`]), so `ρ_d t(uv) E / π` with `E` interpolated, since
//! `ρ_d` is constant over a mesh. Reading the map at the vertices instead
//! would blur it to the lighting mesh's resolution. Corners whose radiance
//! already holds the map (the glossy meshes' view-dependent estimate, which
//! folds `ρ_d t(uv)` in at each vertex) take the white layer.

use glam::Vec2;
use lustre_density::{VertexIrradiance, diffuse_radiance};
use lustre_geometry::material::MaterialModel;
use lustre_geometry::{Bvh, Camera, Hit, MeshId, Rgb, Scene};

use crate::diffuse_map::{DiffuseMaps, WHITE_LAYER};
use crate::passes::redraw::{ScenePipeline, additive_target, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::gouraud_wgsl;
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

/// Layout of the per-corner diffuse map layer buffer: `@location(5) u32`, one per [`crate::GpuVertex`] ([`corner_layers`]).
pub const LAYER_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<u32>() as wgpu::BufferAddress,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![5 => Uint32],
};

/// The GPU Gouraud pass (section 2.4) for one scene's triangle corners.
#[derive(Debug)]
pub struct GouraudPass {
    pipeline: wgpu::RenderPipeline,
    /// Outgoing radiance per triangle corner (`[f32; 3]`), parallel to [`SceneBuffers::vertices`].
    radiance: wgpu::Buffer,
    /// The diffuse map layer per triangle corner (`u32`), parallel to `radiance`.
    layers: wgpu::Buffer,
    /// The maps' layout (group 1).
    maps_layout: wgpu::BindGroupLayout,
    /// The maps bound (group 1): white until [`GouraudPass::set_diffuse_maps`].
    maps: wgpu::BindGroup,
    /// Corners the radiance buffer holds: the scene's `vertex_count`.
    corners: u32,
}

impl GouraudPass {
    /// Builds the pipeline for HDR targets of `hdr_format` and a zero radiance buffer with one value per corner of `scene`, no diffuse map read.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &SceneBuffers,
    ) -> Result<Self> {
        let corners = scene.vertex_count;
        let white = DiffuseMaps::white(ctx)?;
        ctx.checked("gouraud pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "gouraud", &gouraud_wgsl());
            let maps_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gouraud-maps"),
                entries: &DiffuseMaps::layout_entries(0, wgpu::ShaderStages::FRAGMENT),
            });
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "gouraud",
                    module: &module,
                    layouts: &[&maps_layout],
                    extra_vertex_buffers: &[RADIANCE_LAYOUT, LAYER_LAYOUT],
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
            // Zero-initialised: every corner on the white layer.
            let layers = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gouraud-layers"),
                size: (corners.max(1) as usize * size_of::<u32>()) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let maps = maps_bind_group(device, &maps_layout, &white);
            Self {
                pipeline,
                radiance,
                layers,
                maps_layout,
                maps,
                corners,
            }
        })
    }

    /// Reads `maps` from now on, each corner's fragments scaled by the map of its layer in `layers` ([`corner_layers`], one per corner, [`WHITE_LAYER`] for none). Fails unless there is one layer per corner, each one `maps` holds.
    pub fn set_diffuse_maps(
        &mut self,
        ctx: &GpuContext,
        maps: &DiffuseMaps,
        layers: &[u32],
    ) -> Result<()> {
        let invalid = |message: String| MprError::InvalidSetting {
            what: "gouraud diffuse maps",
            message,
        };
        if layers.len() != self.corners as usize {
            return Err(invalid(format!(
                "{} layers given for {} triangle corners",
                layers.len(),
                self.corners
            )));
        }
        let held = maps.layers().iter().copied().max().unwrap_or(WHITE_LAYER);
        if let Some(&l) = layers.iter().find(|&&l| l > held) {
            return Err(invalid(format!(
                "layer {l} asked for, the maps hold layers up to {held}"
            )));
        }
        if !layers.is_empty() {
            ctx.queue
                .write_buffer(&self.layers, 0, bytemuck::cast_slice(layers));
        }
        self.maps = maps_bind_group(&ctx.device, &self.maps_layout, maps);
        Ok(())
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
        pass.set_bind_group(1, &self.maps, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_vertex_buffer(1, self.radiance.slice(..));
        pass.set_vertex_buffer(2, self.layers.slice(..));
        pass.draw(0..scene.vertex_count, 0..1);
        Ok(())
    }
}

/// The bind group of `maps` for the pass's group 1.
fn maps_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    maps: &DiffuseMaps,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gouraud-maps"),
        layout,
        entries: &maps.entries(0),
    })
}

/// The diffuse map layer of every scene triangle corner, in [`corner_radiance`]'s order: the layer `maps` gives the mesh's material, or [`WHITE_LAYER`] on the meshes of `tinted_at_vertices` (whose corner radiance already holds the map) and for a material without a map.
pub fn corner_layers(scene: &Scene, maps: &DiffuseMaps, tinted_at_vertices: &[MeshId]) -> Vec<u32> {
    let mut out = Vec::with_capacity(3 * scene.triangle_count());
    for (m, mesh) in scene.meshes().iter().enumerate() {
        let layer = if tinted_at_vertices.contains(&(m as MeshId)) {
            WHITE_LAYER
        } else {
            maps.layers()
                .get(mesh.material as usize)
                .copied()
                .unwrap_or(WHITE_LAYER)
        };
        out.extend(std::iter::repeat_n(layer, 3 * mesh.indices.len()));
    }
    out
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

/// CPU counterpart of [`GouraudPass`] without diffuse maps: per pixel
/// centre, the hit triangle's corner radiance interpolated with the hit's
/// barycentrics (`(1 - u - v) L0 + u L1 + v L2`) when the camera is on the
/// side its shading normal points to; zero elsewhere. Row 0 is the top.
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
    gouraud_pass_cpu_tinted(bvh, camera, width, height, corner_radiance, |_| Rgb::ONE)
}

/// [`gouraud_pass_cpu`] with the interpolated radiance scaled by `tint` of the hit: for a pass reading diffuse maps, [`lustre_geometry::Material::diffuse_tint`] of the hit's material at its UV where the triangle's corners have a map layer, one elsewhere (level 0, bilinear: the GPU's trilinear read agrees where the map is magnified).
///
/// # Panics
///
/// Unless `corner_radiance` holds three values per triangle of `bvh`.
pub fn gouraud_pass_cpu_tinted(
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    corner_radiance: &[[f32; 3]],
    tint: impl Fn(&Hit) -> Rgb + Sync,
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
                (((1.0 - h.u - h.v) * l0 + h.u * l1 + h.v * l2) * tint(&h)).to_array()
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
