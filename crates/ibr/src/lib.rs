//! Radiance maps with depth for glossy planar reflections: R. Bastos, K. Hoff, W. Wynn and A. Lastra, "Increased photorealism for interactive architectural walkthroughs", I3D 1999.
//!
//! The view-dependent term of the paper's shading equation 2,
//! `L = kd D + ks (M * K) R`, split into "what is reflected" (M, this
//! crate's radiance maps) and "how it is reflected" (K and R, from
//! `lustre-brdf`: [`lustre_brdf::kernel_texture`] and
//! [`lustre_brdf::reflectance_modulation`], re-exported here):
//!
//! - [`reflector`]: planar reflectors and their reflector elements;
//! - [`sampling`]: cameras on each element's hemisphere, off-axis frusta;
//! - [`radiance_map`]: radiance and depth per texel, captured from a
//!   [`radiance_map::RadianceSource`];
//! - [`quadtree`]: nodes of bounded depth range with representative points;
//! - [`selection`]: the minimal-angle and distance-based selections;
//! - [`reprojection`]: points into the reflected view, sized by equation 3,
//!   and their zero-order reconstruction;
//! - [`reflector_maps`]: one reflector's maps and their memory (table 1);
//! - [`cache`]: the versioned, checksummed cache file.
//!
//! Everything here runs on the CPU and is the reference of the GPU passes
//! of `lustre-mpr`.

pub mod cache;
mod error;
pub mod quadtree;
pub mod radiance_map;
pub mod reflector;
pub mod reflector_maps;
pub mod reprojection;
pub mod sampling;
pub mod selection;
pub mod view;

pub use error::{IbrError, Result};
pub use lustre_brdf::{kernel_texture, reflectance_modulation};
pub use quadtree::{MapQuadtree, QuadtreeSettings};
pub use radiance_map::{RadianceMap, RadianceSource};
pub use reflector::{Reflector, ReflectorElement};
pub use reflector_maps::{MemoryReport, ReflectorMaps};
pub use reprojection::{PointSizing, ProjectedPoint, ReflectedImage, reconstruct, reproject};
pub use sampling::{SampleCamera, SamplingSettings};
pub use selection::{SelectionRule, select};
pub use view::PinholeView;
