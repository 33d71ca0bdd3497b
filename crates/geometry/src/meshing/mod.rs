//! Mesh utilities: regular subdivision for per-vertex lighting and planar
//! polygon triangulation.
//!
//! Vertex-lighting techniques store their result at mesh vertices, so the
//! mesh must be fine enough for the lighting's detail: García et al. mesh
//! their surfaces into 0.02 × 0.02 squares (section 2.9). [`subdivide`] splits
//! every triangle of a mesh regularly with one subdivision count for the
//! whole mesh, so the mesh stays watertight. [`triangulate_polygon`] turns a
//! planar outline with holes into triangles with spade's constrained Delaunay
//! triangulation.

mod polygon;
mod subdivide;

pub use polygon::{newell_normal, triangulate_polygon};
pub use subdivide::{subdivide, subdivision_count};
