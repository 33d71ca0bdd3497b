//! Area-weighted vertex normals that respect a crease angle.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::Part;

/// Tolerance on the cosine so that faces exactly at the crease angle are smoothed.
const COS_TOLERANCE: f32 = 1e-6;

/// Generates per-corner normals and splits vertices where they differ.
///
/// The normal at corner `k` of triangle `t` is the normalised sum of
/// `(b - a) × (c - a)` (twice the area times the unit normal) over the
/// triangles `f` that touch the corner's position (matched by value) with
/// `n_f · n_t >= cos(crease)`; `t` itself is always one of them. Corners of
/// one input vertex whose normals come out equal share an output vertex.
/// The triangles must not be degenerate.
pub(super) fn crease_normals(
    positions: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
    crease_degrees: f32,
) -> Part {
    let cos_crease = crease_degrees.to_radians().cos() - COS_TOLERANCE;
    let weighted: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    let unit: Vec<Vec3> = weighted.iter().map(|w| w.normalize_or_zero()).collect();

    // Group vertices by position value (+0.0 turns -0.0 into 0.0).
    let mut group_of_position: HashMap<[u32; 3], u32> = HashMap::new();
    let group: Vec<u32> = positions
        .iter()
        .map(|&p| {
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = group_of_position.len() as u32;
            *group_of_position.entry(key).or_insert(next)
        })
        .collect();
    let mut incident: Vec<Vec<u32>> = vec![Vec::new(); group_of_position.len()];
    for (t, tri) in triangles.iter().enumerate() {
        for &i in tri {
            let list = &mut incident[group[i as usize] as usize];
            if list.last() != Some(&(t as u32)) {
                list.push(t as u32);
            }
        }
    }

    let mut part = Part::default();
    let mut vertex_of: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        let corners = tri.map(|i| {
            let mut sum = Vec3::ZERO;
            for &f in &incident[group[i as usize] as usize] {
                if unit[f as usize].dot(unit[t]) >= cos_crease {
                    sum += weighted[f as usize];
                }
            }
            let mut normal = sum.normalize_or_zero();
            if normal == Vec3::ZERO {
                normal = unit[t];
            }
            *vertex_of
                .entry((i, normal.to_array().map(f32::to_bits)))
                .or_insert_with(|| {
                    part.positions.push(positions[i as usize]);
                    part.normals.push(normal);
                    part.uvs.push(uvs[i as usize]);
                    (part.positions.len() - 1) as u32
                })
        });
        part.indices.push(corners);
    }
    part
}
