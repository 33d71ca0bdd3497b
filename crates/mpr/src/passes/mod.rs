//! One module per pass, its WGSL beside it (DESIGN.md "Layout").

pub mod depth;
pub mod tonemap;
