//! Sample cameras on the hemisphere behind each reflector element, with off-axis frusta through the element (Bastos et al. 1999, section 8.1.3, "Sampling of the plenoptic function", figure 4 left).
//!
//! **Hemisphere points at evenly spaced arc lengths.** The hemisphere of
//! radius `r` (the element's half diagonal) lies behind the reflector, on
//! the side opposite its normal `n`: there the reflected eye lies, seeing
//! the scene in front of the reflector through it. Its points are taken on
//! rings of polar angle `θk = k Δ` from `-n` (`Δ` the arc step in radians;
//! neighbouring rings are `r Δ` apart along the sphere), for `θk` below
//! [`SamplingSettings::max_polar_degrees`] (a camera in the reflector's
//! plane has a degenerate frustum); ring `k` holds
//! `max(1, round(2π sin θk / Δ))` points at azimuths `φ = 2π (i + ½ (k mod
//! 2)) / count` (alternate rings offset by half a step), so that points on a
//! ring are also about `r Δ` apart. Arc steps of 60°, 45° and 30° give 6, 7
//! and 17 cameras a hemisphere, three of the counts of the paper's table 1.
//!
//! **Off-axis frustum.** A camera's centre of projection is its hemisphere
//! point `p`, at height `h = r cos θ` behind the plane; its image plane is
//! the reflector's plane and its image the element: texel `(i, j)` of a
//! `W × H` map is the point `q = c + s a u + t b v` of the element, with
//! `s = 2 (i + ½)/W − 1`, `t = 2 (j + ½)/H − 1` (`a`, `b` the element's
//! half-extents). Depth is the distance along `n` from `p`'s parallel
//! plane, `z = (X − p)·n`, so the point of texel `(i, j)` at depth `z` is
//! `X = p + (q − p) z / h` and the element itself is at `z = h`, the near
//! plane (nothing behind the reflector is seen). As a pinhole camera with
//! axes `(u, −v, n)` (rows run along `+v`), its focal lengths in pixels
//! are `fx = W h / (2a)`, `fy = H h / (2b)` and its principal point
//! `(W/2 − fx (c − p)·u / h, H/2 − fy (c − p)·v / h)`.

use glam::{Vec2, Vec3};

use crate::error::{Result, out_of_range};
use crate::reflector::ReflectorElement;
use crate::view::PinholeView;

/// How the reflectors are sampled: planar resolution, arc step on the hemisphere, radiance map resolution (section 8.1.3, table 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingSettings {
    /// Reflector elements along the reflector's `u` and `v` (the planar resolution).
    pub planar_resolution: (u32, u32),
    /// Arc length between neighbouring cameras on a hemisphere, as an angle in degrees.
    pub arc_step_degrees: f32,
    /// Cameras are placed at polar angles below this (degrees from the axis behind the reflector).
    pub max_polar_degrees: f32,
    /// Texels of each radiance map along `u` and `v`.
    pub map_resolution: (u32, u32),
}

impl Default for SamplingSettings {
    /// One element, a 30° arc step (17 cameras), 128 × 128 maps: the paper's door mirrors per hemisphere (table 1).
    fn default() -> Self {
        Self {
            planar_resolution: (1, 1),
            arc_step_degrees: 30.0,
            max_polar_degrees: 85.0,
            map_resolution: (128, 128),
        }
    }
}

impl SamplingSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<()> {
        let (nu, nv) = self.planar_resolution;
        if !(1..=1024).contains(&nu) || !(1..=1024).contains(&nv) {
            return Err(out_of_range(
                "planar resolution",
                format!("{nu}x{nv}"),
                "1 to 1024 elements per side",
            ));
        }
        if !(self.arc_step_degrees >= 1.0 && self.arc_step_degrees <= 90.0) {
            return Err(out_of_range(
                "arc step",
                format!("{}°", self.arc_step_degrees),
                "1° to 90°",
            ));
        }
        if !(self.max_polar_degrees > 0.0 && self.max_polar_degrees < 90.0) {
            return Err(out_of_range(
                "maximum polar angle",
                format!("{}°", self.max_polar_degrees),
                "above 0° and below 90°",
            ));
        }
        let (w, h) = self.map_resolution;
        if !(1..=4096).contains(&w) || !(1..=4096).contains(&h) {
            return Err(out_of_range(
                "radiance map resolution",
                format!("{w}x{h}"),
                "1 to 4096 texels per side",
            ));
        }
        Ok(())
    }
}

/// One sample camera: a hemisphere point as centre of projection and its reflector element as near plane (section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleCamera {
    /// Index of its hemisphere (reflector element) within the reflector.
    pub hemisphere: u32,
    /// The element it looks through.
    pub element: ReflectorElement,
    /// Centre of projection, on the hemisphere behind the element.
    pub position: Vec3,
    /// Polar angle from the axis behind the element, radians.
    pub polar: f32,
    /// Azimuth about that axis from `u` towards `v`, radians.
    pub azimuth: f32,
}

