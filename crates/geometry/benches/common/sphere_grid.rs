//! The benches' large scene, shared by the criterion bench `bvh` and the
//! example `embree_compare` (included with `#[path]`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use lustre_geometry::WorldTriangle;

/// 64 UV spheres of 64×64 segments (8,064 triangles each) on a 4×4×4 grid.
pub fn sphere_grid() -> Vec<WorldTriangle> {
    let (rings, segments) = (64, 64);
    let mut out = Vec::new();
    for cell in 0..64 {
        let centre = Vec3::new(
            (cell % 4) as f32,
            ((cell / 4) % 4) as f32,
            (cell / 16) as f32,
        ) * 2.5;
        let point = |ring: u32, seg: u32| {
            let theta = PI * ring as f32 / rings as f32;
            let phi = 2.0 * PI * seg as f32 / segments as f32;
            Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
        };
        for ring in 0..rings {
            for seg in 0..segments {
                let [a, b, c, d] = [
                    point(ring, seg),
                    point(ring + 1, seg),
                    point(ring + 1, seg + 1),
                    point(ring, seg + 1),
                ];
                let quads: &[[Vec3; 3]] = if ring == 0 {
                    &[[a, b, c]]
                } else if ring == rings - 1 {
                    &[[a, b, d]]
                } else {
                    &[[a, b, c], [a, c, d]]
                };
                for tri in quads {
                    out.push(WorldTriangle {
                        positions: tri.map(|p| centre + p),
                        normals: *tri,
                        uvs: [Vec2::ZERO; 3],
                        surface: cell,
                        material: 0,
                    });
                }
            }
        }
    }
    out
}
