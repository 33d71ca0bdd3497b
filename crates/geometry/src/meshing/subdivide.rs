//! Regular subdivision of triangle meshes.
//!
//! Every triangle is split into `n²` congruent sub-triangles on the grid
//! `a + (i/n)(b - a) + (j/n)(c - a)`, `i + j <= n` (the regular "1-to-n²"
//! split, as in uniform loop-free refinement; see Botsch et al., *Polygon
//! Mesh Processing*, 2010, section 6.1). One `n` serves the whole mesh, so an
//! edge shared by two triangles is split at the same points from both sides
//! and no T-junction appears.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use crate::{GeometryError, Mesh, Result};

/// The subdivision count `n = ceil(longest edge / target_edge)` (at least 1) that makes every edge at most `target_edge` long (García et al. section 2.9 mesh into 0.02 m squares).
///
/// Errors when `target_edge` is not positive and finite, when the mesh's
/// arrays disagree or hold non-finite positions, or when the result would need
/// more than `u32::MAX` vertices.
pub fn subdivision_count(mesh: &Mesh, target_edge: f32) -> Result<u32> {
    let bad = |message: String| GeometryError::InvalidMesh {
        mesh: mesh.name.clone(),
        message,
    };
    if !(target_edge.is_finite() && target_edge > 0.0) {
        return Err(bad(format!(
            "subdivision target edge length must be positive and finite, not {target_edge}"
        )));
    }
    mesh.validate_arrays()?;
    let longest = mesh
        .indices
        .iter()
        .flat_map(|tri| {
            let p = tri.map(|i| mesh.positions[i as usize].as_dvec3());
            [
                p[0].distance(p[1]),
                p[1].distance(p[2]),
                p[2].distance(p[0]),
            ]
        })
        .fold(0.0_f64, f64::max);
    let target = f64::from(target_edge);
    let mut n = (longest / target).ceil().max(1.0);
    if longest / n > target {
        n += 1.0;
    }
    // Vertices of the result: the corners, n - 1 per edge and
    // (n - 1)(n - 2) / 2 inside each triangle, bounded from above by counting
    // every triangle's edges as unshared.
    let triangles = mesh.indices.len() as f64;
    let bound = mesh.positions.len() as f64
        + 3.0 * triangles * (n - 1.0)
        + triangles * (n - 1.0) * (n - 2.0) / 2.0;
    if n > f64::from(u32::MAX) || bound > f64::from(u32::MAX) {
        return Err(bad(format!(
            "subdividing to edges of {target_edge} (n = {n}) would need more than {} vertices",
            u32::MAX
        )));
    }
    Ok(n as u32)
}

/// Whether vertex `u` comes before vertex `v` along their edge: by position (x, y, z), then by index.
///
/// Edge points are always interpolated from the first vertex to the second,
/// so two triangles that share an edge's positions but not its indices (a
/// flat-shaded mesh) still get bit-identical edge points.
fn precedes(mesh: &Mesh, u: u32, v: u32) -> bool {
    let (pu, pv) = (mesh.positions[u as usize], mesh.positions[v as usize]);
    let key = |p: Vec3| [p.x, p.y, p.z];
    let (ku, kv) = (key(pu), key(pv));
    for axis in 0..3 {
        match ku[axis].total_cmp(&kv[axis]) {
            std::cmp::Ordering::Less => return true,
            std::cmp::Ordering::Greater => return false,
            std::cmp::Ordering::Equal => {}
        }
    }
    u < v
}

/// The vertex attributes being built.
struct Builder<'a> {
    /// The input mesh.
    mesh: &'a Mesh,
    /// Output positions.
    positions: Vec<Vec3>,
    /// Output normals.
    normals: Vec<Vec3>,
    /// Output texture coordinates.
    uvs: Vec<Vec2>,
}

