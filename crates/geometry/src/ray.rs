//! Rays, ray-triangle intersection and hit records.

use glam::{Vec2, Vec3, Vec3A};

use crate::material::MaterialId;
use crate::scene::{SurfaceId, TriangleId};

/// A ray `origin + t * direction` for `t` in `[t_min, t_max]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (unit length for distances to be metres).
    pub direction: Vec3,
    /// Smallest accepted distance (to step off the surface a ray leaves).
    pub t_min: f32,
    /// Largest accepted distance.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray, `t` in `[0, ∞)`.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// A ray with a distance interval.
    pub fn segment(origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            direction,
            t_min,
            t_max,
        }
    }

    /// The point at distance `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// Where a ray meets a triangle: distance and barycentrics of corners 1 and 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Ray distance.
    pub t: f32,
    /// Barycentric weight of corner 1.
    pub u: f32,
    /// Barycentric weight of corner 2 (corner 0 weighs `1 - u - v`).
    pub v: f32,
}

/// Möller-Trumbore ray-triangle intersection (Möller & Trumbore 1997), both
/// sides, accepting `t` in `[ray.t_min, ray.t_max]`.
#[inline]
pub fn intersect_triangle(ray: &Ray, [p0, p1, p2]: [Vec3; 3]) -> Option<TriangleHit> {
    intersect_triangle_a(
        ray.origin.into(),
        ray.direction.into(),
        ray.t_min,
        ray.t_max,
        &[p0.into(), p1.into(), p2.into()],
    )
}

/// [`intersect_triangle`] on 16-byte aligned vectors (SIMD on x86-64), the
/// form the BVH stores; both give bit-identical results.
#[inline]
pub(crate) fn intersect_triangle_a(
    origin: Vec3A,
    direction: Vec3A,
    t_min: f32,
    t_max: f32,
    [p0, p1, p2]: &[Vec3A; 3],
) -> Option<TriangleHit> {
    let e1 = *p1 - *p0;
    let e2 = *p2 - *p0;
    let pvec = direction.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = origin - *p0;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = direction.dot(qvec) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    (t >= t_min && t <= t_max).then_some(TriangleHit { t, u, v })
}

/// A closest hit without its shading record: the triangle, the distance and
/// the barycentrics ([`crate::Bvh::hit_record`] builds the full [`Hit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeanHit {
    /// The triangle hit, as a scene-wide triangle id.
    pub triangle: TriangleId,
    /// Ray distance.
    pub t: f32,
    /// Barycentric weight of corner 1.
    pub u: f32,
    /// Barycentric weight of corner 2 (corner 0 weighs `1 - u - v`).
    pub v: f32,
}

/// A closest-hit record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// The triangle hit, as a scene-wide triangle id.
    pub triangle: TriangleId,
    /// The surface the triangle belongs to.
    pub surface: SurfaceId,
    /// The material of the triangle.
    pub material: MaterialId,
    /// Ray distance.
    pub t: f32,
    /// Barycentric weight of corner 1.
    pub u: f32,
    /// Barycentric weight of corner 2.
    pub v: f32,
    /// World position of the hit.
    pub position: Vec3,
    /// Unit geometric normal (from the winding, not flipped toward the ray).
    pub geometric_normal: Vec3,
    /// Unit interpolated shading normal.
    pub shading_normal: Vec3,
    /// Interpolated texture coordinates.
    pub uv: Vec2,
}
