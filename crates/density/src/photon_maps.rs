//! Photon Maps (section 1.2, Jensen): the `k` impacts nearest to a vertex, `E = Σ φ_j / (π r_k²)`.
//!
//! Only the impacts compatible with the vertex's surface count (Jensen,
//! "Realistic Image Synthesis Using Photon Mapping", 2001, radiance estimate;
//! beyond García, Ureña & Lastra's text): an impact whose surface normal,
//! turned to the side its photon arrived from, makes a cosine below
//! [`NORMAL_FILTER_COSINE`](crate::radiance::NORMAL_FILTER_COSINE) with the vertex normal is skipped, so a vertex near
//! an edge no longer gathers the impacts of the adjoining face. See
//! [`ImpactMap`].

use lustre_geometry::Scene;
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::error::{DensityError, Result};
use crate::radiance::ImpactMap;
use crate::ray_set::RaySet;

/// Photon Maps irradiance at every vertex (section 1.2; section 2.9.1, `PME = E / (π R²)`): the power of the `k` compatible impacts nearest to the vertex ([`ImpactMap`]) over the area `π r_k²` of the circle reaching the `k`-th; zero where no impact lies at a positive distance. Fails when `k` is zero.
pub fn photon_maps(scene: &Scene, rays: &RaySet, k: usize) -> Result<VertexIrradiance> {
    if k == 0 {
        return Err(DensityError::InvalidOption {
            option: "k",
            message: "the number of nearest impacts must be at least 1".into(),
        });
    }
    let map = ImpactMap::try_build(rays)?;
    Ok((0..scene.meshes().len() as u32)
        .map(|m| {
            scene
                .world_positions(m)
                .par_iter()
                .zip(scene.world_normals(m).par_iter())
                .map(|(&x, &n)| map.irradiance(x, n, k).as_vec3())
                .collect()
        })
        .collect())
}
