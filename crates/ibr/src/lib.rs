//! Radiance maps with depth for glossy planar reflections: R. Bastos, K. Hoff, W. Wynn and A. Lastra, "Increased photorealism for interactive architectural walkthroughs", I3D 1999.
//!
//! The view-dependent term of the paper's shading equation 2,
//! `L = kd D + ks (M * K) R`, splits into "what is reflected" (M, this
//! crate's radiance maps) and "how it is reflected" (K and R, from
//! `lustre-brdf`, re-exported here as [`kernel_texture`] and
//! [`reflectance_modulation`]).
//!
//! | paper | item |
//! |---|---|
//! | 8.1.3 sampling, first stage: reflector elements at a planar resolution | [`reflector::Reflector::elements`] |
//! | 8.1.3 sampling: hemispheres, cameras at evenly spaced arc lengths, off-axis frusta through the element | [`sampling`] ([`sampling::hemisphere_directions`], [`SampleCamera`]) |
//! | 8.1.3 radiance maps with depth | [`radiance_map::RadianceMap::capture`] from a [`RadianceSource`] |
//! | 8.1.3 quadtree: depth range or minimum count, representative point, frustum culling | [`quadtree`] |
//! | 8.1.3 selection: minimal angle, distance-based, k best | [`selection`] |
//! | 8.1.3 reprojection of 3D points | [`reprojection::reproject`], [`view::PinholeView`] |
//! | 8.1.3 equation 3, point size and step size | [`reprojection::point_size_terms`], [`reprojection::LeafDraw`] |
//! | 8.1.3 reconstruction: zero-order boxes | [`reprojection::reconstruct`] |
//! | 8.2.1 kernel texture K from D G | [`kernel_texture::KernelTexture`] (lustre-brdf) |
//! | 8.2.2 reflectance sphere map R = F / (π (N·L)(N·V)) | [`reflectance_modulation::reflectance_sphere_map`] (lustre-brdf) |
//! | 9 the 1D table, flipped indexing | [`reflectance_modulation::FlippedRadialReflectance`] (lustre-brdf) |
//! | 8.2.1 convolution `M * K` over the stencilled region, kernel size from the reflected distance | [`glossy::kernel_radius`], [`glossy::pixel_kernel`], [`glossy::convolve`] |
//! | 8.2.2 modulation by R per pixel | [`glossy::modulate`] |
//! | 9 table 1, memory per reflector | [`reflector_maps::ReflectorMaps::memory`] |
//! | 6 preprocessing kept between runs | [`cache`] |
//! | 2 reflected images at a resolution chosen from the glossiness | [`resolution`] |
//! | 9 the kernel sized by depth ("the more accurate method") | [`glossy::convolve_by_depth`] |
//!
//! Everything here runs on the CPU and is the reference of the GPU passes
//! of `lustre-mpr` (`passes::radiance_map`, `passes::glossy_reflection`,
//! `passes::reflector_blend`); the capture on the GPU and the terms in the
//! frame are `lustre_mpr::ibr`.

pub mod cache;
mod error;
pub mod glossy;
pub mod quadtree;
pub mod radiance_map;
pub mod reflector;
pub mod reflector_maps;
pub mod reprojection;
pub mod resolution;
pub mod sampling;
pub mod selection;
pub mod view;

pub use error::{IbrError, Result};
pub use lustre_brdf::{kernel_texture, reflectance_modulation};
pub use quadtree::{MapQuadtree, QuadtreeSettings};
pub use radiance_map::{RadianceMap, RadianceSource};
pub use reflector::{Reflector, ReflectorElement};
pub use reflector_maps::{MemoryReport, ReflectorMaps};
pub use reprojection::{
    LeafDraw, PointSizing, ProjectedPoint, ReflectedImage, leaf_draws, reconstruct, reproject,
};
pub use sampling::{SampleCamera, SamplingSettings};
pub use selection::{SelectionRule, select};
pub use view::PinholeView;
