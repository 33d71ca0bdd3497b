//! Procedural parts of the specular built-in scenes (Diefenbach & Badler 1997,
//! figures 1 and 16): quads, boxes, spheres and lathed solids, every closed
//! part a closed manifold with outward, consistent winding (section 4.1's
//! shadow volumes count silhouette faces of closed objects).

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::Mesh;

/// An empty mesh with a name and a material.
pub(crate) fn empty(name: &str, material: u32) -> Mesh {
    Mesh {
        name: name.to_owned(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        material,
    }
}

/// Appends `part` to `mesh` (indices shifted), keeping `mesh`'s name and material.
pub(crate) fn append(mesh: &mut Mesh, part: &Mesh) {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&part.positions);
    mesh.normals.extend_from_slice(&part.normals);
    mesh.uvs.extend_from_slice(&part.uvs);
    mesh.indices
        .extend(part.indices.iter().map(|t| t.map(|i| i + base)));
}

/// The quad `corner`, `corner + u`, `corner + u + v`, `corner + v` facing `u × v`, two triangles.
pub(crate) fn quad(name: &str, corner: Vec3, u: Vec3, v: Vec3, material: u32) -> Mesh {
    let normal = u.cross(v).normalize();
    Mesh {
        name: name.to_owned(),
        positions: vec![corner, corner + u, corner + u + v, corner + v],
        normals: vec![normal; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        indices: vec![[0, 1, 2], [2, 3, 0]],
        material,
    }
}

/// The axis-aligned box `[min, max]` with outward faces and flat normals
/// (12 triangles; faces do not share vertices, edges share positions).
pub(crate) fn cuboid(name: &str, min: Vec3, max: Vec3, material: u32) -> Mesh {
    let mut mesh = empty(name, material);
    let centre = 0.5 * (min + max);
    let half = 0.5 * (max - min);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            // Tangents with s × t = n: counter-clockwise seen from outside.
            let s = Vec3::AXES[(axis + 1) % 3] * sign;
            let t = n.cross(s);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                // Exactly min or max on each axis, so faces meet bit for bit.
                let corner = n + a * s + b * t;
                let p = Vec3::select(
                    corner.cmplt(Vec3::ZERO),
                    min,
                    Vec3::select(corner.cmpgt(Vec3::ZERO), max, centre),
                );
                debug_assert!((p - centre - corner * half).abs().max_element() < 1e-5);
                mesh.positions.push(p);
                mesh.normals.push(n);
                mesh.uvs.push(Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0)));
            }
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base + 2, base + 3, base]);
        }
    }
    mesh
}

/// A UV sphere of `radius` round `centre`: `slices` longitudes, `stacks`
/// latitude bands, triangle fans at the poles (no degenerate triangles),
/// smooth normals, outward.
pub(crate) fn sphere(
    name: &str,
    centre: Vec3,
    radius: f32,
    slices: u32,
    stacks: u32,
    material: u32,
) -> Mesh {
    let mut mesh = empty(name, material);
    let push = |mesh: &mut Mesh, n: Vec3, uv: Vec2| {
        mesh.positions.push(centre + radius * n);
        mesh.normals.push(n);
        mesh.uvs.push(uv);
    };
    push(&mut mesh, -Vec3::Y, Vec2::new(0.5, 0.0));
    for k in 1..stacks {
        let theta = PI * k as f32 / stacks as f32;
        let (y, r) = (-theta.cos(), theta.sin());
        for j in 0..slices {
            let phi = TAU * j as f32 / slices as f32;
            push(
                &mut mesh,
                Vec3::new(r * phi.cos(), y, r * phi.sin()),
                Vec2::new(j as f32 / slices as f32, k as f32 / stacks as f32),
            );
        }
    }
    push(&mut mesh, Vec3::Y, Vec2::new(0.5, 1.0));
    let top = mesh.positions.len() as u32 - 1;
    let ring = |k: u32, j: u32| 1 + (k - 1) * slices + j % slices;
    for j in 0..slices {
        // Longitude φ runs from +x to +z, counter-clockwise seen from below
        // (the outside of the bottom pole): the fans match the bands' edges.
        mesh.indices.push([0, ring(1, j), ring(1, j + 1)]);
        mesh.indices
            .push([top, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    for k in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b) = (ring(k, j), ring(k, j + 1));
            let (c, d) = (ring(k + 1, j + 1), ring(k + 1, j));
            mesh.indices.push([a, d, c]);
            mesh.indices.push([a, c, b]);
        }
    }
    mesh
}

