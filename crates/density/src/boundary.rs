//! Photon Maps' boundary correction (beyond García, Ureña & Lastra's text and Jensen's estimate): the area of the `k`-nearest disc that lies on the vertex's surface instead of `π r_k²`.
//!
//! `E = Σ φ / (π r_k²)` assumes that the whole disc of radius `r_k` around
//! the vertex lies on its surface. A vertex on the edge of the floor against
//! a wall sees impacts on half of that disc only, a vertex in a corner on a
//! quarter, so the plain estimate there is a half or a quarter of the
//! irradiance (section 2.9.1's border bias `α/2π`), and the bias reaches as
//! far from every edge as `r_k`: dark outlines along every joint and box
//! edge. The `k`-nearest search ([`crate::ImpactMap`]) gathers the impacts
//! in the ball of radius `r_k` around the vertex whose surface faces like the
//! vertex's (the normal filter, [`NORMAL_FILTER_COSINE`]); the correction
//! divides their power by the area of exactly that: the surface in the ball
//! whose normal passes the same filter.
//!
//! That area is measured in the vertex's tangent plane along
//! [`DIRECTIONS`] fixed directions `u_j` (evenly spread, turned by
//! [`PATTERN_TURN`] off the axes and diagonals of a regularly subdivided
//! mesh), each standing for a sector of `2π / m`. The triangles near the
//! vertex ([`Surfaces`]) whose geometric normal makes a cosine of at least
//! [`NORMAL_FILTER_COSINE`] with the vertex normal in absolute value (the
//! filter turns impact normals to the side their photon arrived from, so
//! either face can hold compatible impacts) are projected along the normal
//! onto the tangent plane; along each direction the radii `ρ` at which the
//! line `ρ u_j` lies over such a triangle whose point is in the ball are an
//! interval, found exactly (three edge half-planes and the ball's
//! quadratic). The area is `Σ_j (2π/m) ∫ w ρ dρ` over the union of the
//! intervals, `w = 1 / |cos|` of the surface met first coming down the
//! normal: the surface's own area above the tangent plane's, so a surface
//! tilted within the filter (a curved mesh) counts its own area, not its
//! projection. Along each direction it is exact; over the directions it is
//! the midpoint rule, whose error against the exact clipped-disc area is
//! below 0.01 of `π r²` and 0.001 in RMS (`tests/boundary.rs`).
//!
//! Consequences:
//!
//! - A vertex on an edge against a wall, or on the free edge of a surface,
//!   gets half the disc, a right-angled corner a quarter, up to rounding:
//!   the directions are symmetric under half and quarter turns, and none runs
//!   along a line through the vertex on the meshes' axes or diagonals.
//! - Only one layer counts at each point of the disc: the ceiling above the
//!   light (which no photon reaches) and the light 1 cm below it (which holds
//!   the impacts) count once.
//! - The floor under a box standing on it counts as surface; its impacts are
//!   missing, so a vertex beside the box averages its irradiance with the
//!   box's zero, the usual blur of a kernel across a discontinuity, as across
//!   a shadow's edge.
//! - The triangles are the scene as it is now: in the quasi-static loop the
//!   mobile objects at the frame's pose ([`crate::World`]), measured again
//!   every frame with the estimate.
//!
//! Where no compatible triangle lies in the ball (a degenerate vertex) the
//! plain `π r_k²` is kept, and a vertex whose search found no impact is zero
//! without any probe.

use glam::{Vec2, Vec3};
use lustre_geometry::Bvh;
use lustre_geometry::sampling::Frame;

use crate::radiance::NORMAL_FILTER_COSINE;
use crate::world::World;

/// Directions of the probe pattern: 64 measure the area of a disc cut by a straight edge within 0.5 % of `π r²` (exactly for an edge through the vertex, and for a right-angled corner at it).
pub const DIRECTIONS: u32 = 64;

/// Turn of the probe directions in the tangent plane, in radians: off the axes and diagonals of a regularly subdivided mesh's edges.
pub const PATTERN_TURN: f32 = 0.3;

