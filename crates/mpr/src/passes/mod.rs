//! One module per pass, its WGSL beside it (DESIGN.md "Layout").

pub mod accumulate;
pub mod beams;
pub mod depth;
pub mod diffuse_texture;
pub mod direct;
pub mod emission;
pub mod glossy_image;
pub mod glossy_lobe;
pub mod glossy_reflection;
pub mod gouraud;
pub mod light_volume;
pub mod radiance_map;
pub mod redraw;
pub mod reflector_blend;
pub mod shadow;
pub mod shadow_volume;
pub mod shadowed_direct;
pub mod specular;
pub mod splat;
pub mod splat_lowres;
pub mod tonemap;