/// The horizontal outline of a lathed solid: a rounded rectangle with
/// corner centres at `(±half.x, ±half.y)` (x and z) and corner radius
/// `radius`, or a circle of that radius when `half` is zero. Rings inset by
/// `d` keep the corner centres and have corner radius `radius - d`, so the
/// wall thickness is the same all round.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Outline {
    /// Centre of the outline (x, z).
    pub centre: Vec2,
    /// Half lengths of the straight sides (x, z); zero for a circle.
    pub half: Vec2,
    /// Corner radius of the outermost ring.
    pub radius: f32,
    /// Segments per quarter arc.
    pub arc_segments: u32,
    /// Longest segment along a straight side.
    pub side_step: f32,
}

impl Outline {
    /// The ring inset by `d`, counter-clockwise from +x towards +z.
    fn ring(&self, d: f32) -> Vec<Vec2> {
        let rho = self.radius - d;
        let corners = [
            Vec2::new(self.half.x, self.half.y),
            Vec2::new(-self.half.x, self.half.y),
            Vec2::new(-self.half.x, -self.half.y),
            Vec2::new(self.half.x, -self.half.y),
        ];
        let mut out = Vec::new();
        for q in 0..4 {
            for k in 0..self.arc_segments {
                let phi = FRAC_PI_2 * (q as f32 + k as f32 / self.arc_segments as f32);
                out.push(self.centre + corners[q] + rho * Vec2::new(phi.cos(), phi.sin()));
            }
            let end_dir = Vec2::from_angle(FRAC_PI_2 * (q + 1) as f32);
            let side = corners[(q + 1) % 4] - corners[q];
            let steps = if side.length() > 0.0 {
                (side.length() / self.side_step).ceil().max(1.0) as u32
            } else {
                0
            };
            for m in 0..steps {
                out.push(
                    self.centre + corners[q] + rho * end_dir + side * (m as f32 / steps as f32),
                );
            }
        }
        out
    }
}

/// A closed solid of revolution round a vertical axis over `outline`: the
/// profile `(inset, y)` runs from the outer bottom, up the outside, over the
/// top and down the inside, each point a ring of the outline inset by
/// `inset` at height `y`; the first ring is closed by a flat cap facing down,
/// the last by one facing up (triangle fans from the ring's centre). The
/// sides are smooth shaded, the caps flat. With the profile so ordered the
/// faces point out of the solid.
pub(crate) fn lathe(name: &str, outline: &Outline, profile: &[Vec2], material: u32) -> Mesh {
    let mut mesh = empty(name, material);
    let rings: Vec<Vec<Vec3>> = profile
        .iter()
        .map(|p| {
            outline
                .ring(p.x)
                .into_iter()
                .map(|q| Vec3::new(q.x, p.y, q.y))
                .collect()
        })
        .collect();
    let n = rings[0].len() as u32;
    let at = |i: u32, j: u32| i * n + j % n;
    for (i, ring) in rings.iter().enumerate() {
        for (j, &p) in ring.iter().enumerate() {
            mesh.positions.push(p);
            mesh.normals.push(Vec3::ZERO);
            mesh.uvs.push(Vec2::new(
                j as f32 / n as f32,
                i as f32 / (rings.len() - 1) as f32,
            ));
        }
    }
    for i in 0..rings.len() as u32 - 1 {
        for j in 0..n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            mesh.indices.push([a, d, c]);
            mesh.indices.push([a, c, b]);
        }
    }
    // Smooth normals: area-weighted sums of the faces round each vertex.
    for t in 0..mesh.indices.len() {
        let tri = mesh.indices[t];
        let [p0, p1, p2] = tri.map(|i| mesh.positions[i as usize]);
        let weighted = (p1 - p0).cross(p2 - p0);
        for i in tri {
            mesh.normals[i as usize] += weighted;
        }
    }
    for normal in &mut mesh.normals {
        *normal = normal.normalize();
    }
    // The caps, with their own flat-shaded vertices at the same positions.
    let last = rings.len() - 1;
    for (ring, down) in [(&rings[0], true), (&rings[last], false)] {
        let centre = ring.iter().copied().sum::<Vec3>() / ring.len() as f32;
        let normal = if down { -Vec3::Y } else { Vec3::Y };
        let base = mesh.positions.len() as u32;
        mesh.positions.push(centre);
        mesh.positions.extend_from_slice(ring);
        mesh.normals
            .extend(std::iter::repeat_n(normal, ring.len() + 1));
        mesh.uvs.push(Vec2::splat(0.5));
        mesh.uvs.extend(ring.iter().map(|p| {
            let d = (*p - centre).normalize_or_zero();
            Vec2::new(0.5 + 0.5 * d.x, 0.5 + 0.5 * d.z)
        }));
        for j in 0..n {
            let (p, q) = (base + 1 + j, base + 1 + (j + 1) % n);
            mesh.indices
                .push(if down { [base, p, q] } else { [base, q, p] });
        }
    }
    mesh
}

