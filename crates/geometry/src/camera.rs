//! The pinhole perspective camera.

use glam::{Mat4, Vec2, Vec3};

use crate::{Plane, Ray};

/// A pinhole perspective camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Centre of projection.
    pub position: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// The up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
    /// Width over height of the image.
    pub aspect: f32,
    /// Distance of the near plane (the far plane is at infinity).
    pub near: f32,
    /// Offset of the projected image in NDC (zero: none), the sub-pixel
    /// shift of jittered accumulation (Diefenbach & Badler 1997, section 7).
    pub jitter: Vec2,
}

impl Camera {
    /// A camera with the given pose and a square image.
    pub fn look_at(position: Vec3, target: Vec3, up: Vec3, fov_y_degrees: f32) -> Self {
        Self {
            position,
            target,
            up,
            fov_y_degrees,
            aspect: 1.0,
            near: 1e-3,
            jitter: Vec2::ZERO,
        }
    }

    /// This camera with another aspect ratio (width over height).
    pub fn with_aspect(mut self, aspect: f32) -> Self {
        self.aspect = aspect;
        self
    }

    /// This camera with its image shifted so that a `width`×`height`
    /// rasteriser, which samples pixel centres, samples each pixel at
    /// `offset` in [0, 1)² instead (0.5, 0.5: no shift; row 0 at the top):
    /// one projection of jittered accumulation (Diefenbach & Badler 1997, section 7).
    pub fn with_pixel_offset(mut self, offset: Vec2, width: u32, height: u32) -> Self {
        self.jitter = Vec2::new(
            2.0 * (0.5 - offset.x) / width as f32,
            -2.0 * (0.5 - offset.y) / height as f32,
        );
        self
    }

    /// Right-handed orthonormal camera frame: (right, up, forward).
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// World to view matrix (right-handed, the camera looks down -Z).
    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.position, self.target, self.up)
    }

    /// View to clip matrix in wgpu's convention with reverse Z: depth 1 at the
    /// near plane, 0 at infinity (clear depth to 0 and test `Greater`); a
    /// non-zero [`Camera::jitter`] translates the result in NDC.
    pub fn projection_matrix(&self) -> Mat4 {
        let projection = glam::camera::rh::proj::directx::perspective_infinite_reverse(
            self.fov_y_degrees.to_radians(),
            self.aspect,
            self.near,
        );
        if self.jitter == Vec2::ZERO {
            projection
        } else {
            Mat4::from_translation(self.jitter.extend(0.0)) * projection
        }
    }

    /// World to clip matrix.
    pub fn view_projection(&self) -> Mat4 {
        self.projection_matrix() * self.view_matrix()
    }

    /// The primary ray through a point of the image, `ndc` in [-1, 1]^2 with
    /// +x to the right and +y up (pixel centres: see [`Camera::pixel_ndc`]);
    /// it follows [`Camera::jitter`], as the projection does.
    pub fn primary_ray(&self, ndc: Vec2) -> Ray {
        let ndc = ndc - self.jitter;
        let (right, up, forward) = self.frame();
        let tan_half = (0.5 * self.fov_y_degrees.to_radians()).tan();
        let dir = forward + right * (ndc.x * tan_half * self.aspect) + up * (ndc.y * tan_half);
        Ray::new(self.position, dir.normalize())
    }

    /// NDC of a point of pixel `(x, y)` of a `width`×`height` image (row 0 at
    /// the top), `offset` in [0, 1)^2 within the pixel (0.5, 0.5 is its centre).
    pub fn pixel_ndc(x: u32, y: u32, width: u32, height: u32, offset: Vec2) -> Vec2 {
        Vec2::new(
            2.0 * (x as f32 + offset.x) / width as f32 - 1.0,
            1.0 - 2.0 * (y as f32 + offset.y) / height as f32,
        )
    }

    /// The view matrix of the virtual camera behind a planar mirror: `view * R`
    /// with `R` the reflection about `plane`. It has negative determinant, so
    /// front faces wind the other way and the pass must flip its cull mode.
    pub fn mirrored_view_matrix(&self, plane: &Plane) -> Mat4 {
        self.view_matrix() * plane.reflection_matrix()
    }

    /// The camera mirrored about `plane`: position and target reflected, up
    /// reflected. This is a proper (rotation) camera; it sees the mirror image
    /// flipped left to right relative to [`Camera::mirrored_view_matrix`].
    pub fn reflected(&self, plane: &Plane) -> Self {
        Self {
            position: plane.reflect_point(self.position),
            target: plane.reflect_point(self.target),
            up: plane.reflect_vector(self.up),
            ..*self
        }
    }
}