/// The scene's triangles as the probes meet them.
pub trait Surfaces: Sync {
    /// Calls `f` with the corners of every triangle whose bounding box overlaps the box `min..=max` (others may come too; each at most once).
    fn triangles_near(&self, min: Vec3, max: Vec3, f: &mut dyn FnMut([Vec3; 3]));
}

impl Surfaces for Bvh {
    fn triangles_near(&self, min: Vec3, max: Vec3, f: &mut dyn FnMut([Vec3; 3])) {
        self.overlapping(min, max, |t| f(self.triangles()[t as usize].positions));
    }
}

impl Surfaces for World {
    fn triangles_near(&self, min: Vec3, max: Vec3, f: &mut dyn FnMut([Vec3; 3])) {
        World::triangles_near(self, min, max, f);
    }
}

/// A triangle compatible with the vertex, in the vertex's tangent frame scaled by `1 / r`: corners `(s, t)` relative to the vertex, its plane as a height `z = z0 + slope · (s, t)` along the normal, and `1 / |cos|` of its normal with the vertex's.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    corners: [Vec2; 3],
    /// 1 for counter-clockwise corners, −1 for clockwise ones.
    orientation: f32,
    z0: f32,
    slope: Vec2,
    weight: f64,
}

/// The part of one direction's ray `ρ u`, `ρ ∈ [lo, hi]`, over a candidate, with the candidate's height along it and weight.
#[derive(Debug, Clone, Copy)]
struct Span {
    lo: f32,
    hi: f32,
    z0: f32,
    dz: f32,
    weight: f64,
}

impl Candidate {
    /// The part of the ray `ρ u` (`u` a unit direction, `ρ ≥ 0`) that lies over the triangle and whose point on the triangle's plane lies in the unit ball.
    fn span(&self, u: Vec2) -> Option<Span> {
        let (mut lo, mut hi) = (0.0f32, f32::INFINITY);
        for i in 0..3 {
            let a = self.corners[i];
            let e = self.corners[(i + 1) % 3] - a;
            // Inside the edge: orientation · (e × (ρ u − a)) = α + ρ β ≥ 0.
            let alpha = -self.orientation * e.perp_dot(a);
            let beta = self.orientation * e.perp_dot(u);
            if beta > 0.0 {
                lo = lo.max(-alpha / beta);
            } else if beta < 0.0 {
                hi = hi.min(-alpha / beta);
            } else if alpha < 0.0 {
                return None;
            }
        }
        // In the ball: ρ² + (z0 + ρ dz)² ≤ 1.
        let dz = self.slope.dot(u);
        let qa = 1.0 + dz * dz;
        let qb = 2.0 * self.z0 * dz;
        let qc = self.z0 * self.z0 - 1.0;
        let disc = qb * qb - 4.0 * qa * qc;
        if !(disc >= 0.0) {
            return None;
        }
        let root = disc.sqrt();
        lo = lo.max((-qb - root) / (2.0 * qa));
        hi = hi.min((-qb + root) / (2.0 * qa));
        (lo < hi).then_some(Span {
            lo,
            hi,
            z0: self.z0,
            dz,
            weight: self.weight,
        })
    }
}

/// The fixed pattern of probe directions in the tangent plane.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscPattern {
    directions: Vec<Vec2>,
}

impl Default for DiscPattern {
    fn default() -> Self {
        Self::new(DIRECTIONS)
    }
}