/// The unit directions `(polar, azimuth)` of the cameras on one hemisphere at arc step `step` (radians), polar angles below `max_polar` (module documentation).
pub fn hemisphere_directions(step: f32, max_polar: f32) -> Vec<(f32, f32)> {
    let mut out = Vec::new();
    let mut k = 0u32;
    loop {
        let polar = k as f32 * step;
        if polar >= max_polar {
            break;
        }
        let count = if k == 0 {
            1
        } else {
            ((std::f32::consts::TAU * polar.sin() / step).round() as u32).max(1)
        };
        let offset = if k % 2 == 1 { 0.5 } else { 0.0 };
        for i in 0..count {
            let azimuth = std::f32::consts::TAU * (i as f32 + offset) / count as f32;
            out.push((polar, azimuth));
        }
        k += 1;
    }
    out
}

impl SampleCamera {
    /// The camera of `element` at polar angle `polar` and azimuth `azimuth` (radians) on its hemisphere.
    pub fn new(hemisphere: u32, element: ReflectorElement, polar: f32, azimuth: f32) -> Self {
        let r = element.hemisphere_radius();
        let (sp, cp) = polar.sin_cos();
        let (sa, ca) = azimuth.sin_cos();
        let position = element.centre
            + (element.u * (sp * ca) + element.v * (sp * sa) - element.normal * cp) * r;
        Self {
            hemisphere,
            element,
            position,
            polar,
            azimuth,
        }
    }

    /// Height `h` of the centre of projection behind the reflector's plane.
    pub fn height(&self) -> f32 {
        (self.element.centre - self.position).dot(self.element.normal)
    }

    /// The point of the element at map coordinates `(s, t)` in [-1, 1]².
    pub fn element_point(&self, s: f32, t: f32) -> Vec3 {
        let e = &self.element;
        e.centre + e.u * (s * e.half_u) + e.v * (t * e.half_v)
    }

    /// Map coordinates `(s, t)` of texel `(i, j)`'s centre in a `w × h` map.
    pub fn texel_st(i: u32, j: u32, w: u32, h: u32) -> Vec2 {
        Vec2::new(
            2.0 * (i as f32 + 0.5) / w as f32 - 1.0,
            2.0 * (j as f32 + 0.5) / h as f32 - 1.0,
        )
    }

    /// The world point at depth `z` along the ray of map coordinates `(s, t)`: `p + (q − p) z / h`.
    pub fn unproject(&self, st: Vec2, z: f32) -> Vec3 {
        let q = self.element_point(st.x, st.y);
        self.position + (q - self.position) * (z / self.height())
    }

    /// Map coordinates and depth `(s, t, z)` of world point `x`, `None` unless it lies beyond the near plane (`z > h`).
    pub fn project(&self, x: Vec3) -> Option<(Vec2, f32)> {
        let e = &self.element;
        let z = (x - self.position).dot(e.normal);
        let h = self.height();
        if !(z > h) {
            return None;
        }
        let q = self.position + (x - self.position) * (h / z);
        let d = q - e.centre;
        Some((Vec2::new(d.dot(e.u) / e.half_u, d.dot(e.v) / e.half_v), z))
    }

    /// The camera as a pinhole view of a `w × h` image whose pixel `(i, j)` is texel `(i, j)` (module documentation).
    pub fn pinhole(&self, w: u32, h: u32) -> PinholeView {
        let e = &self.element;
        let height = self.height();
        let fx = w as f32 * height / (2.0 * e.half_u);
        let fy = h as f32 * height / (2.0 * e.half_v);
        let o = e.centre - self.position;
        PinholeView {
            eye: self.position,
            right: e.u,
            up: -e.v,
            forward: e.normal,
            focal: Vec2::new(fx, fy),
            principal: Vec2::new(
                0.5 * w as f32 - fx * o.dot(e.u) / height,
                0.5 * h as f32 - fy * o.dot(e.v) / height,
            ),
            width: w,
            height: h,
        }
    }
}

/// Every sample camera of `elements` under `settings`, hemisphere by hemisphere (section 8.1.3).
pub fn sample_cameras(
    elements: &[ReflectorElement],
    settings: &SamplingSettings,
) -> Result<Vec<SampleCamera>> {
    settings.validate()?;
    let directions = hemisphere_directions(
        settings.arc_step_degrees.to_radians(),
        settings.max_polar_degrees.to_radians(),
    );
    Ok(elements
        .iter()
        .enumerate()
        .flat_map(|(k, &e)| {
            directions
                .iter()
                .map(move |&(polar, azimuth)| SampleCamera::new(k as u32, e, polar, azimuth))
        })
        .collect())
}
