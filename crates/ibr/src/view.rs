//! The pinhole view that radiance maps are captured from and reprojected into: a sample camera's off-axis frustum, or the reflected view of the eye (Bastos et al. 1999, section 8.1.3, "Reprojection").
//!
//! A view maps a world point `X` to camera coordinates
//! `(xc, yc, zc) = ((X − eye)·right, (X − eye)·up, (X − eye)·forward)` and to
//! the pixel `(cx + fx xc/zc, cy − fy yc/zc)` (row 0 at the top), visible
//! where `zc > 0`. The axes need not form a right-handed frame: the
//! reflected view ([`PinholeView::mirrored`]) is the eye's frame mirrored
//! about the reflector's plane, a left-handed one, which maps a point `X`
//! to the pixel where the eye sees its mirror image `R X` — the image that
//! overlays the reflector (Diefenbach's mirrored view matrix `view · R`).

use glam::{Vec2, Vec3};
use lustre_geometry::{Camera, Plane};

/// A pinhole view: centre of projection, axes, focal lengths and principal point in pixels, image size (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeView {
    /// Centre of projection.
    pub eye: Vec3,
    /// Unit axis of increasing pixel column.
    pub right: Vec3,
    /// Unit axis of decreasing pixel row.
    pub up: Vec3,
    /// Unit viewing axis; depth is measured along it.
    pub forward: Vec3,
    /// Focal lengths `(fx, fy)` in pixels.
    pub focal: Vec2,
    /// Principal point `(cx, cy)` in pixels.
    pub principal: Vec2,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl PinholeView {
    /// The view of `camera` for a `width × height` image (its jitter included).
    pub fn from_camera(camera: &Camera, width: u32, height: u32) -> Self {
        let (right, up, forward) = camera.frame();
        let tan_half = (0.5 * camera.fov_y_degrees.to_radians()).tan();
        let fy = height as f32 / (2.0 * tan_half);
        let fx = width as f32 / (2.0 * tan_half * camera.aspect);
        let principal = Vec2::new(
            0.5 * width as f32 * (1.0 + camera.jitter.x),
            0.5 * height as f32 * (1.0 - camera.jitter.y),
        );
        Self {
            eye: camera.position,
            right,
            up,
            forward,
            focal: Vec2::new(fx, fy),
            principal,
            width,
            height,
        }
    }

    /// The reflected view of `camera` about `plane`: eye and axes mirrored, so that it images a point where the eye sees the point's mirror image (module documentation).
    pub fn mirrored(camera: &Camera, plane: &Plane, width: u32, height: u32) -> Self {
        Self::from_camera(camera, width, height).reflected(plane)
    }

    /// This view reflected about `plane`: eye and axes mirrored, pixels kept.
    pub fn reflected(&self, plane: &Plane) -> Self {
        Self {
            eye: plane.reflect_point(self.eye),
            right: plane.reflect_vector(self.right),
            up: plane.reflect_vector(self.up),
            forward: plane.reflect_vector(self.forward),
            ..*self
        }
    }

    /// The same view on a grid `scale` times coarser: `⌈width/scale⌉ × ⌈height/scale⌉` pixels, focal lengths and principal point divided by `scale`, so coarse pixel coordinates are the fine ones over `scale` ([`crate::resolution`]).
    pub fn coarsened(&self, scale: u32) -> Self {
        let s = scale.max(1);
        Self {
            focal: self.focal / s as f32,
            principal: self.principal / s as f32,
            width: self.width.div_ceil(s),
            height: self.height.div_ceil(s),
            ..*self
        }
    }

    /// Camera coordinates `(xc, yc, zc)` of world point `x`.
    pub fn camera_coordinates(&self, x: Vec3) -> Vec3 {
        let d = x - self.eye;
        Vec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Pixel position and depth `zc` of world point `x`, `None` unless `zc > 0`.
    pub fn project(&self, x: Vec3) -> Option<(Vec2, f32)> {
        let c = self.camera_coordinates(x);
        if !(c.z > 0.0) {
            return None;
        }
        Some((self.pixel(c), c.z))
    }

    /// The pixel position of camera coordinates `c` (with `c.z > 0`).
    pub fn pixel(&self, c: Vec3) -> Vec2 {
        Vec2::new(
            self.principal.x + self.focal.x * c.x / c.z,
            self.principal.y - self.focal.y * c.y / c.z,
        )
    }

    /// The unit direction from the eye through pixel position `pixel`.
    pub fn direction(&self, pixel: Vec2) -> Vec3 {
        let x = (pixel.x - self.principal.x) / self.focal.x;
        let y = (self.principal.y - pixel.y) / self.focal.y;
        (self.forward + self.right * x + self.up * y).normalize()
    }
}