impl DiscPattern {
    /// `m` directions evenly spread, at `(j + ½) 2π/m` turned by [`PATTERN_TURN`] (at least one): for an even `m` point symmetric, for a multiple of 4 symmetric under quarter turns.
    pub fn new(m: u32) -> Self {
        let m = m.max(1);
        let directions = (0..m)
            .map(|j| {
                let a = (j as f32 + 0.5) * std::f32::consts::TAU / m as f32 + PATTERN_TURN;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        Self { directions }
    }

    /// The unit directions.
    pub fn directions(&self) -> &[Vec2] {
        &self.directions
    }

    /// The area of compatible surface in the ball of radius `r` around `x` (unit normal `n`), as a fraction of `π r²` (see the module docs); 1 for a radius or normal that is not usable, `None` where no compatible surface lies in the ball.
    pub fn fraction(&self, surfaces: &dyn Surfaces, x: Vec3, n: Vec3, r: f32) -> Option<f64> {
        if !(r > 0.0 && r.is_finite()) || n == Vec3::ZERO {
            return Some(1.0);
        }
        let frame = Frame::from_normal(n);
        let mut candidates = Vec::new();
        surfaces.triangles_near(x - Vec3::splat(r), x + Vec3::splat(r), &mut |corners| {
            if let Some(c) = candidate(&frame, x, r, corners) {
                candidates.push(c);
            }
        });
        if candidates.is_empty() {
            return None;
        }
        let mut spans = Vec::new();
        let mut ends = Vec::new();
        let mut sum = 0.0f64;
        for &u in &self.directions {
            spans.clear();
            spans.extend(candidates.iter().filter_map(|c| c.span(u)));
            sum += covered(&mut spans, &mut ends);
        }
        // Each direction stands for a sector of 2π/m: ∫ w ρ dρ over it, over π.
        let fraction = sum * 2.0 / self.directions.len() as f64;
        (fraction > 0.0).then_some(fraction)
    }
}

/// `∫ w(ρ) ρ dρ` over the union of the spans, `w` the weight of the span highest along the normal where several overlap (each point of the disc counts once, on the first surface met coming down the normal).
fn covered(spans: &mut [Span], ends: &mut Vec<f32>) -> f64 {
    let integral =
        |lo: f32, hi: f32, w: f64| w * 0.5 * (hi as f64 * hi as f64 - lo as f64 * lo as f64);
    match spans {
        [] => 0.0,
        [s] => integral(s.lo, s.hi, s.weight),
        [first, rest @ ..] if rest.iter().all(|s| s.weight == first.weight) => {
            // One weight (parallel surfaces): only the union's extent counts.
            let weight = first.weight;
            spans.sort_by(|a, b| a.lo.total_cmp(&b.lo));
            let mut sum = 0.0;
            let (mut lo, mut hi) = (spans[0].lo, spans[0].hi);
            for s in &spans[1..] {
                if s.lo > hi {
                    sum += integral(lo, hi, weight);
                    (lo, hi) = (s.lo, s.hi);
                } else {
                    hi = hi.max(s.hi);
                }
            }
            sum + integral(lo, hi, weight)
        }
        _ => {
            ends.clear();
            ends.extend(spans.iter().flat_map(|s| [s.lo, s.hi]));
            ends.sort_by(f32::total_cmp);
            let mut sum = 0.0;
            for w in ends.windows(2) {
                let (lo, hi) = (w[0], w[1]);
                if !(hi > lo) {
                    continue;
                }
                let mid = 0.5 * (lo + hi);
                let top = spans
                    .iter()
                    .filter(|s| s.lo <= mid && mid <= s.hi)
                    .max_by(|a, b| (a.z0 + mid * a.dz).total_cmp(&(b.z0 + mid * b.dz)));
                if let Some(s) = top {
                    sum += integral(lo, hi, s.weight);
                }
            }
            sum
        }
    }
}

/// The triangle `corners` in the tangent frame at `x` scaled by `1 / r`, when its normal passes the filter against the frame's normal (either side).
fn candidate(frame: &Frame, x: Vec3, r: f32, corners: [Vec3; 3]) -> Option<Candidate> {
    let local = corners.map(|p| frame.to_local(p - x) / r);
    let m = (local[1] - local[0]).cross(local[2] - local[0]);
    let len = m.length();
    if !(len > 0.0) {
        return None;
    }
    let cos = m.z.abs() / len;
    if !(cos >= NORMAL_FILTER_COSINE) {
        return None;
    }
    // The plane m · (p − p0) = 0 as z = z0 − (mx s + my t) / mz.
    let z0 = m.dot(local[0]) / m.z;
    Some(Candidate {
        corners: local.map(|l| Vec2::new(l.x, l.y)),
        orientation: m.z.signum(),
        z0,
        slope: Vec2::new(-m.x / m.z, -m.y / m.z),
        weight: 1.0 / cos as f64,
    })
}