/// `mesh` under a rigid transform: positions and normals (the inverse
/// transpose) mapped; the winding stays outward for a rotation.
pub(crate) fn transformed(mut mesh: Mesh, xf: Affine3A) -> Mesh {
    let normal_matrix = Mat3::from(xf.matrix3).inverse().transpose();
    for p in &mut mesh.positions {
        *p = xf.transform_point3(*p);
    }
    for n in &mut mesh.normals {
        *n = (normal_matrix * *n).normalize();
    }
    mesh
}

/// A closed cylinder of `radius` from `a` to `b`, `segments` round,
/// `lengthwise` segments along its length.
pub(crate) fn cylinder(
    name: &str,
    a: Vec3,
    b: Vec3,
    radius: f32,
    segments: u32,
    lengthwise: u32,
    material: u32,
) -> Mesh {
    let length = a.distance(b);
    let outline = Outline {
        centre: Vec2::ZERO,
        half: Vec2::ZERO,
        radius,
        arc_segments: segments.div_ceil(4).max(1),
        side_step: 1.0,
    };
    let profile: Vec<Vec2> = (0..=lengthwise)
        .map(|k| Vec2::new(0.0, length * k as f32 / lengthwise as f32))
        .collect();
    let mesh = lathe(name, &outline, &profile, material);
    let rotation = glam::Quat::from_rotation_arc(Vec3::Y, (b - a) / length);
    transformed(mesh, Affine3A::from_rotation_translation(rotation, a))
}

