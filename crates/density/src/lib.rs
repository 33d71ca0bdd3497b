//! # lustre-density
//!
//! The CPU side of García Hernández, Ureña & Lastra, "Real Time Global
//! Illumination for Quasi-Static Scenes" (2003): a static scene with mobile
//! objects, the two-level ray set of section 2.3, the three per-vertex density
//! estimators of section 1.2, and the frame-to-frame recalculation of section 2
//! that keeps them up to date as the mobile objects move. No GPU dependency;
//! `lustre-mpr`'s Gouraud pass draws the result.
//!
//! | paper | item |
//! |---|---|
//! | 2.2.2: a static scene and mobile objects (several allowed) | [`World`] |
//! | 2.3, figure 2.1: primary rays from the lights, each owning its reflections | [`RaySet`], [`PrimaryRay`], [`RaySegment`], [`trace_ray_set`], [`trace_ray_set_in`] |
//! | 2.3, figure 2.2: PHOTOSIMULATION RECALCULUS, OldRays and NewRays | [`update_ray_set`], [`RayUpdate`] (beyond the paper: its [`Twins`], re-traced segments that kept their origin, direction and power) |
//! | beyond the paper, for figure 2.2 and 2.5.2: per path, the cells of a coarse grid it passes, so that a frame visits only the paths near the mobile objects | [`path_cells::PathCells`], [`update_ray_set_paths`] |
//! | 2.4.2, equations 2.4–2.15: `E_t = E_{t-1} + E(N^t) − E(O^t)` on static vertices | [`QuasiStatic::set_pose`] |
//! | 2.5.1, figure 2.4: Impact Count's per-triangle `Add`/`Substract` | [`Estimator::ImpactCount`] |
//! | 2.5.2: the full estimate on the mobile objects' vertices | [`QuasiStatic::set_pose`] |
//! | 2.10: glossy vertices' ray lists updated with OldRays/NewRays, view-dependent radiance | [`QuasiStatic::glossy_radiance`] |
//! | 3.4.2: vertex-based calculation shared by triangles of different colours | [`EstimationPoints`] |
//! | 1.2.1, 2.6–2.8: ray cache with the sorted order reused, disc indexing tuned by radius, pre-intersection tests; a segment grid beyond the paper | [`DiscSet`], [`Acceleration`], [`PreTest`], [`SegmentGrid`] |
//! | 1.2, 2.5.1 Impact Count: impact energy per triangle over its area, vertex mean | [`impact_count`] |
//! | 1.2 Photon Maps (Jensen): `k` nearest impacts, `Σ φ / (π r_k²)`; beyond the paper, Jensen's normal filter and the disc's area taken on the vertex's surface (half on an edge, a quarter in a corner) | [`photon_maps`], [`KdTree`], [`boundary`] |
//! | 1.2 DETP: fixed-radius disc on the tangent plane, rays crossing it | [`detp`], [`Disc`] |
//! | 2.4, equation 2.2: `L_r = ρ/π E` | [`diffuse_radiance`] |
//! | 2.4, equation 2.8: contributions of rays are additive | every estimator sums per-ray terms |
//! | 1.2.1 Artifact Control: reachable area near walls and corners, rays followed through concave parts of the own mesh | [`artifact::reachable_areas`], [`artifact::extension`], [`artifact::artifact_controlled_detp`] |
//! | 2.10, equation 2.1 on the disc: per-vertex ray lists of glossy vertices, `L = Σ f_r φ / (π r²)` | [`glossy::GlossyVertex`], [`glossy::GlossyVertices`] |
//! | beyond the paper: the glossy discs larger than the diffuse ones, `L = ρ/π E(r) + Σ (f_r − ρ/π) φ / (π r_g²)` | [`QuasiStaticOptions::glossy_radius`], [`glossy::GlossyVertices::lobe_radiance`] |
//! | beyond the paper: artifact control's shortcuts, discs no other mesh comes near and convex meshes | [`triangle_grid::TriangleGrid`], [`artifact::reachable_area_near`], [`artifact::is_concave`] |
//! | 2.10, equation 2.1 with Impact Count and Photon Maps: each impact weighted by `f_r(ωi, ωo)`, over the vertex's triangles' area or the `k`-nearest disc's area on the surface (Jensen's radiance estimate); per-triangle lists updated with OldRays/NewRays | [`radiance::TriangleImpacts`], [`radiance::ImpactMap`], [`impact_count_radiance`], [`photon_maps_radiance`] |
//! | 2.10.1 QuadTree without summarising (exact) and with summarising (mean-direction update) | [`quadtree::QuadTree`], [`quadtree::SummaryTree`], [`quadtree::summary_degradation`] |
//!
//! Each photon's bounce `n` draws from its own random stream, so a path
//! recalculated from any of its rays is the path a full trace of the new pose
//! would give: the updated ray set equals a fresh trace exactly, and the
//! incremental irradiance equals the estimate from scratch up to rounding
//! (`tests/quasi_static.rs` checks both over random motions).
//!
//! All estimators return the irradiance `E` (W/m², RGB) at every vertex of
//! every mesh, indexed `[mesh][vertex]` ([`VertexIrradiance`]).
//!
//! ```
//! use lustre_geometry::{builtin, Bvh};
//! use lustre_density::{detp, impact_count, trace_ray_set, RaySetOptions};
//!
//! let scene = builtin("cornell").unwrap();
//! let bvh = Bvh::build(&scene);
//! let rays = trace_ray_set(&scene, &bvh, &RaySetOptions { photons: 2_000, ..Default::default() }).unwrap();
//! assert_eq!(rays.emitted(), 2_000);
//! let e_ic = impact_count(&scene, &rays);
//! let e_detp = detp(&scene, &rays, 0.2).unwrap();
//! assert_eq!(e_ic.len(), e_detp.len());
//! ```
//!
//! The quasi-static loop, with the small box of `cornell` mobile:
//!
//! ```
//! use glam::{Affine3A, Vec3};
//! use lustre_density::{Estimator, QuasiStatic, QuasiStaticOptions};
//! use lustre_geometry::builtin;
//!
//! let scene = builtin("cornell").unwrap();
//! let small = scene.object_by_name("small-box").unwrap();
//! let options = QuasiStaticOptions::new(Estimator::Detp { radius: 0.2 }, 2_000);
//! let mut sim = QuasiStatic::new(scene, &[small], options).unwrap();
//! let frame = sim.set_pose(&[(small, Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)))]).unwrap();
//! assert!(frame.recalculated > 0);
//! let e = sim.irradiance(); // [mesh][vertex], for the Gouraud pass
//! # assert_eq!(e.len(), sim.scene().meshes().len());
//! ```

