//! Planes and the mirror transform about a plane.

use glam::{Mat3, Mat4, Vec3, Vec4};

/// The plane of points `x` with `normal · x = offset`; `normal` has unit length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vec3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: f32,
}

impl Plane {
    /// The plane through `point` with the given normal (normalised here).
    pub fn from_point_normal(point: Vec3, normal: Vec3) -> Self {
        let normal = normal.normalize();
        Self {
            normal,
            offset: normal.dot(point),
        }
    }

    /// Signed distance of `p` from the plane (positive on the normal's side).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }

    /// The point `p` mirrored about the plane.
    pub fn reflect_point(&self, p: Vec3) -> Vec3 {
        p - 2.0 * self.signed_distance(p) * self.normal
    }

    /// The direction `v` mirrored about the plane.
    pub fn reflect_vector(&self, v: Vec3) -> Vec3 {
        v - 2.0 * self.normal.dot(v) * self.normal
    }

    /// The plane as the 4-vector `(n, -offset)` for clip-plane tests in homogeneous form.
    pub fn to_vec4(&self) -> Vec4 {
        self.normal.extend(-self.offset)
    }

    /// The same plane with its normal turned round (the other side in front).
    pub fn flipped(&self) -> Self {
        Self {
            normal: -self.normal,
            offset: -self.offset,
        }
    }

    /// The affine mirror transform `x -> x - 2 (n·x - d) n` as a matrix.
    ///
    /// Its linear part `I - 2 n nᵀ` has determinant -1, so it flips the winding
    /// of triangles: a pass that renders through it must swap its front face.
    pub fn reflection_matrix(&self) -> Mat4 {
        let n = self.normal;
        let linear = Mat3::IDENTITY - 2.0 * Mat3::from_cols(n * n.x, n * n.y, n * n.z);
        let translation = 2.0 * self.offset * n;
        Mat4::from_cols(
            linear.x_axis.extend(0.0),
            linear.y_axis.extend(0.0),
            linear.z_axis.extend(0.0),
            translation.extend(1.0),
        )
    }
}
