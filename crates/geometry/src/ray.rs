//! Rays, ray-triangle intersection and hit records.

use std::ops::{Add, Mul, Sub};

use glam::{Vec2, Vec3, Vec3A, Vec4};

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
    intersect_triangle_edges(origin, direction, t_min, t_max, *p0, *p1 - *p0, *p2 - *p0)
}

/// The cross product `a × b` by components, `a.y * b.z - a.z * b.y` and so on
/// (glam's `Vec3A::cross` without FMA, bit for bit), on scalars or on lanes.
#[inline(always)]
fn cross<T: Copy + Mul<Output = T> + Sub<Output = T>>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The dot product `(a.x * b.x + a.y * b.y) + a.z * b.z` (glam's `Vec3A::dot`, bit for bit), on scalars or on lanes.
#[inline(always)]
fn dot<T: Copy + Mul<Output = T> + Add<Output = T>>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// [`intersect_triangle_a`] on corner 0 and the edges `e1 = p1 - p0`, `e2 = p2 - p0`
/// computed beforehand (the BVH stores them); bit-identical results.
#[inline]
pub(crate) fn intersect_triangle_edges(
    origin: Vec3A,
    direction: Vec3A,
    t_min: f32,
    t_max: f32,
    p0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
) -> Option<TriangleHit> {
    let (d, e1, e2) = (direction.to_array(), e1.to_array(), e2.to_array());
    let pvec = cross(d, e2);
    let det = dot(e1, pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = (origin - p0).to_array();
    let u = dot(tvec, pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = cross(tvec, e1);
    let v = dot(d, qvec) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = dot(e2, qvec) * inv_det;
    (t >= t_min && t <= t_max).then_some(TriangleHit { t, u, v })
}

/// Four triangles side by side for [`intersect_triangles4`]: corner 0 and
/// the two edges by coordinate, one triangle per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Triangles4 {
    /// Corner 0: x, y, z of the four triangles.
    pub p0: [Vec4; 3],
    /// Edge `p1 - p0`.
    pub e1: [Vec4; 3],
    /// Edge `p2 - p0`.
    pub e2: [Vec4; 3],
}

/// [`intersect_triangle_edges`] on four triangles at once, lane by lane with
/// the same operations in the same order (bit-identical per lane): the
/// bitmask of the lanes hit (bit `k` for lane `k`) and their `t`, `u`, `v`.
#[inline]
pub(crate) fn intersect_triangles4(
    origin: Vec3A,
    direction: Vec3A,
    t_min: f32,
    t_max: f32,
    tris: &Triangles4,
) -> (u32, [f32; 4], [f32; 4], [f32; 4]) {
    let d = direction.to_array().map(Vec4::splat);
    let o = origin.to_array().map(Vec4::splat);
    let pvec = cross(d, tris.e2);
    let det = dot(tris.e1, pvec);
    let mut ok = det.cmpne(Vec4::ZERO) & det.is_finite_mask();
    let inv_det = Vec4::ONE / det;
    let tvec = [o[0] - tris.p0[0], o[1] - tris.p0[1], o[2] - tris.p0[2]];
    let u = dot(tvec, pvec) * inv_det;
    ok &= u.cmpge(Vec4::ZERO) & u.cmple(Vec4::ONE);
    let qvec = cross(tvec, tris.e1);
    let v = dot(d, qvec) * inv_det;
    // `!(v < 0 || u + v > 1)`, which lets NaN through as the scalar test does.
    ok &= !(v.cmplt(Vec4::ZERO) | (u + v).cmpgt(Vec4::ONE));
    let t = dot(tris.e2, qvec) * inv_det;
    ok &= t.cmpge(Vec4::splat(t_min)) & t.cmple(Vec4::splat(t_max));
    (ok.bitmask(), t.to_array(), u.to_array(), v.to_array())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of numbers in [-1, 1) (a 64-bit LCG's high bits).
    struct Stream(u64);

    impl Stream {
        /// The next number of the stream (Knuth's MMIX LCG).
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        }

        /// A point in [-1, 1)³, snapped to a 1/8 grid every fourth time (shared planes, zero components).
        fn point(&mut self) -> Vec3A {
            let p = Vec3A::new(self.next(), self.next(), self.next());
            if self.next() < -0.5 {
                (p * 8.0).round() / 8.0
            } else {
                p
            }
        }
    }

    #[test]
    fn four_lanes_equal_the_scalar_test_bit_for_bit() {
        let mut s = Stream(7);
        let mut hits = 0;
        for _ in 0..40_000 {
            let corners: [[Vec3A; 3]; 4] =
                std::array::from_fn(|_| [s.point(), s.point(), s.point()]);
            let lanes = corners.map(|[p0, p1, p2]| [p0, p1 - p0, p2 - p0]);
            let by_axis = |which: usize| {
                [0, 1, 2].map(|axis| Vec4::from_array(lanes.map(|l| l[which][axis])))
            };
            let tris = Triangles4 {
                p0: by_axis(0),
                e1: by_axis(1),
                e2: by_axis(2),
            };
            let origin = s.point() * 2.0;
            let direction = s.point();
            let (t_min, t_max) = (s.next().max(0.0), 1.0 + s.next().abs() * 3.0);
            let (mask, t, u, v) = intersect_triangles4(origin, direction, t_min, t_max, &tris);
            for k in 0..4 {
                let scalar = intersect_triangle_a(origin, direction, t_min, t_max, &corners[k]);
                match scalar {
                    Some(h) => {
                        hits += 1;
                        assert!(mask & (1 << k) != 0, "lane {k} misses, scalar {h:?}");
                        assert_eq!(
                            (t[k].to_bits(), u[k].to_bits(), v[k].to_bits()),
                            (h.t.to_bits(), h.u.to_bits(), h.v.to_bits())
                        );
                    }
                    None => assert!(mask & (1 << k) == 0, "lane {k} hits, scalar misses"),
                }
            }
        }
        assert!(hits > 800, "{hits} hits");
    }

    #[test]
    fn explicit_cross_and_dot_equal_glam() {
        let mut s = Stream(11);
        for _ in 0..10_000 {
            let (a, b) = (s.point() * 100.0, s.point() * 0.01);
            let c = Vec3A::from_array(cross(a.to_array(), b.to_array()));
            assert_eq!(
                c.to_array().map(f32::to_bits),
                a.cross(b).to_array().map(f32::to_bits)
            );
            assert_eq!(
                dot(a.to_array(), b.to_array()).to_bits(),
                a.dot(b).to_bits()
            );
        }
    }
}
