//! Photon Maps (section 1.2, Jensen): the `k` impacts nearest to a vertex, `E = Σ φ_j / (π r_k²)`, with the disc's area taken on the vertex's surface.
//!
//! Only the impacts compatible with the vertex's surface count (Jensen,
//! "Realistic Image Synthesis Using Photon Mapping", 2001, radiance estimate;
//! beyond García, Ureña & Lastra's text): an impact whose surface normal,
//! turned to the side its photon arrived from, makes a cosine below
//! [`NORMAL_FILTER_COSINE`](crate::radiance::NORMAL_FILTER_COSINE) with the vertex normal is skipped, so a vertex near
//! an edge no longer gathers the impacts of the adjoining face. See
//! [`ImpactMap`].
//!
//! Their power is divided by the area of the disc of radius `r_k` that lies
//! on surfaces passing the same filter rather than by `π r_k²` (the boundary
//! correction, beyond both García et al. and Jensen; [`crate::boundary`]):
//! a vertex on the floor's edge against a wall gathers impacts from half a
//! disc, one in a corner from a quarter, and `π r_k²` made them a half and a
//! quarter as bright as they are (section 2.9.1's border bias `α/2π`), with
//! dark outlines along every joint and box edge.

use lustre_geometry::{Bvh, Scene};
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::error::{DensityError, Result};
use crate::radiance::ImpactMap;
use crate::ray_set::RaySet;

/// Photon Maps irradiance at every vertex (section 1.2; section 2.9.1, `PME = E / (π R²)`): the power of the `k` compatible impacts nearest to the vertex ([`ImpactMap`]) over the area of the circle reaching the `k`-th that lies on compatible surfaces of the scene ([`crate::boundary`]); zero where no impact lies at a positive distance. Fails when `k` is zero.
pub fn photon_maps(scene: &Scene, rays: &RaySet, k: usize) -> Result<VertexIrradiance> {
    if k == 0 {
        return Err(DensityError::InvalidOption {
            option: "k",
            message: "the number of nearest impacts must be at least 1".into(),
        });
    }
    let map = ImpactMap::try_build(rays)?;
    let bvh = Bvh::build(scene);
    Ok((0..scene.meshes().len() as u32)
        .map(|m| {
            scene
                .world_positions(m)
                .par_iter()
                .zip(scene.world_normals(m).par_iter())
                .map(|(&x, &n)| map.irradiance(Some(&bvh), x, n, k).as_vec3())
                .collect()
        })
        .collect())
}