/// Appends the flat quad `corners` (a loop) to `mesh`, wound so that it faces `outward`.
pub(crate) fn push_facing(mesh: &mut Mesh, corners: [Vec3; 4], outward: Vec3) {
    let [a, b, c, d] = corners;
    let corners = if (b - a).cross(c - a).dot(outward) >= 0.0 {
        [a, b, c, d]
    } else {
        [a, d, c, b]
    };
    let normal = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize();
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(corners);
    mesh.normals.extend([normal; 4]);
    mesh.uvs.extend([Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
    mesh.indices.push([base, base + 1, base + 2]);
    mesh.indices.push([base + 2, base + 3, base]);
}

/// A picture frame: the closed solid (genus one) between the axis-aligned
/// rectangles `outer` and `inner` (each `(min, max)` in the two axes after
/// `axis`, cyclically), from `depth.0` to `depth.1` along `axis`; 32
/// triangles, flat shaded, outward.
pub(crate) fn frame_solid(
    name: &str,
    axis: usize,
    depth: (f32, f32),
    outer: (Vec2, Vec2),
    inner: (Vec2, Vec2),
    material: u32,
) -> Mesh {
    let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
    let point = |uv: Vec2, d: f32| {
        let mut p = Vec3::ZERO;
        p[axis] = d;
        p[u_axis] = uv.x;
        p[v_axis] = uv.y;
        p
    };
    let corners =
        |(min, max): (Vec2, Vec2)| [min, Vec2::new(max.x, min.y), max, Vec2::new(min.x, max.y)];
    let (o, i) = (corners(outer), corners(inner));
    let (oc, ic) = (0.5 * (outer.0 + outer.1), 0.5 * (inner.0 + inner.1));
    let axis_dir = Vec3::AXES[axis];
    let mut mesh = empty(name, material);
    for k in 0..4 {
        let l = (k + 1) % 4;
        // Front and back: the trapezoid between outer edge k and inner edge k.
        for (d, facing) in [(depth.1, axis_dir), (depth.0, -axis_dir)] {
            push_facing(
                &mut mesh,
                [
                    point(o[k], d),
                    point(o[l], d),
                    point(i[l], d),
                    point(i[k], d),
                ],
                facing,
            );
        }
        // Outer side k faces away from the outer centre, inner side k towards the inner one.
        let out = point(0.5 * (o[k] + o[l]) - oc, 0.0);
        push_facing(
            &mut mesh,
            [
                point(o[k], depth.0),
                point(o[l], depth.0),
                point(o[l], depth.1),
                point(o[k], depth.1),
            ],
            out,
        );
        let into = point(ic - 0.5 * (i[k] + i[l]), 0.0);
        push_facing(
            &mut mesh,
            [
                point(i[k], depth.0),
                point(i[l], depth.0),
                point(i[l], depth.1),
                point(i[k], depth.1),
            ],
            into,
        );
    }
    mesh
}

/// `n + 1` coordinates from `a` to `b` in equal steps, exactly `a` and `b`
/// at the ends, so that parts built on the same edges meet bit for bit.
pub(crate) fn edges(a: f32, b: f32, n: u32) -> Vec<f32> {
    (0..=n)
        .map(|k| match k {
            0 => a,
            k if k == n => b,
            k => a + (b - a) * (k as f32 / n as f32),
        })
        .collect()
}

/// Axis-aligned rectangular cells in the plane where coordinate `axis` is
/// `at`: cell `(i, j)` spans `u_edges[i]..u_edges[i + 1]` and
/// `v_edges[j]..v_edges[j + 1]` along the two axes after `axis`
/// (cyclically), and is kept when `keep(i, j)`; two triangles each, facing
/// +`axis` when `positive`, else -`axis`, flat normals. Corners are taken
/// from the edges exactly, so cells of different meshes on the same edges
/// share their corners bit for bit.
#[allow(clippy::too_many_arguments)]
pub(crate) fn cells(
    name: &str,
    axis: usize,
    at: f32,
    u_edges: &[f32],
    v_edges: &[f32],
    positive: bool,
    keep: impl Fn(usize, usize) -> bool,
    material: u32,
) -> Mesh {
    let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
    let point = |u: f32, v: f32| {
        let mut p = Vec3::ZERO;
        p[axis] = at;
        p[u_axis] = u;
        p[v_axis] = v;
        p
    };
    let normal = if positive {
        Vec3::AXES[axis]
    } else {
        -Vec3::AXES[axis]
    };
    let mut mesh = empty(name, material);
    for i in 0..u_edges.len() - 1 {
        for j in 0..v_edges.len() - 1 {
            if !keep(i, j) {
                continue;
            }
            let (u0, u1, v0, v1) = (u_edges[i], u_edges[i + 1], v_edges[j], v_edges[j + 1]);
            // u × v is +axis: (u0 v0, u1 v0, u1 v1, u0 v1) winds counter-clockwise seen from +axis.
            let corners = [
                (point(u0, v0), Vec2::ZERO),
                (point(u1, v0), Vec2::X),
                (point(u1, v1), Vec2::ONE),
                (point(u0, v1), Vec2::Y),
            ];
            let base = mesh.positions.len() as u32;
            for (p, uv) in corners {
                mesh.positions.push(p);
                mesh.normals.push(normal);
                mesh.uvs.push(uv);
            }
            if positive {
                mesh.indices.push([base, base + 1, base + 2]);
                mesh.indices.push([base + 2, base + 3, base]);
            } else {
                mesh.indices.push([base, base + 2, base + 1]);
                mesh.indices.push([base + 2, base, base + 3]);
            }
        }
    }
    mesh
}

/// `mesh` without the triangles all of whose corners lie at its greatest
/// y: a box open at the top, for a lid that is a mesh of its own.
pub(crate) fn open_top(mut mesh: Mesh) -> Mesh {
    let top = mesh
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max);
    let positions = &mesh.positions;
    mesh.indices
        .retain(|t| !t.iter().all(|&i| positions[i as usize].y == top));
    mesh
}

/// A closed tube along the polyline `centres` (at least two points) with
/// radius `radii[k]` at `centres[k]`, `segments` round: rings square to the
/// curve, their zero angle along `side × tangent` (`side` must not be
/// along the curve; for a curve in a plane, the plane's normal), smooth
/// normals on the sides and flat caps at both ends, faces outward.
pub(crate) fn tube(
    name: &str,
    centres: &[Vec3],
    radii: &[f32],
    side: Vec3,
    segments: u32,
    material: u32,
) -> Mesh {
    let mut mesh = empty(name, material);
    let last = centres.len() - 1;
    let n = segments;
    let mut rings = Vec::with_capacity(centres.len());
    for (k, &c) in centres.iter().enumerate() {
        let (a, b) = (centres[k.saturating_sub(1)], centres[(k + 1).min(last)]);
        let t = (b - a).normalize();
        // t × (n × t) = n: the angle runs so that the quads below face out.
        let nx = side.cross(t).normalize();
        let ny = nx.cross(t);
        let ring: Vec<(Vec3, Vec3)> = (0..n)
            .map(|j| {
                let phi = TAU * j as f32 / n as f32;
                let d = phi.cos() * nx + phi.sin() * ny;
                (c + radii[k] * d, d)
            })
            .collect();
        rings.push((t, ring));
    }
    for (k, (_, ring)) in rings.iter().enumerate() {
        for (j, &(p, d)) in ring.iter().enumerate() {
            mesh.positions.push(p);
            mesh.normals.push(d);
            mesh.uvs.push(Vec2::new(
                j as f32 / n as f32,
                k as f32 / last.max(1) as f32,
            ));
        }
    }
    let at = |k: u32, j: u32| k * n + j % n;
    for k in 0..last as u32 {
        for j in 0..n {
            let (a, b, c, d) = (at(k, j), at(k, j + 1), at(k + 1, j + 1), at(k + 1, j));
            mesh.indices.push([a, d, c]);
            mesh.indices.push([a, c, b]);
        }
    }
    for (k, back) in [(0, true), (last, false)] {
        let (t, ring) = &rings[k];
        let normal = if back { -*t } else { *t };
        let base = mesh.positions.len() as u32;
        mesh.positions.push(centres[k]);
        mesh.normals.push(normal);
        mesh.uvs.push(Vec2::splat(0.5));
        for &(p, d) in ring {
            mesh.positions.push(p);
            mesh.normals.push(normal);
            mesh.uvs.push(Vec2::new(0.5 + 0.5 * d.x, 0.5 + 0.5 * d.z));
        }
        for j in 0..n {
            let (p, q) = (base + 1 + j, base + 1 + (j + 1) % n);
            mesh.indices
                .push(if back { [base, p, q] } else { [base, q, p] });
        }
    }
    mesh
}

/// Points of the cubic Bézier curve with control points `c`, at `steps + 1` equal parameter steps.
pub(crate) fn bezier(c: [Vec3; 4], steps: u32) -> Vec<Vec3> {
    (0..=steps)
        .map(|k| {
            let t = k as f32 / steps as f32;
            let s = 1.0 - t;
            s * s * s * c[0] + 3.0 * s * s * t * c[1] + 3.0 * s * t * t * c[2] + t * t * t * c[3]
        })
        .collect()
}

/// Appends triangle `t` (vertex indices of `mesh`), wound to face `outward`.
pub(crate) fn push_triangle(mesh: &mut Mesh, t: [u32; 3], outward: Vec3) {
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    if (b - a).cross(c - a).dot(outward) >= 0.0 {
        mesh.indices.push(t);
    } else {
        mesh.indices.push([t[0], t[2], t[1]]);
    }
}
