//! Photon Maps (section 1.2, Jensen): the `k` impacts nearest to a vertex, `E = Σ φ_j / (π r_k²)`.

use glam::Vec3;
use lustre_geometry::{Rgb, Scene};
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::error::{DensityError, Result};
use crate::kdtree::KdTree;
use crate::ray_set::RaySet;

/// The Photon Maps estimate at `x` (section 2.9.1, `PME = E / (π R²)`): the power of the `k` impacts nearest to `x` over `π r_k²`; zero where no impact lies at a positive distance.
fn photon_map_estimate(tree: &KdTree, powers: &[Rgb], x: Vec3, k: usize) -> glam::DVec3 {
    let found = tree.nearest(x, k);
    let r2 = found.last().map_or(0.0, |n| n.distance_squared);
    if !(r2 > 0.0) {
        return glam::DVec3::ZERO;
    }
    let sum: glam::DVec3 = found
        .iter()
        .map(|n| powers[n.index as usize].as_dvec3())
        .sum();
    sum / (std::f64::consts::PI * r2 as f64)
}

/// Photon Maps irradiance at every vertex (section 1.2; section 2.9.1, `PME = E / (π R²)`): the power of the `k` impacts nearest to the vertex over the area `π r_k²` of the circle reaching the `k`-th; zero where no impact lies at a positive distance. Fails when `k` is zero.
pub fn photon_maps(scene: &Scene, rays: &RaySet, k: usize) -> Result<VertexIrradiance> {
    if k == 0 {
        return Err(DensityError::InvalidOption {
            option: "k",
            message: "the number of nearest impacts must be at least 1".into(),
        });
    }
    let (positions, powers): (Vec<Vec3>, Vec<Rgb>) =
        rays.impacts().map(|(s, h)| (h.position, s.power)).unzip();
    let tree = KdTree::build(&positions)?;
    Ok((0..scene.meshes().len())
        .map(|m| {
            scene
                .world_positions(m as u32)
                .par_iter()
                .map(|&x| photon_map_estimate(&tree, &powers, x, k).as_vec3())
                .collect()
        })
        .collect())
}
