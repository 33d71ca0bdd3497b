//! Shared helpers: a ray-cast radiance source over a built-in scene whose surfaces have distinct constant radiances.

#![allow(dead_code)]

use glam::Vec3;
use lustre_geometry::{Bvh, Ray, Rgb, Scene, SurfaceKind, builtin};
use lustre_ibr::Reflector;

/// A distinct, view-independent radiance per surface.
pub fn surface_radiance(surface: u32) -> Rgb {
    let h = surface.wrapping_mul(2_654_435_761);
    Rgb::new(
        0.1 + (h & 0xff) as f32 / 255.0,
        0.1 + ((h >> 8) & 0xff) as f32 / 255.0,
        0.1 + ((h >> 16) & 0xff) as f32 / 255.0,
    )
}

/// The scene, its BVH, and its floor as a reflector.
pub struct Room {
    pub scene: Scene,
    pub bvh: Bvh,
    pub floor: Reflector,
}

impl Room {
    /// `cornell` with its floor as the reflector.
    pub fn cornell() -> Self {
        let scene = builtin("cornell").unwrap();
        let bvh = Bvh::build(&scene);
        let (id, _) = scene
            .surfaces()
            .iter()
            .enumerate()
            .find(|(_, s)| matches!(s.kind, SurfaceKind::Planar(p) if p.normal.y > 0.99 && s.area > 3.0))
            .expect("the floor");
        let floor = Reflector::from_surface(&scene, id as u32).unwrap();
        Self { scene, bvh, floor }
    }

    /// Radiance and distance along a ray, skipping the reflector itself.
    pub fn trace(&self, origin: Vec3, direction: Vec3) -> Option<(Rgb, f32)> {
        let hit = self
            .bvh
            .closest_hit(&Ray::segment(origin, direction, 1e-4, f32::INFINITY))?;
        Some((surface_radiance(hit.surface), hit.t))
    }
}
