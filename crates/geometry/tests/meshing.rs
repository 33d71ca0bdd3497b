//! Tests of `lustre_geometry::meshing`: regular subdivision (counts, edge
//! lengths, area and volume, watertightness, attribute interpolation, errors)
//! and planar polygon triangulation (areas against the shoelace formula,
//! orientation, coverage, errors).

use std::collections::{HashMap, HashSet};

use glam::{Quat, Vec2, Vec3};
use lustre_geometry::meshing::{newell_normal, subdivide, subdivision_count, triangulate_polygon};
use lustre_geometry::{GeometryError, Mesh, triangle_area};
use proptest::prelude::*;

// ---------------------------------------------------------------------------
// Helpers, independent of the code under test.
// ---------------------------------------------------------------------------

/// A single triangle with smooth-looking normals and UVs that are an affine function of position.
fn triangle_mesh([a, b, c]: [Vec3; 3]) -> Mesh {
    let positions = vec![a, b, c];
    Mesh {
        name: "triangle".into(),
        normals: vec![
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, -0.6, 0.8),
        ],
        uvs: positions.iter().map(|&p| affine_uv(p)).collect(),
        positions,
        indices: vec![[0, 1, 2]],
        material: 0,
    }
}

/// The UV map used by [`triangle_mesh`]: linear interpolation must reproduce it exactly.
fn affine_uv(p: Vec3) -> Vec2 {
    Vec2::new(2.0 * p.x + 0.5 - p.z, p.y - p.x + 0.25 * p.z)
}

/// A closed box [0, 2] × [0, 1] × [0, 0.5] with 8 shared vertices and 12 outward triangles.
fn closed_box() -> Mesh {
    let size = Vec3::new(2.0, 1.0, 0.5);
    let positions: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) * size)
        .collect();
    let centre = size / 2.0;
    // Quads as corner bit patterns, counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1], // z = 0, facing -z
        [4, 5, 7, 6], // z = 1, facing +z
        [0, 1, 5, 4], // y = 0, facing -y
        [2, 6, 7, 3], // y = 1, facing +y
        [0, 4, 6, 2], // x = 0, facing -x
        [1, 3, 7, 5], // x = 1, facing +x
    ];
    let indices = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh {
        name: "box".into(),
        normals: positions
            .iter()
            .map(|&p| (p - centre).normalize())
            .collect(),
        uvs: positions.iter().map(|p| p.truncate()).collect(),
        positions,
        indices,
        material: 0,
    }
}