pub mod accel;
pub mod artifact;
pub mod boundary;
mod detp;
mod error;
pub mod glossy;
mod impact_count;
pub mod kdtree;
pub mod path_cells;
mod photon_maps;
mod points;
pub mod quadtree;
mod quasi_static;
pub mod radiance;
mod ray_set;
pub mod triangle_grid;
mod update;
mod vertex_lit;
mod world;

pub use accel::{Acceleration, Crossings, DiscSet, DiscSetOptions, PreTest, SegmentGrid};
pub use detp::{Disc, detp, segment_meets_box};
pub use error::{DensityError, Result};
pub use impact_count::{impact_count, triangle_irradiance};
pub use kdtree::KdTree;
pub use photon_maps::photon_maps;
pub use points::{EstimationPoint, EstimationPoints};
pub use quasi_static::{Estimator, FrameStats, QuasiStatic, QuasiStaticOptions};
pub use radiance::{
    ImpactMap, MAX_RADIUS_FACTOR, NORMAL_FILTER_COSINE, TriangleImpacts, impact_count_radiance,
    photon_maps_radiance,
};
pub use ray_set::{
    PrimaryRay, RaySegment, RaySet, RaySetOptions, SegmentHit, trace_ray_set, trace_ray_set_in,
};
pub use update::{RayUpdate, Twins, twin_segments, update_ray_set, update_ray_set_paths};
pub use vertex_lit::vertex_lit_scene;
pub use world::{World, WorldHit};

/// Irradiance `E` (W/m², RGB) at each vertex of each mesh, indexed `[mesh][vertex]` (section 2.4.1, figure 2.3: one value per vertex).
pub type VertexIrradiance = Vec<Vec<lustre_geometry::Rgb>>;

/// The Lambertian reflectance of equation 2.2 at every vertex of mesh `mesh`, [`lustre_geometry::Material::diffuse_reflectance_at`] the vertex's texture coordinates (section 2.4.2: `B = ρ E` per vertex); empty for a mesh that does not exist.
pub fn vertex_reflectances(
    scene: &lustre_geometry::Scene,
    mesh: lustre_geometry::MeshId,
) -> Vec<lustre_geometry::Rgb> {
    let Some(m) = scene.meshes().get(mesh as usize) else {
        return Vec::new();
    };
    let Some(material) = scene.materials().get(m.material as usize) else {
        return vec![lustre_geometry::Rgb::ZERO; m.positions.len()];
    };
    if material.diffuse_map.is_none() {
        return vec![material.model.diffuse_reflectance(); m.positions.len()];
    }
    m.uvs
        .iter()
        .map(|&uv| material.diffuse_reflectance_at(uv))
        .collect()
}

/// Reflected radiance of a diffuse surface, `L_r = ρ/π E` (section 2.4.2, equation 2.2).
pub fn diffuse_radiance(
    reflectance: lustre_geometry::Rgb,
    irradiance: lustre_geometry::Rgb,
) -> lustre_geometry::Rgb {
    reflectance * irradiance * std::f32::consts::FRAC_1_PI
}
