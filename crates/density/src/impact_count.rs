//! Impact Count (section 1.2, Patanaik; section 2.5.1): the energy of the impacts on each face over its area, then a mean per vertex over the faces it belongs to.

use lustre_geometry::{Rgb, Scene, triangle_area};

use crate::VertexIrradiance;
use crate::ray_set::RaySet;

/// Irradiance of every triangle (scene-wide [`lustre_geometry::TriangleId`] order): `E_t = Σ φ_j / A_t` over the impacts `j` on triangle `t` (section 1.2, "the energy of the impacts on the faces are added"); zero for a degenerate triangle.
pub fn triangle_irradiance(scene: &Scene, rays: &RaySet) -> Vec<Rgb> {
    let (power, area) = triangle_power_and_area(scene, rays);
    power
        .iter()
        .zip(&area)
        .map(|(&p, &a)| if a > 0.0 { p / a } else { Rgb::ZERO })
        .collect()
}

/// Impact power `Σ φ_j` and world area `A_t` of every triangle (section 2.5.1: the triangle's `Add`/`Substract` of impacts).
fn triangle_power_and_area(scene: &Scene, rays: &RaySet) -> (Vec<Rgb>, Vec<f32>) {
    let n = scene.triangle_count();
    // Summed in f64 so many small impacts add up to f32 precision.
    let mut power = vec![glam::DVec3::ZERO; n];
    for (segment, hit) in rays.impacts() {
        if let Some(p) = power.get_mut(hit.triangle as usize) {
            *p += segment.power.as_dvec3();
        }
    }
    let mut area = vec![0.0f32; n];
    for (m, mesh) in scene.meshes().iter().enumerate() {
        let positions = scene.world_positions(m as u32);
        for (t, idx) in mesh.indices.iter().enumerate() {
            let id = scene.triangle_id(m as u32, t as u32) as usize;
            area[id] = triangle_area(idx.map(|i| positions[i as usize]));
        }
    }
    (power.into_iter().map(|p| p.as_vec3()).collect(), area)
}

/// Impact Count irradiance at every vertex (section 1.2): the area-weighted mean of the irradiance `E_t` of the triangles the vertex belongs to, `E_v = Σ_t A_t E_t / Σ_t A_t = Σ_t Σφ_t / Σ_t A_t`.
pub fn impact_count(scene: &Scene, rays: &RaySet) -> VertexIrradiance {
    let (power, area) = triangle_power_and_area(scene, rays);
    scene
        .meshes()
        .iter()
        .enumerate()
        .map(|(m, mesh)| {
            let mut p = vec![Rgb::ZERO; mesh.positions.len()];
            let mut a = vec![0.0f32; mesh.positions.len()];
            for (t, idx) in mesh.indices.iter().enumerate() {
                let id = scene.triangle_id(m as u32, t as u32) as usize;
                for &v in idx {
                    p[v as usize] += power[id];
                    a[v as usize] += area[id];
                }
            }
            p.iter()
                .zip(&a)
                .map(|(&p, &a)| if a > 0.0 { p / a } else { Rgb::ZERO })
                .collect()
        })
        .collect()
}
