//! Radiance maps with depth: per texel the outgoing radiance and the depth of the point its ray reaches (Bastos et al. 1999, section 8.1.3, "Radiance maps with depth").
//!
//! The radiance stored is the view-independent solution D (a diffuse
//! radiosity, here the scene's real global illumination), so a texel's
//! value holds from any viewpoint and reprojection can move it to a new
//! view. Radiance is kept at half precision (6 bytes a texel, HDR) and
//! depth as `f32` (the camera's `z`, [`crate::sampling`]); a texel whose ray
//! leaves the scene has depth `+∞` and no radiance. What the maps see comes
//! from a [`RadianceSource`]: on the CPU a ray caster (this module's
//! [`RadianceMap::capture`], the reference), on the GPU the capture pass
//! of `lustre-mpr`, which draws D from each sample camera.

use glam::Vec3;
use half::f16;
use lustre_geometry::Rgb;
use rayon::prelude::*;

use crate::sampling::SampleCamera;

/// What a radiance map sees along a ray: the radiance leaving the first surface hit towards the ray's origin and the distance to it, or `None` if the ray leaves the scene.
pub trait RadianceSource: Sync {
    /// Radiance and hit distance along the ray from `origin` in unit direction `direction`.
    fn trace(&self, origin: Vec3, direction: Vec3) -> Option<(Rgb, f32)>;
}

impl<F> RadianceSource for F
where
    F: Fn(Vec3, Vec3) -> Option<(Rgb, f32)> + Sync,
{
    fn trace(&self, origin: Vec3, direction: Vec3) -> Option<(Rgb, f32)> {
        self(origin, direction)
    }
}

/// A radiance map with depth: `width × height` texels of radiance (half precision) and depth, seen by one sample camera (section 8.1.3).
#[derive(Debug, Clone, PartialEq)]
pub struct RadianceMap {
    /// The camera it was captured from.
    pub camera: SampleCamera,
    /// Texels along the element's `u`.
    pub width: u32,
    /// Texels along the element's `v`.
    pub height: u32,
    /// Radiance per texel, row-major (rows along `v`), RGB at half precision.
    pub radiance: Vec<[f16; 3]>,
    /// Depth `z` per texel (`+∞`: nothing seen).
    pub depth: Vec<f32>,
}

/// Bytes a texel takes: three half-precision radiance channels and an `f32` depth.
pub const TEXEL_BYTES: usize = 3 * 2 + 4;

impl RadianceMap {
    /// Captures the map of `camera` at `width × height` by tracing one ray per texel centre from the element into the scene (the CPU reference of the capture pass).
    pub fn capture(
        camera: &SampleCamera,
        width: u32,
        height: u32,
        source: &dyn RadianceSource,
    ) -> Self {
        Self::capture_texels(camera, width, height, &|_, q, dir| source.trace(q, dir))
    }

    /// Captures the map of `camera` from `texel(k, q, dir)`: the radiance and hit distance of texel `k` (row-major), whose ray leaves element point `q` in unit direction `dir` (a GPU image read back, with its distances ray cast, goes through here).
    pub fn capture_texels(
        camera: &SampleCamera,
        width: u32,
        height: u32,
        texel: &(dyn Fn(usize, Vec3, Vec3) -> Option<(Rgb, f32)> + Sync),
    ) -> Self {
        let h = camera.height();
        let texels: Vec<([f16; 3], f32)> = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let st = SampleCamera::texel_st(k % width, k / width, width, height);
                let q = camera.element_point(st.x, st.y);
                let dir = (q - camera.position).normalize();
                match texel(k as usize, q, dir) {
                    Some((radiance, t)) if t.is_finite() && t >= 0.0 => {
                        // z grows along the ray by dir·n per unit distance, from h at q.
                        let z = h + t * dir.dot(camera.element.normal);
                        (to_half(radiance), z)
                    }
                    _ => ([f16::ZERO; 3], f32::INFINITY),
                }
            })
            .collect();
        let (radiance, depth) = texels.into_iter().unzip();
        Self {
            camera: *camera,
            width,
            height,
            radiance,
            depth,
        }
    }

    /// Texel index of `(i, j)`.
    pub fn index(&self, i: u32, j: u32) -> usize {
        (j * self.width + i) as usize
    }

    /// Radiance of texel `(i, j)`.
    pub fn radiance_at(&self, i: u32, j: u32) -> Rgb {
        let [r, g, b] = self.radiance[self.index(i, j)];
        Rgb::new(r.to_f32(), g.to_f32(), b.to_f32())
    }

    /// The world point texel `(i, j)` sees, `None` where it sees nothing.
    pub fn world_point(&self, i: u32, j: u32) -> Option<Vec3> {
        let z = self.depth[self.index(i, j)];
        z.is_finite().then(|| {
            self.camera
                .unproject(SampleCamera::texel_st(i, j, self.width, self.height), z)
        })
    }

    /// Bytes of its texels ([`TEXEL_BYTES`] each).
    pub fn texel_bytes(&self) -> usize {
        self.depth.len() * TEXEL_BYTES
    }
}

/// RGB at half precision, clamped to half's finite range.
pub fn to_half(c: Rgb) -> [f16; 3] {
    let h = |x: f32| {
        f16::from_f32(if x.is_finite() {
            x.clamp(0.0, 65504.0)
        } else {
            0.0
        })
    };
    [h(c.x), h(c.y), h(c.z)]
}
