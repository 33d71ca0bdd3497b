//! # lustre-beams
//!
//! Backward polygon beam tracing on the CPU after B. Duvenhage, K. Bouatouch
//! and D. G. Kourie, "Exploring the use of glossy light volumes for
//! interactive global illumination", Afrigraph 2010: from each point light
//! through each scatterer triangle, a scattered beam (reflected or refracted
//! vertex rays) carrying the flux `Φ_s = I_light Ω_light`, and a negative
//! shadow beam; a fragment's irradiance from a specular beam is
//! `E = Φ_s / A_⊥ cos θ` (equation 1), from a glossy one
//! `E = Φ_s / A_⊥ cos θ min(P_E, 1)` with `P_E` the volume under the
//! scatter Gaussian over the triangular domain ABC (section 4.2). No GPU
//! dependency; lustre-mpr's beam pass evaluates the same beams per fragment
//! on the GPU (its WGSL mirrors [`Beam::arrival`]).
//!
//! | paper | item |
//! |---|---|
//! | 3.1, 4.3: rays from the light through the scatterer's vertices, reflected, refracted and shadow rays grouped into beams, in parallel | [`build_beams`], [`BeamSet::build`], [`reflect`], [`refract`] |
//! | 3.1: beam flux conserved within the beam; 4.1: `Φ_s = I_light Ω_light` | [`Beam::flux`], [`solid_angle`], [`scatterer_flux`] |
//! | 3.1, figure 5: flux plane perpendicular to the average wavefront normal, flux triangle `A_F B_F C_F` | [`Beam::flux_triangle`], [`FluxTriangle`] |
//! | 3.1: the fragment-in-beam test; 4.3: generator plane | [`Beam::contains`], [`Beam::in_front`] |
//! | 4.1, equation 1: `E = Φ_s / A_⊥ cos θ` | [`Beam::irradiance`] (specular beams) |
//! | 4.2.1: the map from world space to the 2D triangular domain ABC, `A = φ_a l_a` | [`Beam::scatter_volume`] |
//! | 4.2.2, figures 11 and 12: `P_E` from AOB, BOC, COA, the split point D outside | [`lustre_brdf::scatter_distribution::ScatterDistribution::triangle_volume_split`], [`SplitPoint`] |
//! | 4.2, equation 5, figure 11 step 3: `E = Φ_s / A_⊥ cos θ min(P_E, 1)` | [`Beam::irradiance`] (glossy beams) |
//! | 4.2.2's "better approximation" of the volume (beyond the paper): the Gaussian integrated over ABC | [`GlossyVolume::Integrated`] |
//! | 1.2: σ from the micro-facet variance | [`ScatterMaterial`], `ScatterDistribution::from_beckmann_alpha{,_refracted,_thin_slab}` |
//! | 3.1: negative shadow beams, first-order shadows | [`BeamKind::Shadow`], [`BeamSet::direct_irradiance`] |
//! | 4.3: linear traversal of all beams per fragment | [`BeamSet::irradiance_at_linear`] |
//! | 5.2 (future work): a beam hierarchy | [`BeamHierarchy`], [`BeamSet::irradiance_at`] |
//!
//! Choices where the paper is silent:
//!
//! - Only point lights start beams (isotropic, cosine and spot lights);
//!   `Φ_s = I_light Ω_light` is exact for an isotropic light, and for a
//!   cosine light the cosine is integrated over the scatterer
//!   ([`scatterer_flux`]: a large mirror beside an area light's centre
//!   spans grazing directions, and the intensity towards its centroid
//!   times its solid angle sent up to twice the light's power through it);
//!   a spot light's intensity is taken towards the centroid. Area lights are
//!   ignored and counted ([`BeamInput::area_lights_ignored`]): convert them
//!   first with `Scene::with_area_lights_as_points`.
//! - Reflectors scatter from the front only (section 3.1, local
//!   visibility); dielectric interfaces from either side. A dielectric gives
//!   a reflected beam (Fresnel F at the centroid's incidence angle) and a
//!   refracted one (`1 - F`); if any vertex ray is totally internally
//!   reflected the triangle has no refracted beam (clipping the beam at the
//!   critical angle is left out) and is counted.
//! - A closed glass slab (a dielectric mesh whose planar face has a
//!   parallel, opposite face behind it, `lustre_geometry::slab`) is one
//!   thin slab, not two interfaces: single-scatter beams without second-order
//!   shadows would send the light through it twice, once refracted at the
//!   face it enters and once at the face it leaves, which is lit "from
//!   either side". Its faces scatter as a thin slab from outside only
//!   ([`Scatterer::slab_face`]); the beam leaves the lateral offset out.
//! - `cos θ` uses the vertex directions interpolated at the fragment's
//!   barycentrics in the flux triangle (clamped to the triangle outside it).
//! - Glossy beams are cut off [`glossy_cutoff`] σ (as an angle) outside
//!   their specular beam, the edges of the beam moved out by that angle
//!   ([`Beam::support`]), at most 85° from the mean direction: far enough
//!   that the dropped planar-facet volume is below
//!   [`BuildOptions::glossy_epsilon`] (1e-3) over any domain.
//! - The split point D of figure 12 ([`SplitPoint`]): the paper takes
//!   `D_W` at the flux-plane parameter s of `D_F` on the scatterer's edge;
//!   the default re-scatters from the edge point whose ray meets `D_F`
//!   instead, which keeps `P_E` continuous across the flux triangle's edges
//!   (section 4.2.2 asks for it; the paper's choice steps there by about
//!   0.3 % of E at α = 0.2). A D on the 2D domain's straight edge
//!   ([`SplitPoint::Domain`]) is also continuous and within about 1 % of
//!   the default.
//! - Transmission through a window pane (`thin-dielectric`) is a thin slab:
//!   rays go straight through with `T = (1 - F)/(1 + F)`, the reflected beam
//!   carries `R = 2F/(1 + F)`; its glossy spread is that of two rough faces,
//!   `σ² = (η - 1)² α²`; one rough interface spreads `σ² = (1 - 1/η)² α²/2`,
//!   a reflector `σ² = 2α²` (`lustre-brdf`'s scatter distribution).
//! - Adjacent beams of a mesh with smooth vertex normals share their edge
//!   rays, but each tests containment in its own flux plane, so the two
//!   boundaries of a shared edge need not coincide (the warped volumes of
//!   section 3); in `pool` the mismatch is below what 20 000 random floor
//!   points find (each lies in exactly one refracted beam,
//!   `tests/scenes.rs`), though a point exactly on a shared edge can be
//!   missed. Shadow beams (one apex, the light) and the reflected beams of
//!   coplanar mirror triangles (one apex, the light's image) tile exactly;
//!   differently tilted flat facets open real gaps and overlaps, as a
//!   faceted mirror does.
//! - The hierarchy covers the scene's box; points outside it are evaluated
//!   by the linear traversal, so [`BeamSet::irradiance_at`] equals
//!   [`BeamSet::irradiance_at_linear`] everywhere.
//!
//! ```
//! use glam::Vec3;
//! use lustre_beams::{BeamSet, BuildOptions, PointSource, ScatterMaterial, Scatterer};
//! use lustre_geometry::{Aabb, Rgb};
//!
//! let light = PointSource::isotropic(Vec3::new(0.0, 2.0, 0.0), Rgb::splat(10.0));
//! let mirror = Scatterer::flat(
//!     [Vec3::new(-0.5, 0.0, 0.5), Vec3::new(0.5, 0.0, 0.5), Vec3::new(0.0, 0.0, -0.5)],
//!     ScatterMaterial::Reflector { reflectance: Rgb::ONE, conductor: None, roughness: 0.0 },
//! );
//! let bounds = Aabb { min: Vec3::splat(-4.0), max: Vec3::splat(4.0) };
//! let beams = BeamSet::build(&[light], &[mirror], bounds, &BuildOptions::default()).unwrap();
//! // Above the mirror, looking down: lit by the mirror image of the light at y = -2.
//! let p = Vec3::new(0.0, 1.0, 0.0);
//! let e = beams.irradiance_at(p, -Vec3::Y);
//! assert!((e.x - 10.0 / 9.0).abs() < 0.05);
//! ```

mod beam;
mod beam_set;
mod construction;
mod error;
mod hierarchy;
mod scatterer;

pub use beam::{Beam, BeamKind, BeamSlab, FluxTriangle, GlossyVolume, Scatter, SplitPoint};
pub use beam_set::{BeamSet, direct_irradiance};
pub use construction::{
    BuildOptions, BuildStats, build_beams, glossy_cutoff, projected_solid_angle, reflect, refract,
    scatterer_flux, solid_angle,
};
pub use error::{BeamError, Result};
pub use hierarchy::{BeamHierarchy, HierarchyNode};
pub use scatterer::{
    BeamInput, Emission, PointSource, ScatterMaterial, Scatterer, THIN_DIELECTRIC,
};