/// Signed volume enclosed by a closed mesh (divergence theorem, Σ a · (b × c) / 6).
fn signed_volume(mesh: &Mesh) -> f64 {
    mesh.indices
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Checks that every directed edge appears once and its reverse once: a closed, consistently oriented 2-manifold.
fn assert_watertight(mesh: &Mesh) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for tri in &mesh.indices {
        for k in 0..3 {
            *directed.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(u, v), &count) in &directed {
        assert_eq!(count, 1, "edge {u} -> {v} is used {count} times");
        assert_eq!(
            directed.get(&(v, u)),
            Some(&1),
            "edge {u} -> {v} has no twin: a crack or T-junction"
        );
    }
    // Euler characteristic of a sphere: V - E + F = 2.
    let used: HashSet<u32> = mesh.indices.iter().flatten().copied().collect();
    let (v, e, f) = (
        used.len() as i64,
        directed.len() as i64 / 2,
        mesh.indices.len() as i64,
    );
    assert_eq!(v - e + f, 2, "V - E + F = {v} - {e} + {f}");
}

/// Longest edge of any triangle.
fn longest_edge(mesh: &Mesh) -> f32 {
    mesh.indices
        .iter()
        .flat_map(|&tri| {
            let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .fold(0.0, f32::max)
}

// ---------------------------------------------------------------------------
// subdivide
// ---------------------------------------------------------------------------

#[test]
fn one_triangle_splits_into_n_squared() {
    let tri = [
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.2, 0.7, 0.0),
    ];
    let mesh = triangle_mesh(tri);
    let longest = longest_edge(&mesh);
    for n in 1..=7_u32 {
        // A target a little above longest / n gives exactly n segments.
        let target = longest / n as f32 * 1.001;
        assert_eq!(subdivision_count(&mesh, target).unwrap(), n);
        let fine = subdivide(&mesh, target).unwrap();
        fine.validate().unwrap();
        assert_eq!(
            fine.positions.len() as u32,
            (n + 1) * (n + 2) / 2,
            "n = {n}"
        );
        assert_eq!(fine.indices.len() as u32, n * n, "n = {n}");
        assert!(longest_edge(&fine) <= target * (1.0 + 1e-5));
        assert!((fine.area() - mesh.area()).abs() <= 1e-5 * mesh.area());
    }
}

#[test]
fn coarse_target_leaves_the_mesh_unchanged() {
    let mesh = closed_box();
    assert_eq!(subdivide(&mesh, 10.0).unwrap(), mesh);
    let empty = Mesh {
        indices: Vec::new(),
        ..closed_box()
    };
    assert_eq!(subdivide(&empty, 0.1).unwrap(), empty);
}

#[test]
fn subdivided_closed_box_stays_watertight() {
    let mesh = closed_box();
    assert_watertight(&mesh);
    let volume = signed_volume(&mesh);
    assert!(
        (volume - 1.0).abs() < 1e-6,
        "the test box is built inside out: {volume}"
    );
    for target in [0.9_f32, 0.3, 0.11] {
        let fine = subdivide(&mesh, target).unwrap();
        fine.validate().unwrap();
        assert_watertight(&fine);
        assert!(
            longest_edge(&fine) <= target * (1.0 + 1e-5),
            "target {target}"
        );
        assert!((fine.area() - mesh.area()).abs() <= 1e-4 * mesh.area());
        assert!((signed_volume(&fine) - volume).abs() <= 1e-5);
        // Points along shared edges are merged: no two vertices coincide.
        let distinct: HashSet<[u32; 3]> = fine
            .positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        assert_eq!(distinct.len(), fine.positions.len(), "duplicated vertices");
        // One n for the whole mesh: V = 8 + 18 (n - 1) + 12 (n - 1)(n - 2) / 2.
        let n = subdivision_count(&mesh, target).unwrap() as usize;
        assert_eq!(
            fine.positions.len(),
            8 + 18 * (n - 1) + 6 * (n - 1) * (n - 2)
        );
        assert_eq!(fine.indices.len(), 12 * n * n);
        assert!(fine.normals.iter().all(|v| (v.length() - 1.0).abs() < 1e-5));
    }
}

#[test]
fn flat_shaded_meshes_split_shared_edges_identically() {
    // Mesh::flat duplicates vertices per triangle; the edge points of the
    // two triangles along an edge must still coincide bit for bit.
    let shared = closed_box();
    let flat = Mesh::flat("flat box", &shared.positions, &shared.indices, 0);
    let fine = subdivide(&flat, 0.23).unwrap();
    fine.validate().unwrap();
    let key = |i: u32| fine.positions[i as usize].to_array().map(f32::to_bits);
    let mut directed: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
    for tri in &fine.indices {
        for k in 0..3 {
            *directed
                .entry((key(tri[k]), key(tri[(k + 1) % 3])))
                .or_default() += 1;
        }
    }
    for (&(u, v), &count) in &directed {
        assert_eq!(count, 1);
        assert_eq!(
            directed.get(&(v, u)),
            Some(&1),
            "geometric crack at {u:?} -> {v:?}"
        );
    }
    // Flat normals stay flat.
    for (t, tri) in fine.indices.iter().enumerate() {
        let geometric = fine.geometric_normal(t);
        for &i in tri {
            assert!(fine.normals[i as usize].distance(geometric) < 1e-5);
        }
    }
}

#[test]
fn attributes_are_interpolated_linearly() {
    let tri = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.5),
        Vec3::new(0.0, 1.0, 0.25),
    ];
    let mesh = triangle_mesh(tri);
    let fine = subdivide(&mesh, 0.1).unwrap();
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let normal = e1.cross(e2);
    for (i, &p) in fine.positions.iter().enumerate() {
        // The point stays in the triangle's plane; its barycentrics follow from
        // Cramer's rule and give the expected normal.
        assert!((p - tri[0]).dot(normal).abs() < 1e-5);
        let d = p - tri[0];
        let denom = normal.length_squared();
        let b1 = d.cross(e2).dot(normal) / denom;
        let b2 = e1.cross(d).dot(normal) / denom;
        let b0 = 1.0 - b1 - b2;
        assert!(
            b0 > -1e-5 && b1 > -1e-5 && b2 > -1e-5,
            "{p} is outside the triangle"
        );
        let want = (mesh.normals[0] * b0 + mesh.normals[1] * b1 + mesh.normals[2] * b2).normalize();
        assert!(fine.normals[i].distance(want) < 1e-5, "normal at {p}");
        assert!((fine.normals[i].length() - 1.0).abs() < 1e-5);
        assert!(fine.uvs[i].distance(affine_uv(p)) < 1e-5, "uv at {p}");
    }
    // Every sub-triangle keeps the orientation of its parent.
    for t in 0..fine.indices.len() {
        assert!(fine.geometric_normal(t).dot(normal.normalize()) > 0.999);
    }
}

