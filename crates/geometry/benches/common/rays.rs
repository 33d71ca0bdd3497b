//! The benches' ray sets, shared by the criterion bench `bvh` and the example
//! `embree_compare` (included with `#[path]`).

use glam::{Vec2, Vec3};
use lustre_geometry::sampling::sample_uniform_sphere;
use lustre_geometry::{Camera, Ray};

/// A deterministic stream of numbers in [0, 1) (SplitMix64) for ray generation.
struct Stream(u64);

impl Stream {
    /// The next number of the SplitMix64 sequence (Steele et al. 2014), 24 bits in [0, 1).
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Coherent rays: one primary ray through the centre of each pixel of a `side`×`side` image, row by row.
pub fn primary_rays(camera: &Camera, side: u32) -> Vec<Ray> {
    (0..side * side)
        .map(|i| {
            camera.primary_ray(Camera::pixel_ndc(
                i % side,
                i / side,
                side,
                side,
                Vec2::splat(0.5),
            ))
        })
        .collect()
}

/// Incoherent rays: `n` rays from random points inside `lo..hi` in uniformly random directions.
pub fn random_rays(lo: Vec3, hi: Vec3, n: u32, seed: u64) -> Vec<Ray> {
    let mut s = Stream(seed);
    (0..n)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(s.next(), s.next(), s.next());
            Ray::new(o, sample_uniform_sphere(Vec2::new(s.next(), s.next())))
        })
        .collect()
}
