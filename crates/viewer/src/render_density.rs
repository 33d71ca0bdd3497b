//! Per-vertex radiance of García Hernández, Ureña & Lastra (2003) for
//! `lustre render --technique detp|impact|photonmap`: the ray set of section
//! 2.3, one of the density estimators of section 1.2 at every mesh vertex
//! (section 2.4.1, figure 2.3), `L_r = ρ/π E` per triangle corner (section
//! 2.4, equation 2.2) for the Gouraud pass, on a scene meshed finely enough
//! for per-vertex lighting (section 2.9).

use std::time::Instant;

use anyhow::Context;
use lustre_density::{RaySetOptions, VertexIrradiance, detp, impact_count, photon_maps};
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Bvh, Scene};
use lustre_mpr::passes::gouraud::corner_radiance;

/// Default DETP disc radius in m (section 1.2): 2.5 % of the 2 m Cornell box, half the default mesh edge (the paper's reference uses 1 % of the scene with 100 M rays; at 100k photons 0.1 m has less noise and more bias near corners).
pub const DEFAULT_DETP_RADIUS: f32 = 0.05;
/// Default number `k` of nearest impacts of Photon Maps (section 1.2, Jensen).
pub const DEFAULT_PHOTONMAP_K: usize = 50;
/// Default longest edge in m after subdivision for per-vertex lighting (section 2.9 meshes into 0.02 m squares; 0.1 m gives `cornell` about 6,500 vertices, keeping DETP's every-segment-at-every-vertex cost near ten seconds on two cores).
pub const DEFAULT_MESH_EDGE: f32 = 0.1;

/// A density estimator of section 1.2 with its parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Estimator {
    /// Density Estimation on the Tangent Plane: disc of this radius in m.
    Detp {
        /// Disc radius `r` in m.
        radius: f32,
    },
    /// Impact Count: impact power over triangle area, mean per vertex (section 2.5.1).
    ImpactCount,
    /// Photon Maps: the `k` nearest impacts.
    PhotonMaps {
        /// Number of nearest impacts.
        k: usize,
    },
}

impl Estimator {
    /// The estimator's name as the sidecar reports it.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Detp { .. } => "detp",
            Self::ImpactCount => "impact",
            Self::PhotonMaps { .. } => "photonmap",
        }
    }
}

/// Per-corner radiance for the Gouraud pass and what producing it cost.
#[derive(Debug, Clone)]
pub struct VertexRadiance {
    /// `L_r = ρ/π E` per scene triangle corner, in `SceneBuffers` order (W/(m² sr), RGB).
    pub corners: Vec<[f32; 3]>,
    /// Primary rays of the ray set (photons that carried power).
    pub primary_rays: usize,
    /// Segments of the ray set (primary rays and reflections).
    pub segments: usize,
    /// Time to trace the ray set (section 2.3), ms.
    pub ray_set_ms: f64,
    /// Time of the estimator over every vertex (section 2.4.1), ms.
    pub estimate_ms: f64,
}

/// `scene` with every non-emissive mesh subdivided regularly to edges of at most `edge` m (section 2.9); emissive meshes keep their shape, so area lights stay the rectangles they were.
pub fn vertex_lit_scene(scene: &Scene, edge: f32) -> anyhow::Result<Scene> {
    let meshes = scene
        .meshes()
        .iter()
        .map(|mesh| {
            if scene.materials()[mesh.material as usize].is_emissive() {
                Ok(mesh.clone())
            } else {
                subdivide(mesh, edge).with_context(|| {
                    format!("cannot subdivide mesh `{}` to {edge} m edges", mesh.name)
                })
            }
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    scene
        .with_meshes(meshes)
        .with_context(|| format!("scene `{}` after subdivision", scene.name))
}

/// Traces the ray set of `photons` photons (section 2.3, figure 2.1) and runs `estimator` at every vertex (section 2.4.1, figure 2.3), returning `L_r = ρ/π E` per triangle corner with the time of each phase.
pub fn vertex_radiance(
    estimator: Estimator,
    scene: &Scene,
    bvh: &Bvh,
    photons: u64,
    seed: u64,
) -> anyhow::Result<VertexRadiance> {
    let start = Instant::now();
    let rays = lustre_density::trace_ray_set(
        scene,
        bvh,
        &RaySetOptions {
            photons,
            seed,
            ..RaySetOptions::default()
        },
    )
    .with_context(|| format!("cannot trace the ray set of `{}`", scene.name))?;
    let ray_set_ms = start.elapsed().as_secs_f64() * 1e3;

    let start = Instant::now();
    let irradiance: VertexIrradiance = match estimator {
        Estimator::Detp { radius } => detp(scene, &rays, radius).context("--radius")?,
        Estimator::ImpactCount => impact_count(scene, &rays),
        Estimator::PhotonMaps { k } => photon_maps(scene, &rays, k).context("--k")?,
    };
    let estimate_ms = start.elapsed().as_secs_f64() * 1e3;
    let corners = corner_radiance(scene, &irradiance)
        .with_context(|| format!("vertex radiance of `{}`", scene.name))?;
    Ok(VertexRadiance {
        corners,
        primary_rays: rays.rays.len(),
        segments: rays.segments().count(),
        ray_set_ms,
        estimate_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    #[test]
    fn subdivision_keeps_the_light_a_rectangle_and_refines_the_rest() {
        let scene = builtin("cornell").unwrap();
        let fine = vertex_lit_scene(&scene, 0.5).unwrap();
        assert_eq!(fine.lights().len(), scene.lights().len());
        assert_eq!(fine.lights()[0].power(), scene.lights()[0].power());
        assert!(fine.triangle_count() > 10 * scene.triangle_count());
        assert!((fine.bounds().extent() - scene.bounds().extent()).length() < 1e-6);
    }

    #[test]
    fn every_estimator_gives_one_finite_radiance_per_corner() {
        let scene = vertex_lit_scene(&builtin("cornell").unwrap(), 0.5).unwrap();
        let bvh = Bvh::build(&scene);
        for estimator in [
            Estimator::Detp { radius: 0.2 },
            Estimator::ImpactCount,
            Estimator::PhotonMaps { k: 10 },
        ] {
            let r = vertex_radiance(estimator, &scene, &bvh, 2_000, 1).unwrap();
            assert_eq!(r.corners.len(), 3 * scene.triangle_count());
            assert!(
                r.corners
                    .iter()
                    .flatten()
                    .all(|c| c.is_finite() && *c >= 0.0)
            );
            assert!(r.corners.iter().any(|c| c[0] > 0.0), "{}", estimator.name());
            assert!(r.segments >= r.primary_rays);
        }
        let bad = vertex_radiance(Estimator::Detp { radius: 0.0 }, &scene, &bvh, 10, 1);
        assert!(format!("{:#}", bad.unwrap_err()).contains("radius"));
    }
}