#[test]
fn bad_targets_and_meshes_are_errors() {
    let mesh = closed_box();
    for target in [0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let result = subdivide(&mesh, target);
        assert!(
            matches!(result, Err(GeometryError::InvalidMesh { .. })),
            "target {target}: {result:?}"
        );
    }
    // More vertices than u32 indices can address: an error, not an allocation failure.
    assert!(matches!(
        subdivide(&mesh, 1e-6),
        Err(GeometryError::InvalidMesh { .. })
    ));
    let mut out_of_range = closed_box();
    out_of_range.indices.push([0, 1, 8]);
    assert!(subdivide(&out_of_range, 0.5).is_err());
    let mut nan = closed_box();
    nan.positions[3].y = f32::NAN;
    assert!(subdivide(&nan, 0.5).is_err());
    let mut short = closed_box();
    short.uvs.pop();
    assert!(subdivide(&short, 0.5).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_triangles_meet_the_target(
        corners in prop::array::uniform3(prop::array::uniform3(-3.0_f32..3.0)),
        fraction in 0.05_f32..1.5,
    ) {
        let tri = corners.map(Vec3::from_array);
        let mesh = triangle_mesh(tri);
        prop_assume!(triangle_area(tri) > 1e-3);
        let target = longest_edge(&mesh) * fraction;
        let fine = subdivide(&mesh, target).unwrap();
        let n = (longest_edge(&mesh) / target).ceil().max(1.0) as usize;
        prop_assert_eq!(fine.indices.len(), n * n);
        prop_assert!(longest_edge(&fine) <= target * (1.0 + 1e-5));
        prop_assert!((fine.area() - mesh.area()).abs() <= 1e-4 * mesh.area());
        let parent = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
        for t in 0..fine.indices.len() {
            prop_assert!(fine.geometric_normal(t).dot(parent) > 0.99);
        }
    }
}

// ---------------------------------------------------------------------------
// triangulate_polygon
// ---------------------------------------------------------------------------

/// Signed shoelace area of a 2D loop (positive when counter-clockwise).
fn shoelace(points: &[[f64; 2]]) -> f64 {
    let mut twice = 0.0;
    for i in 0..points.len() {
        let [x0, y0] = points[i];
        let [x1, y1] = points[(i + 1) % points.len()];
        twice += x0 * y1 - x1 * y0;
    }
    twice / 2.0
}

/// Crossing-number point-in-polygon test.
fn contains(points: &[[f64; 2]], [x, y]: [f64; 2]) -> bool {
    let mut inside = false;
    for i in 0..points.len() {
        let [xi, yi] = points[i];
        let [xj, yj] = points[(i + 1) % points.len()];
        if (yi > y) != (yj > y) && x < xi + (y - yi) * (xj - xi) / (yj - yi) {
            inside = !inside;
        }
    }
    inside
}

/// A placement of the plane z = 0 in space: a rotation then a translation.
#[derive(Clone, Copy, Debug)]
struct Placement {
    rotation: Quat,
    translation: Vec3,
}

impl Placement {
    fn identity() -> Self {
        Self {
            rotation: Quat::IDENTITY,
            translation: Vec3::ZERO,
        }
    }

    fn tilted() -> Self {
        Self {
            rotation: Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 1.1),
            translation: Vec3::new(3.0, -1.0, 2.0),
        }
    }

    fn place(&self, [x, y]: [f64; 2]) -> Vec3 {
        self.rotation * Vec3::new(x as f32, y as f32, 0.0) + self.translation
    }

    fn unplace(&self, p: Vec3) -> [f64; 2] {
        let q = self.rotation.inverse() * (p - self.translation);
        [f64::from(q.x), f64::from(q.y)]
    }
}

