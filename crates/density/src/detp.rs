//! Density Estimation on the Tangent Plane (section 1.2, Lastra et al.): a disc of fixed radius on the tangent plane at each vertex; every ray crossing it contributes `φ / (π r²)`.

use glam::Vec3;
use lustre_geometry::{MeshId, Rgb, Scene};
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::error::{DensityError, Result};
use crate::ray_set::{RaySegment, RaySet};

/// A disc centred at a point, in the plane tangent to the surface there (section 1.2, "a fixed size disc centered in the point ... contained in the plane tangent to the surface").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre: the vertex.
    pub centre: Vec3,
    /// Unit normal of the tangent plane; its side is the disc's front.
    pub normal: Vec3,
    /// Radius `r`.
    pub radius: f32,
    /// The mesh the vertex belongs to: a segment that ends on this mesh may cross the disc within its artifact-control [`RaySegment::extension`] past its hit (section 1.2.1).
    pub mesh: Option<MeshId>,
}

impl Disc {
    /// Whether a ray segment crosses the disc from its front (section 1.2, "rays intersecting a given disc"): it travels against the normal, reaches the plane between its origin and its end (within `slack` past the end, for a segment that ends on the very surface the disc lies on), at a point no farther than `r` from the centre.
    pub fn is_crossed_by(&self, segment: &RaySegment, slack: f32) -> bool {
        // Every test is evaluated and combined with `&` rather than `&&`: the same answer (a comparison with NaN is
        // false either way), without the data-dependent branches that disc indexing's candidates mispredict.
        let denom = segment.direction.dot(self.normal);
        let t = (self.centre - segment.origin).dot(self.normal) / denom;
        let p = segment.origin + t * segment.direction;
        (denom < 0.0)
            & (t >= 0.0)
            & (t <= self.reach(segment) + slack)
            & (p.distance_squared(self.centre) <= self.radius * self.radius)
    }

    /// How far along a segment the disc may be crossed: its length, plus its artifact-control extension when it ends on the disc's own mesh (section 1.2.1, concave surfaces).
    pub fn reach(&self, segment: &RaySegment) -> f32 {
        match (segment.hit, self.mesh) {
            (Some(hit), Some(mesh)) if hit.mesh == mesh => hit.distance + segment.extension,
            _ => segment.length(),
        }
    }

    /// A box round every point where [`Disc::is_crossed_by`] with `slack` finds a segment crossing the disc: `centre ± r`, padded by the slack, a thousandth of `r` and `10⁻⁵` of the centre's largest coordinate for rounding (the disc's part of it; [`segment_meets_box`] adds the segment's).
    pub fn bounds(&self, slack: f32) -> (Vec3, Vec3) {
        let pad = slack + 1e-3 * self.radius + 1e-5 * self.centre.abs().max_element();
        let half = Vec3::splat(self.radius + pad);
        (self.centre - half, self.centre + half)
    }

    /// The disc's contribution of one segment, `φ / (π r²)` when it crosses the disc, else zero (section 1.2; additive over rays, equation 2.8).
    pub fn irradiance_of(&self, segment: &RaySegment, slack: f32) -> Rgb {
        if self.is_crossed_by(segment, slack) {
            segment.power / (std::f32::consts::PI * self.radius * self.radius)
        } else {
            Rgb::ZERO
        }
    }
}

/// DETP irradiance at every vertex (section 1.2; section 2.4.1, figure 2.3): a disc of radius `radius` on the tangent plane (the vertex's shading normal), `E = Σ φ_j / (π r²)` over the ray segments `j` crossing it from the front, including rays that leave the scene without a hit. Fails unless `radius` is positive and finite.
pub fn detp(scene: &Scene, rays: &RaySet, radius: f32) -> Result<VertexIrradiance> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(DensityError::InvalidOption {
            option: "radius",
            message: format!("{radius} is not a positive finite disc radius"),
        });
    }
    // A segment ending on the disc's own surface reaches the plane at its end; f32 rounding may put it just past it.
    let slack = crate::accel::scene_slack(scene);
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    Ok((0..scene.meshes().len())
        .map(|m| {
            let positions = scene.world_positions(m as u32);
            let normals = scene.world_normals(m as u32);
            positions
                .par_iter()
                .zip(normals.par_iter())
                .map(|(&centre, &normal)| {
                    let normal = normal.normalize_or_zero();
                    if normal == Vec3::ZERO {
                        return Rgb::ZERO;
                    }
                    let disc = Disc {
                        centre,
                        normal,
                        radius,
                        mesh: Some(m as MeshId),
                    };
                    let sum: glam::DVec3 = segments
                        .iter()
                        .filter(|s| disc.is_crossed_by(s, slack))
                        .map(|s| s.power.as_dvec3())
                        .sum();
                    (sum / (std::f64::consts::PI * (radius as f64).powi(2))).as_vec3()
                })
                .collect()
        })
        .collect())
}

/// Whether `segment`, followed as far as any disc may see it (its length, or its hit plus its artifact-control extension, plus `slack`), passes through the box `lo..=hi` (slab test): false only when it crosses no disc whose [`Disc::bounds`] lie in the box, so a set of discs in a small region can skip every other segment (beyond the paper, section 2.5.2: the mobile object's discs against every ray).
///
/// The box is grown by `10⁻⁵` of the origin's largest coordinate: [`Disc::is_crossed_by`] rounds its crossing point `o + t d` by a few ulps of `|o|` as well as of `|c|` (see `accel::envelope`), and a tiny disc seen from far away may accept a segment whose exact path passes just outside `centre ± r` plus the disc's own pad.
pub fn segment_meets_box(segment: &RaySegment, slack: f32, lo: Vec3, hi: Vec3) -> bool {
    let reach = segment_reach(segment, slack);
    let pad = Vec3::splat(1e-5 * segment.origin.abs().max_element());
    span_in_box(segment.origin, segment.direction, reach, lo - pad, hi + pad).is_some()
}

/// How far the tests follow a segment: its length, or its hit plus its artifact-control extension, plus `slack` (infinite for a segment without a hit).
pub(crate) fn segment_reach(segment: &RaySegment, slack: f32) -> f32 {
    segment
        .hit
        .map_or(f32::INFINITY, |h| h.distance + segment.extension.max(0.0))
        + slack
}

/// The part `[t0, t1]` of `origin + t direction`, `t` in `[0, reach]`, inside the box `lo..=hi` (the slab test); `None` when they do not meet.
pub(crate) fn span_in_box(
    origin: Vec3,
    direction: Vec3,
    reach: f32,
    lo: Vec3,
    hi: Vec3,
) -> Option<(f32, f32)> {
    let (mut t0, mut t1) = (0.0f32, reach);
    for axis in 0..3 {
        let (o, d) = (origin[axis], direction[axis]);
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}
