//! WGSL twins of the Rust BRDFs, exported as source text for a GPU crate to include (no wgpu dependency here).
//!
//! `BRDF_WGSL` defines, in the local shading frame (+Z normal, directions
//! pointing away from the surface, `f` without the cosine):
//! `brdf_lambert`, `brdf_modified_phong`, `brdf_diefenbach_phong`,
//! `brdf_ward_isotropic` and `brdf_cook_torrance_beckmann` (Smith G,
//! conductor Fresnel), each matching its Rust model
//! ([`crate::models::Lambert`], [`crate::models::ModifiedPhong`],
//! [`crate::models::DiefenbachPhong`], [`crate::models::Ward`] with the
//! original normalisation and αx = αy, [`crate::models::CookTorrance`] with
//! Beckmann D, Smith G and [`crate::Fresnel::Conductor`]). It declares no
//! bindings or entry points, so it can be prepended to any module.

/// The WGSL BRDF module (`src/shaders/brdf.wgsl`).
pub const BRDF_WGSL: &str = include_str!("shaders/brdf.wgsl");