impl Builder<'_> {
    /// Appends the vertex with barycentric weights `w` of corners `tri`; `fallback` is used when the interpolated normal vanishes.
    fn push(&mut self, tri: [u32; 3], w: [f32; 3], fallback: Vec3) -> u32 {
        let index = self.positions.len() as u32;
        let m = self.mesh;
        let [a, b, c] = tri.map(|i| i as usize);
        self.positions
            .push(m.positions[a] * w[0] + m.positions[b] * w[1] + m.positions[c] * w[2]);
        let normal = m.normals[a] * w[0] + m.normals[b] * w[1] + m.normals[c] * w[2];
        self.normals.push(
            normal
                .try_normalize()
                .or_else(|| fallback.try_normalize())
                .unwrap_or(Vec3::Z),
        );
        self.uvs
            .push(m.uvs[a] * w[0] + m.uvs[b] * w[1] + m.uvs[c] * w[2]);
        index
    }
}

/// Splits every triangle into `n²` sub-triangles with `n = ceil(longest edge / target_edge)` for the whole mesh (regular 1-to-n² refinement; García et al. section 2.9 mesh surfaces into 0.02 m squares for per-vertex lighting).
///
/// Positions, normals and UVs are interpolated linearly; normals are
/// renormalised (a vanishing interpolated normal falls back to the triangle's
/// geometric normal). Corners keep their indices; the points inside an edge
/// are created once per pair of vertex indices, so a mesh that shares
/// indices stays shared and watertight. Every edge of the result is at most
/// `target_edge` long and each triangle keeps its orientation. With `n = 1`
/// the mesh comes back unchanged.
///
/// Errors as [`subdivision_count`] does.
pub fn subdivide(mesh: &Mesh, target_edge: f32) -> Result<Mesh> {
    let n = subdivision_count(mesh, target_edge)?;
    if n == 1 {
        return Ok(mesh.clone());
    }
    let n_us = n as usize;
    let inv_n = 1.0 / n as f32;
    let mut builder = Builder {
        mesh,
        positions: mesh.positions.clone(),
        normals: mesh
            .normals
            .iter()
            .map(|v| v.try_normalize().unwrap_or(Vec3::Z))
            .collect(),
        uvs: mesh.uvs.clone(),
    };
    // First index of the n - 1 points inside each edge, keyed by (first, second) in `precedes` order.
    let mut edge_points: HashMap<(u32, u32), u32> = HashMap::new();
    let mut indices = Vec::with_capacity(mesh.indices.len() * n_us * n_us);
    // Grid point (i, j) of the current triangle, row-major over i + j <= n.
    let row_start = |i: usize| i * (2 * n_us + 3 - i) / 2;
    let mut grid = vec![0_u32; (n_us + 1) * (n_us + 2) / 2];

    for (t, &tri) in mesh.indices.iter().enumerate() {
        let fallback = mesh.geometric_normal(t);
        // Index of the point `step` of n along the edge from corner u to corner v.
        let mut edge_point = |builder: &mut Builder, u: u32, v: u32, step: usize| -> u32 {
            let (first, second) = if precedes(mesh, u, v) { (u, v) } else { (v, u) };
            let start = *edge_points.entry((first, second)).or_insert_with(|| {
                let start = builder.positions.len() as u32;
                for k in 1..n_us {
                    let w = k as f32 * inv_n;
                    builder.push([first, second, second], [1.0 - w, w, 0.0], fallback);
                }
                start
            });
            let k = if first == u { step } else { n_us - step };
            start + (k - 1) as u32
        };
        let [a, b, c] = tri;
        for i in 0..=n_us {
            for j in 0..=(n_us - i) {
                let index = match (i, j) {
                    (0, 0) => a,
                    (i, 0) if i == n_us => b,
                    (0, j) if j == n_us => c,
                    (i, 0) => edge_point(&mut builder, a, b, i),
                    (0, j) => edge_point(&mut builder, a, c, j),
                    (i, j) if i + j == n_us => edge_point(&mut builder, b, c, j),
                    (i, j) => {
                        let wb = i as f32 * inv_n;
                        let wc = j as f32 * inv_n;
                        builder.push(tri, [1.0 - wb - wc, wb, wc], fallback)
                    }
                };
                grid[row_start(i) + j] = index;
            }
        }
        let at = |i: usize, j: usize| grid[row_start(i) + j];
        for i in 0..n_us {
            for j in 0..(n_us - i) {
                indices.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                if i + j + 1 < n_us {
                    indices.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
    }
    Ok(Mesh {
        name: mesh.name.clone(),
        positions: builder.positions,
        normals: builder.normals,
        uvs: builder.uvs,
        indices,
        material: mesh.material,
    })
}
