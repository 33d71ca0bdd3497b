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
        let denom = segment.direction.dot(self.normal);
        if !(denom < 0.0) {
            return false;
        }
        let t = (self.centre - segment.origin).dot(self.normal) / denom;
        if !(t >= 0.0 && t <= self.reach(segment) + slack) {
            return false;
        }
        let p = segment.origin + t * segment.direction;
        p.distance_squared(self.centre) <= self.radius * self.radius
    }

    /// How far along a segment the disc may be crossed: its length, plus its artifact-control extension when it ends on the disc's own mesh (section 1.2.1, concave surfaces).
    pub fn reach(&self, segment: &RaySegment) -> f32 {
        match (segment.hit, self.mesh) {
            (Some(hit), Some(mesh)) if hit.mesh == mesh => hit.distance + segment.extension,
            _ => segment.length(),
        }
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