/// Triangulates a 2D polygon placed in space and checks it against the shoelace area,
/// the expected orientation and an independent inside test.
fn check_polygon(outline: &[[f64; 2]], holes: &[Vec<[f64; 2]>], placement: Placement) {
    let outline3: Vec<Vec3> = outline.iter().map(|&p| placement.place(p)).collect();
    let holes3: Vec<Vec<Vec3>> = holes
        .iter()
        .map(|h| h.iter().map(|&p| placement.place(p)).collect())
        .collect();
    let (vertices, triangles) = triangulate_polygon(&outline3, &holes3).unwrap();

    let signed = shoelace(outline);
    let want_area = signed.abs() - holes.iter().map(|h| shoelace(h).abs()).sum::<f64>();
    // The outline winds counter-clockwise around +z of its plane when its shoelace area is positive.
    let normal = placement.rotation * Vec3::Z * signed.signum() as f32;
    assert!(newell_normal(&outline3).normalize().distance(normal) < 1e-4);

    let inputs: Vec<Vec3> = outline3
        .iter()
        .chain(holes3.iter().flatten())
        .copied()
        .collect();
    assert!(
        vertices.iter().all(|v| inputs.contains(v)),
        "a vertex is not an input point"
    );
    let mut area = 0.0;
    for tri in &triangles {
        let [a, b, c] = tri.map(|i| vertices[i as usize]);
        let twice = (b - a).cross(c - a);
        assert!(
            twice.dot(normal) > 0.0,
            "triangle {tri:?} is not counter-clockwise"
        );
        area += f64::from(triangle_area([a, b, c]));
        let centroid = placement.unplace((a + b + c) / 3.0);
        assert!(
            contains(outline, centroid),
            "triangle {tri:?} is outside the outline"
        );
        assert!(
            holes.iter().all(|h| !contains(h, centroid)),
            "triangle {tri:?} is in a hole"
        );
    }
    assert!(
        (area - want_area).abs() <= 1e-5 * want_area,
        "triangles cover {area}, the polygon {want_area}"
    );
}

fn square() -> Vec<[f64; 2]> {
    vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
}

fn l_shape() -> Vec<[f64; 2]> {
    vec![
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 0.5],
        [0.5, 0.5],
        [0.5, 2.0],
        [0.0, 2.0],
    ]
}

#[test]
fn squares_l_shapes_and_holes() {
    for placement in [Placement::identity(), Placement::tilted()] {
        check_polygon(&square(), &[], placement);
        let clockwise: Vec<_> = square().into_iter().rev().collect();
        check_polygon(&clockwise, &[], placement);
        check_polygon(&l_shape(), &[], placement);
        // A square with a square hole, either winding.
        let outer = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]];
        let hole = vec![[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]];
        check_polygon(&outer, std::slice::from_ref(&hole), placement);
        let reversed: Vec<_> = hole.iter().rev().copied().collect();
        check_polygon(&outer, &[reversed], placement);
        // Two holes, one concave.
        let other = vec![
            [2.5, 0.5],
            [3.5, 0.5],
            [3.5, 2.5],
            [3.0, 2.5],
            [3.0, 1.0],
            [2.5, 1.0],
        ];
        check_polygon(&outer, &[hole.clone(), other], placement);
        // Collinear points along an edge, and a closing point equal to the first.
        let collinear = vec![
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.0, 0.0],
        ];
        check_polygon(&collinear, &[], placement);
    }
}

