//! # lustre-density
//!
//! The CPU estimators of García Hernández, Ureña & Lastra, "Real Time
//! Global Illumination for Quasi-Static Scenes" (2003), on a static
//! scene: the two-level ray set of section 2.3 and the three per-vertex
//! density estimators of section 1.2, computed as in the first frame of
//! section 2.4.1 (figure 2.3). No GPU dependency.
//!
//! | paper | item |
//! |---|---|
//! | 2.3, figure 2.1: primary rays from the lights, each owning its reflections | [`RaySet`], [`PrimaryRay`], [`RaySegment`], [`trace_ray_set`] |
//! | 1.2, 2.5.1 Impact Count: impact energy per triangle over its area, vertex mean | [`impact_count`] |
//! | 1.2 Photon Maps (Jensen): `k` nearest impacts, `Σ φ / (π r_k²)` | [`photon_maps`], [`KdTree`] |
//! | 1.2 DETP: fixed-radius disc on the tangent plane, rays crossing it | [`detp`], [`Disc`] |
//! | 2.4, equation 2.2: `L_r = ρ/π E` | [`diffuse_radiance`] |
//! | 2.4, equation 2.8: contributions of rays are additive | every estimator sums per-ray terms |
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

pub mod accel;
mod detp;
mod error;
mod impact_count;
pub mod kdtree;
mod photon_maps;
mod ray_set;

pub use accel::{Acceleration, DiscSet, DiscSetOptions, PreTest, SegmentGrid};
pub use detp::{Disc, detp};
pub use error::{DensityError, Result};
pub use impact_count::{impact_count, triangle_irradiance};
pub use kdtree::KdTree;
pub use photon_maps::photon_maps;
pub use ray_set::{PrimaryRay, RaySegment, RaySet, RaySetOptions, SegmentHit, trace_ray_set};

/// Irradiance `E` (W/m², RGB) at each vertex of each mesh, indexed `[mesh][vertex]` (section 2.4.1, figure 2.3: one value per vertex).
pub type VertexIrradiance = Vec<Vec<lustre_geometry::Rgb>>;

/// Reflected radiance of a diffuse surface, `L_r = ρ/π E` (section 2.4.2, equation 2.2).
pub fn diffuse_radiance(
    reflectance: lustre_geometry::Rgb,
    irradiance: lustre_geometry::Rgb,
) -> lustre_geometry::Rgb {
    reflectance * irradiance * std::f32::consts::FRAC_1_PI
}
