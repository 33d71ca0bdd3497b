//! Triangulation of planar polygons with holes.
//!
//! The polygon is projected onto its best-fit plane, whose normal is Newell's
//! (M. E. Newell; see F. Tampieri, "Newell's Method for Computing the Plane
//! Equation of a Polygon", Graphics Gems III, 1992), and triangulated with
//! spade's constrained Delaunay triangulation (L. P. Chew, "Constrained
//! Delaunay triangulations", Algorithmica 4, 1989) with the outline and the
//! holes as constraint edges. Triangles are kept by the parity of the number
//! of constraint edges crossed on the way from outside the convex hull (the
//! even-odd rule), so exactly those inside the outline and outside every hole
//! remain.

use glam::{DVec3, Vec3};
use spade::handles::FixedFaceHandle;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::sampling::Frame;
use crate::{GeometryError, Result};

/// Largest distance of a vertex from the best-fit plane, relative to the diagonal of the polygon's bounding box.
const PLANARITY_TOLERANCE: f64 = 1e-4;

/// Smallest polygon area, relative to the squared bounding-box diagonal, below which the outline counts as degenerate.
const AREA_TOLERANCE: f64 = 1e-6;

/// Newell's normal of a closed polygon: `Σ (p_i × p_{i+1})`, twice the vector area, pointing to where the loop looks counter-clockwise (Tampieri 1992, Graphics Gems III).
pub fn newell_normal(points: &[Vec3]) -> Vec3 {
    newell_normal_f64(points).as_vec3()
}

/// [`newell_normal`] in double precision, relative to the first point for accuracy.
fn newell_normal_f64(points: &[Vec3]) -> DVec3 {
    let Some(origin) = points.first().map(|p| p.as_dvec3()) else {
        return DVec3::ZERO;
    };
    let mut normal = DVec3::ZERO;
    for (i, p) in points.iter().enumerate() {
        let q = points[(i + 1) % points.len()];
        normal += (p.as_dvec3() - origin).cross(q.as_dvec3() - origin);
    }
    normal
}

/// The error for a bad polygon.
fn bad_polygon(message: impl Into<String>) -> GeometryError {
    GeometryError::InvalidMesh {
        mesh: "polygon".to_owned(),
        message: message.into(),
    }
}

/// Even-odd point-in-polygon test by crossing number (Haines, "Point in Polygon Strategies", Graphics Gems IV, 1994).
fn inside_loop(point: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let [x, y] = point;
    let mut inside = false;
    for (i, &[xi, yi]) in ring.iter().enumerate() {
        let [xj, yj] = ring[(i + ring.len() - 1) % ring.len()];
        if (yi > y) != (yj > y) && x < xi + (y - yi) * (xj - xi) / (yj - yi) {
            inside = !inside;
        }
    }
    inside
}