#[test]
fn square_triangulates_into_two_triangles() {
    let outline: Vec<Vec3> = square()
        .iter()
        .map(|&p| Placement::identity().place(p))
        .collect();
    let (vertices, triangles) = triangulate_polygon(&outline, &[]).unwrap();
    assert_eq!(vertices, outline);
    assert_eq!(triangles.len(), 2);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn star_shaped_polygons_cover_their_area(
        radii in prop::collection::vec(0.3_f64..1.0, 3..24),
        jitter in prop::collection::vec(0.0_f64..0.8, 24),
    ) {
        // Vertices at increasing angles around the origin: a simple polygon.
        let n = radii.len();
        let outline: Vec<[f64; 2]> = radii
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let angle = (i as f64 + jitter[i]) / n as f64 * std::f64::consts::TAU;
                [r * angle.cos(), r * angle.sin()]
            })
            .collect();
        check_polygon(&outline, &[], Placement::tilted());
    }
}

#[test]
fn bad_polygons_are_errors() {
    let place = |points: &[[f64; 2]]| -> Vec<Vec3> {
        points
            .iter()
            .map(|&p| Placement::tilted().place(p))
            .collect()
    };
    let square3 = place(&square());
    let fails = |outline: &[Vec3], holes: &[Vec<Vec3>], why: &str| match triangulate_polygon(
        outline, holes,
    ) {
        Err(error @ GeometryError::InvalidMesh { .. }) => assert!(
            error.to_string().contains(why),
            "expected an error about `{why}`, got `{error}`"
        ),
        other => panic!("expected an error about `{why}`, got {other:?}"),
    };
    // Too few points.
    fails(&[], &[], "distinct points");
    fails(&square3[..2], &[], "distinct points");
    fails(
        &[square3[0], square3[1], square3[1], square3[0]],
        &[],
        "distinct points",
    );
    // Not finite.
    let mut nan = square3.clone();
    nan[2].x = f32::NAN;
    fails(&nan, &[], "not finite");
    let mut inf = square3.clone();
    inf[1].z = f32::INFINITY;
    fails(&inf, &[], "not finite");
    // Not planar: one corner lifted by a tenth of the side.
    let mut lifted = square3.clone();
    lifted[2] += Placement::tilted().rotation * Vec3::Z * 0.1;
    fails(&lifted, &[], "not planar");
    // Collinear: no area.
    fails(
        &place(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
        &[],
        "no area",
    );
    // Self-intersecting: a bow tie, and a loop that crosses itself.
    let bow_tie = place(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]);
    fails(&bow_tie, &[], "intersects or touches itself");
    let crossed = place(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, -1.0], [0.0, 2.0]]);
    fails(&crossed, &[], "intersects or touches itself");
    // Touching itself: a vertex used twice, and a vertex on another edge.
    let twice = place(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [1.0, 1.0],
        [2.0, 2.0],
        [0.0, 2.0],
        [1.0, 1.0],
    ]);
    fails(&twice, &[], "coincides with point");
    let dent = place(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 0.0], [0.0, 1.0]]);
    fails(&dent, &[], "intersects or touches itself");
    let on_edge = place(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 0.0], [0.0, 4.0]]);
    fails(&on_edge, &[], "intersects or touches itself");
    // Holes that cross the outline, lie outside it, touch it, or are degenerate.
    let crossing = place(&[[0.5, 0.5], [1.5, 0.5], [1.5, 0.8], [0.5, 0.8]]);
    fails(&square3, &[crossing], "intersects or touches itself");
    let outside = place(&[[2.0, 2.0], [3.0, 2.0], [3.0, 3.0]]);
    fails(&square3, &[outside], "not inside the outline");
    let touching = place(&[[0.0, 0.0], [0.5, 0.2], [0.2, 0.5]]);
    fails(&square3, &[touching], "coincides with point");
    let degenerate = place(&[[0.2, 0.2], [0.4, 0.4]]);
    fails(&square3, &[degenerate], "distinct points");
    // A hole inside another hole.
    let big = place(&[[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]]);
    let small = place(&[[0.3, 0.3], [0.6, 0.3], [0.6, 0.6]]);
    fails(&square3, &[big, small], "inside hole");
}
