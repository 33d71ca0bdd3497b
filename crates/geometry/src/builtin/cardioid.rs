//! `cardioid`: a ring of specular triangles on a diffuse floor lit by a point light near the ring, whose reflections gather in a cardioid caustic (Duvenhage, Bouatouch & Kourie 2010, figure 2: "a cardioid caustic (40×2 scattering triangles)"; section 3.1: "the cylindrical reflector is composed of a mesh of 80 specular scattering triangles").
//!
//! Geometry, in metres (+y up):
//!
//! - Floor: the square x, z ∈ [-1.5, 1.5] at y = 0 (diffuse, facing up).
//! - Ring: [`RING_SEGMENTS`] = 40 flat mirror quads (80 triangles) round the
//!   circle of radius [`RING_RADIUS`] about the y axis, from y = 0 to
//!   [`RING_HEIGHT`], facing the axis; reflectance [`RING_REFLECTANCE`].
//! - Light: an isotropic point light ([`LIGHT_POSITION`]) just inside the
//!   ring at x = 0.95 R, above the ring's top, intensity
//!   [`LIGHT_INTENSITY`]: light from (near) a point of the circle reflected
//!   once off the circle gathers on the cardioid `r(φ) = (R/2)(1 + cos φ)`
//!   about the light's side (scaled on the floor by the light's height).
//! - Camera above the ring on the side away from the light, looking down at
//!   the floor's centre, 50° vertical field of view.

use std::f32::consts::TAU;

use glam::Vec3;

use super::parts::quad;
use crate::Object;
use crate::light::PointLight;
use crate::{Camera, Light, Material, MaterialModel, Mesh, Rgb, Scene};

/// Radius of the ring.
pub const RING_RADIUS: f32 = 1.0;
/// Height of the ring's wall.
pub const RING_HEIGHT: f32 = 0.25;
/// Flat quads round the ring (two triangles each).
pub const RING_SEGMENTS: usize = 40;
/// Reflectance of the ring.
pub const RING_REFLECTANCE: Rgb = Rgb::new(0.95, 0.9, 0.8);
/// Reflectance of the floor.
pub const FLOOR_REFLECTANCE: Rgb = Rgb::new(0.6, 0.6, 0.6);
/// Where the point light is.
pub const LIGHT_POSITION: Vec3 = Vec3::new(0.95 * RING_RADIUS, 0.4, 0.0);
/// Its intensity, W/sr.
pub const LIGHT_INTENSITY: Rgb = Rgb::new(2.0, 2.0, 2.0);

/// `cardioid`: the ring of 80 specular triangles on a diffuse floor (Duvenhage et al. 2010, figure 2).
pub fn cardioid() -> Scene {
    cardioid_with(RING_SEGMENTS)
}

/// `cardioid` with its ring cut into `segments` quads (two mirror triangles each; at least 3), the same ring and caustic with more scatterers (the beam benchmarks' 80 to 10,000 triangles).
pub fn cardioid_with(segments: usize) -> Scene {
    let segments = segments.max(3);
    let (floor, ring) = (0, 1);
    let materials = vec![
        Material::diffuse("floor", FLOOR_REFLECTANCE),
        Material::new(
            "ring",
            MaterialModel::Mirror {
                reflectance: RING_REFLECTANCE,
            },
        ),
    ];
    let h = 1.5;
    let mut meshes = vec![quad(
        "floor",
        Vec3::new(-h, 0.0, -h),
        2.0 * h * Vec3::Z,
        2.0 * h * Vec3::X,
        floor,
    )];
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..segments {
        let at = |k: usize, y: f32| {
            let a = TAU * k as f32 / segments as f32;
            Vec3::new(RING_RADIUS * a.cos(), y, RING_RADIUS * a.sin())
        };
        let base = positions.len() as u32;
        positions.extend([
            at(i, 0.0),
            at(i + 1, 0.0),
            at(i + 1, RING_HEIGHT),
            at(i, RING_HEIGHT),
        ]);
        // Counter-clockwise seen from the axis: facing inwards.
        indices.push([base, base + 1, base + 2]);
        indices.push([base, base + 2, base + 3]);
    }
    meshes.push(Mesh::flat("ring", &positions, &indices, ring));
    let camera = Camera::look_at(
        Vec3::new(-1.6, 2.2, 1.2),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        50.0,
    );
    let lights = vec![Light::Point(PointLight {
        position: LIGHT_POSITION,
        intensity: LIGHT_INTENSITY,
    })];
    Scene::new(
        "cardioid",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        lights,
        camera,
    )
    .expect("the built-in cardioid scene is valid")
}
