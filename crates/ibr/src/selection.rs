//! Selection of the radiance maps to reproject for a reflected view: per hemisphere, the cameras of minimal angle to the reflected view, or the nearest ones (Bastos et al. 1999, section 8.1.3, "Selection", figure 4 right).
//!
//! The eye is mirrored about the reflector's plane. For the angle-based
//! selection each hemisphere compares the direction from the mirrored eye
//! to the hemisphere's centre with the direction from each of its cameras
//! to that centre and keeps the `k` of least angle: those whose maps hold
//! the most radiance resolution in the reflected view direction. With a
//! single hemisphere the centre is the reflector's, the paper's wording;
//! with several, each element's own centre is used, so that every
//! hemisphere contributes its best-aligned maps (the paper selects two maps
//! "for each hemisphere" in its timings). The distance-based selection
//! keeps the `k` cameras of each hemisphere nearest to the mirrored eye.

use glam::Vec3;

use crate::sampling::SampleCamera;

/// How the maps of a hemisphere are ranked (section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SelectionRule {
    /// Least angle between the mirrored eye's and the camera's direction to the hemisphere's centre.
    #[default]
    MinimalAngle,
    /// Least distance between the camera and the mirrored eye.
    Distance,
}

/// The indices into `cameras` of the `k` best cameras of each hemisphere for mirrored eye `mirrored_eye` under `rule`, best first within a hemisphere, hemispheres in order.
pub fn select(
    cameras: &[SampleCamera],
    mirrored_eye: Vec3,
    k: usize,
    rule: SelectionRule,
) -> Vec<usize> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < cameras.len() {
        let hemisphere = cameras[start].hemisphere;
        let end = cameras[start..]
            .iter()
            .position(|c| c.hemisphere != hemisphere)
            .map_or(cameras.len(), |n| start + n);
        let mut ranked: Vec<(f32, usize)> = (start..end)
            .map(|i| (score(&cameras[i], mirrored_eye, rule), i))
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out.extend(ranked.into_iter().take(k).map(|(_, i)| i));
        start = end;
    }
    out
}

/// The rank of `camera` for `mirrored_eye`: an angle in radians or a distance (less is better).
pub fn score(camera: &SampleCamera, mirrored_eye: Vec3, rule: SelectionRule) -> f32 {
    match rule {
        SelectionRule::MinimalAngle => {
            let centre = camera.element.centre;
            let a = (centre - mirrored_eye).normalize_or_zero();
            let b = (centre - camera.position).normalize_or_zero();
            a.dot(b).clamp(-1.0, 1.0).acos()
        }
        SelectionRule::Distance => camera.position.distance(mirrored_eye),
    }
}