/// Triangulates the planar polygon `outline` minus `holes` with spade's constrained Delaunay triangulation (Chew 1989), projected on the Newell plane (Tampieri 1992).
///
/// Returns the vertices (the input points that the triangles use, outline
/// first, then the holes in order; a closing point equal to the first and
/// repeated consecutive points are dropped) and triangles counter-clockwise
/// as seen from the outline's Newell normal, covering exactly the outline's
/// interior outside the holes.
///
/// Errors when a loop has fewer than 3 distinct points, a coordinate is not
/// finite, the outline has no area (collinear points), a point lies farther
/// than `1e-4` of the bounding-box diagonal from the best-fit plane, edges
/// cross, overlap or touch (a self-intersecting outline, a hole crossing the
/// outline or another hole, a vertex used twice or lying on an edge), or a
/// hole is not inside the outline or lies inside another hole.
pub fn triangulate_polygon(
    outline: &[Vec3],
    holes: &[Vec<Vec3>],
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    // Loops without repeated consecutive points or a closing duplicate.
    let mut loops: Vec<Vec<Vec3>> = Vec::with_capacity(1 + holes.len());
    for (k, ring) in std::iter::once(outline)
        .chain(holes.iter().map(Vec::as_slice))
        .enumerate()
    {
        let what = if k == 0 {
            "the outline".to_owned()
        } else {
            format!("hole {}", k - 1)
        };
        if let Some(i) = ring.iter().position(|p| !p.is_finite()) {
            return Err(bad_polygon(format!("point {i} of {what} is not finite")));
        }
        let mut clean: Vec<Vec3> = Vec::with_capacity(ring.len());
        for &p in ring {
            if clean.last() != Some(&p) {
                clean.push(p);
            }
        }
        while clean.len() > 1 && clean.first() == clean.last() {
            clean.pop();
        }
        if clean.len() < 3 {
            return Err(bad_polygon(format!(
                "{what} has {} distinct points; a polygon needs at least 3",
                clean.len()
            )));
        }
        loops.push(clean);
    }

    // The best-fit plane: Newell's normal through the outline's centroid.
    let all = || loops.iter().flatten().map(|p| p.as_dvec3());
    let (lo, hi) = all().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    let diagonal = (hi - lo).length();
    let newell = newell_normal_f64(&loops[0]);
    let min_twice_area = 2.0 * AREA_TOLERANCE * diagonal * diagonal;
    if !(newell.length() > min_twice_area) {
        // No net area: either the points are collinear, or the outline winds
        // around itself so that its lobes cancel (a bow tie).
        let origin = loops[0][0].as_dvec3();
        let far = loops[0]
            .iter()
            .map(|p| p.as_dvec3() - origin)
            .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
            .unwrap_or(DVec3::ZERO);
        let spans_plane = loops[0]
            .iter()
            .any(|p| (p.as_dvec3() - origin).cross(far).length() > min_twice_area);
        return Err(bad_polygon(if spans_plane {
            "the outline intersects or touches itself: its signed area is zero"
        } else {
            "the outline has no area (its points are collinear)"
        }));
    }
    let normal = newell.normalize();
    let centroid = loops[0].iter().map(|p| p.as_dvec3()).sum::<DVec3>() / loops[0].len() as f64;
    let worst = all()
        .map(|p| (p - centroid).dot(normal).abs())
        .fold(0.0_f64, f64::max);
    if worst > PLANARITY_TOLERANCE * diagonal {
        return Err(bad_polygon(format!(
            "the polygon is not planar: a point lies {worst} from the best-fit plane (tolerance {})",
            PLANARITY_TOLERANCE * diagonal
        )));
    }

    // Plane coordinates (u, v) with u × v = normal, so counter-clockwise in
    // the plane is counter-clockwise seen from the normal.
    let frame = Frame::from_normal(normal.as_vec3());
    let (s, t) = (frame.s.as_dvec3(), frame.t.as_dvec3());
    let project = |p: Vec3| {
        let d = p.as_dvec3() - centroid;
        [d.dot(s), d.dot(t)]
    };
    let rings: Vec<Vec<[f64; 2]>> = loops
        .iter()
        .map(|ring| ring.iter().map(|&p| project(p)).collect())
        .collect();

    // Insert every vertex, remembering which input point each spade vertex is.
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut source: Vec<Option<(usize, usize)>> = Vec::new();
    let mut handles: Vec<Vec<_>> = Vec::with_capacity(rings.len());
    for (k, ring) in rings.iter().enumerate() {
        let mut ring_handles = Vec::with_capacity(ring.len());
        for (i, &[x, y]) in ring.iter().enumerate() {
            let handle = cdt
                .insert(spade::mitigate_underflow(Point2::new(x, y)))
                .map_err(|e| bad_polygon(format!("point {i} cannot be triangulated: {e}")))?;
            let slot = handle.index();
            if source.len() <= slot {
                source.resize(slot + 1, None);
            }
            if let Some((k0, i0)) = source[slot] {
                return Err(bad_polygon(format!(
                    "the polygon intersects or touches itself: point {i} of loop {k} coincides with point {i0} of loop {k0} (loop 0 is the outline)"
                )));
            }
            source[slot] = Some((k, i));
            ring_handles.push(handle);
        }
        handles.push(ring_handles);
    }

    // Constraint edges; spade reports edges that would cross existing ones.
    let mut edges = 0;
    for (k, ring) in handles.iter().enumerate() {
        for i in 0..ring.len() {
            let (from, to) = (ring[i], ring[(i + 1) % ring.len()]);
            if !cdt.can_add_constraint(from, to) {
                return Err(bad_polygon(format!(
                    "the polygon intersects or touches itself: edge {i} of loop {k} crosses another edge (loop 0 is the outline)"
                )));
            }
            cdt.add_constraint(from, to);
            edges += 1;
        }
    }
    if cdt.num_constraints() != edges {
        return Err(bad_polygon(
            "the polygon intersects or touches itself: an edge overlaps another or passes through a vertex",
        ));
    }

    // Holes must lie inside the outline and outside each other, or the
    // even-odd rule below would fill them.
    for (k, ring) in rings.iter().enumerate().skip(1) {
        if !inside_loop(ring[0], &rings[0]) {
            return Err(bad_polygon(format!(
                "hole {} is not inside the outline",
                k - 1
            )));
        }
        if let Some(other) = (1..rings.len()).find(|&o| o != k && inside_loop(ring[0], &rings[o])) {
            return Err(bad_polygon(format!(
                "hole {} lies inside hole {}",
                k - 1,
                other - 1
            )));
        }
    }

    // Flood the faces from the convex hull, flipping parity across constraints.
    let mut inside: Vec<Option<bool>> = vec![None; cdt.num_all_faces()];
    let mut stack: Vec<(FixedFaceHandle<spade::handles::InnerTag>, bool)> = Vec::new();
    for edge in cdt.convex_hull() {
        for side in [edge, edge.rev()] {
            if let Some(face) = side.face().as_inner() {
                stack.push((face.fix(), side.is_constraint_edge()));
            }
        }
    }
    while let Some((face, parity)) = stack.pop() {
        if inside[face.index()].is_some() {
            continue;
        }
        inside[face.index()] = Some(parity);
        for edge in cdt.face(face).adjacent_edges() {
            if let Some(next) = edge.rev().face().as_inner() {
                if inside[next.fix().index()].is_none() {
                    stack.push((next.fix(), parity ^ edge.is_constraint_edge()));
                }
            }
        }
    }

    // Output: the used input points in input order, and the inside faces.
    let mut triangles_by_source: Vec<[(usize, usize); 3]> = Vec::new();
    for face in cdt.inner_faces() {
        if inside[face.fix().index()] == Some(true) {
            let corners = face
                .vertices()
                .map(|v| source[v.fix().index()].expect("every vertex comes from the input"));
            triangles_by_source.push(corners);
        }
    }
    if triangles_by_source.is_empty() {
        return Err(bad_polygon("the polygon has no interior"));
    }
    let mut output_index: Vec<Vec<Option<u32>>> =
        loops.iter().map(|ring| vec![None; ring.len()]).collect();
    for tri in &triangles_by_source {
        for &(k, i) in tri {
            output_index[k][i] = Some(0);
        }
    }
    let mut vertices = Vec::new();
    for (k, ring) in loops.iter().enumerate() {
        for (i, &p) in ring.iter().enumerate() {
            if output_index[k][i].is_some() {
                output_index[k][i] = Some(vertices.len() as u32);
                vertices.push(p);
            }
        }
    }
    let triangles = triangles_by_source
        .iter()
        .map(|tri| tri.map(|(k, i)| output_index[k][i].expect("marked above")))
        .collect();
    Ok((vertices, triangles))
}
