//! Shared helpers of the `lustre-beams` tests: a small deterministic random stream and the test scatterers.

#![allow(dead_code)]

use glam::Vec3;
use lustre_beams::{ScatterMaterial, Scatterer};
use lustre_geometry::{Aabb, Rgb};

/// xorshift64*: deterministic, no dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    pub fn f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn f32(&mut self) -> f32 {
        self.f64() as f32
    }

    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f32()
    }

    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 1e-3 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// Barycentric coordinates uniform over the triangle, each at least `margin`.
    pub fn barycentrics(&mut self, margin: f32) -> [f32; 3] {
        loop {
            let (u, v) = (self.f32(), self.f32());
            let b = [u, v, 1.0 - u - v];
            if b.iter().all(|&x| x >= margin) {
                return b;
            }
        }
    }
}

/// The light of the mirror tests.
pub const LIGHT: Vec3 = Vec3::new(0.3, 3.0, 0.2);
/// Its intensity, W/sr.
pub const INTENSITY: Rgb = Rgb::new(5.0, 7.0, 9.0);
/// The mirror's reflectance.
pub const REFLECTANCE: Rgb = Rgb::new(0.9, 0.8, 0.7);

/// A mirror triangle in the plane y = 0, facing +y.
pub fn mirror_triangle(roughness: f32) -> Scatterer {
    mirror_triangle_scaled(roughness, 1.0)
}

/// [`mirror_triangle`] scaled about the origin by `scale`.
pub fn mirror_triangle_scaled(roughness: f32, scale: f32) -> Scatterer {
    Scatterer::flat(
        [
            Vec3::new(-0.4, 0.0, -0.3) * scale,
            Vec3::new(0.0, 0.0, 0.45) * scale,
            Vec3::new(0.5, 0.0, -0.2) * scale,
        ],
        ScatterMaterial::Reflector {
            reflectance: REFLECTANCE,
            conductor: None,
            roughness,
        },
    )
}

/// The box the mirror tests evaluate in.
pub fn bounds() -> Aabb {
    Aabb {
        min: Vec3::new(-6.0, -6.0, -6.0),
        max: Vec3::new(6.0, 6.0, 6.0),
    }
}

/// `Σ b_i v_i`.
pub fn lerp3(v: [Vec3; 3], b: [f32; 3]) -> Vec3 {
    v[0] * b[0] + v[1] * b[1] + v[2] * b[2]
}
