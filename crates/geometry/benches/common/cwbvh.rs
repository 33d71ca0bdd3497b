//! obvhs' compressed wide BVH as lustre-geometry built it before its
//! eight-wide BVH, for the baselines of the criterion bench `bvh` and the
//! example `embree_compare` (included with `#[path]`).

use lustre_geometry::WorldTriangle;
use obvhs::cwbvh::CwBvh;
use obvhs::triangle::Triangle;

/// obvhs' CWBVH over `triangles` with its medium settings, and the triangles in its leaf order (`primitive_indices`).
pub fn cwbvh(triangles: &[WorldTriangle]) -> (CwBvh, Vec<Triangle>) {
    let tris: Vec<Triangle> = triangles
        .iter()
        .map(|t| Triangle {
            v0: t.positions[0].into(),
            v1: t.positions[1].into(),
            v2: t.positions[2].into(),
        })
        .collect();
    let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
        &tris,
        obvhs::BvhBuildParams::medium_build(),
        &mut std::time::Duration::default(),
    );
    let ordered = bvh
        .primitive_indices
        .iter()
        .map(|&i| tris[i as usize])
        .collect();
    (bvh, ordered)
}
