//! `pool`: a refractive water surface of 20 × 20 × 2 triangles over a diffuse pool floor, its waves animated over time, lit by a point light above (Duvenhage, Bouatouch & Kourie 2010, figure 3: "caustics from a fluid's surface (20×20×2 scattering triangles)").
//!
//! Geometry, in metres (+y up):
//!
//! - Pool floor: the square x, z ∈ [-1, 1] at y = 0 (diffuse, facing up);
//!   four diffuse walls from y = 0 to [`WALL_HEIGHT`] facing inwards.
//! - Water: a [`WATER_CELLS`] × [`WATER_CELLS`] grid of quads (two
//!   triangles each, shared vertices with smooth normals from the wave's
//!   gradient) over the same square at height [`water_height`]: the mean
//!   level [`WATER_LEVEL`] plus three travelling sine waves
//!   ([`WAVES`]); a smooth dielectric of index 1.33.
//! - Light: an isotropic point light at [`LIGHT_POSITION`], above the water.
//! - Camera above a corner, looking at the pool's centre, 50°.

use glam::{Vec2, Vec3};

use super::parts::quad;
use crate::Object;
use crate::light::PointLight;
use crate::{Camera, Light, Material, MaterialModel, Mesh, Rgb, Scene};

/// Quads along each side of the water surface.
pub const WATER_CELLS: usize = 20;
/// Mean height of the water surface.
pub const WATER_LEVEL: f32 = 0.5;
/// Height of the pool's walls.
pub const WALL_HEIGHT: f32 = 0.7;
/// Index of refraction of water.
pub const WATER_IOR: f32 = 1.33;
/// The waves: amplitude (m), wave vector (rad/m) and angular frequency (rad/s).
pub const WAVES: [(f32, Vec2, f32); 3] = [
    (0.012, Vec2::new(6.0, 2.0), 2.1),
    (0.008, Vec2::new(-3.0, 7.0), 2.9),
    (0.005, Vec2::new(9.0, -5.0), 3.7),
];
/// Where the point light is.
pub const LIGHT_POSITION: Vec3 = Vec3::new(0.3, 2.5, 0.2);
/// Its intensity, W/sr.
pub const LIGHT_INTENSITY: Rgb = Rgb::new(6.0, 6.0, 6.0);

/// The water's height at `(x, z)` and time `t` (seconds): `WATER_LEVEL + Σ a sin(k·(x, z) - ω t)`.
pub fn water_height(x: f32, z: f32, t: f32) -> f32 {
    WAVES.iter().fold(WATER_LEVEL, |h, &(a, k, w)| {
        h + a * (k.dot(Vec2::new(x, z)) - w * t).sin()
    })
}

/// The water surface's unit normal at `(x, z)` and time `t`: `(-∂h/∂x, 1, -∂h/∂z)` normalised.
pub fn water_normal(x: f32, z: f32, t: f32) -> Vec3 {
    let g = WAVES.iter().fold(Vec2::ZERO, |g, &(a, k, w)| {
        g + a * k * (k.dot(Vec2::new(x, z)) - w * t).cos()
    });
    Vec3::new(-g.x, 1.0, -g.y).normalize()
}

/// `pool` at time 0 ([`pool_at`]).
pub fn pool() -> Scene {
    pool_at(0.0)
}

/// `pool` with its waves at time `t` in seconds (Duvenhage et al. 2010, figure 3).
pub fn pool_at(t: f32) -> Scene {
    let (tile, water) = (0, 1);
    let materials = vec![
        Material::diffuse("tile", Rgb::new(0.55, 0.7, 0.75)),
        Material::new(
            "water",
            MaterialModel::Dielectric {
                ior: WATER_IOR,
                transmittance: Rgb::ONE,
            },
        ),
    ];
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let wall = WALL_HEIGHT;
    let mut meshes = vec![
        quad("floor", Vec3::new(-1.0, 0.0, -1.0), 2.0 * z, 2.0 * x, tile),
        quad(
            "wall-west",
            Vec3::new(-1.0, 0.0, -1.0),
            wall * y,
            2.0 * z,
            tile,
        ),
        quad(
            "wall-east",
            Vec3::new(1.0, 0.0, -1.0),
            2.0 * z,
            wall * y,
            tile,
        ),
        quad(
            "wall-north",
            Vec3::new(-1.0, 0.0, -1.0),
            2.0 * x,
            wall * y,
            tile,
        ),
        quad(
            "wall-south",
            Vec3::new(-1.0, 0.0, 1.0),
            wall * y,
            2.0 * x,
            tile,
        ),
    ];
    let n = WATER_CELLS;
    let mut surface = Mesh {
        name: "water".into(),
        positions: Vec::with_capacity((n + 1) * (n + 1)),
        normals: Vec::with_capacity((n + 1) * (n + 1)),
        uvs: Vec::with_capacity((n + 1) * (n + 1)),
        indices: Vec::with_capacity(2 * n * n),
        material: water,
    };
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            let (px, pz) = (-1.0 + 2.0 * u, -1.0 + 2.0 * v);
            surface
                .positions
                .push(Vec3::new(px, water_height(px, pz, t), pz));
            surface.normals.push(water_normal(px, pz, t));
            surface.uvs.push(Vec2::new(u, v));
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from above.
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            surface.indices.push([a, d, c]);
            surface.indices.push([a, c, b]);
        }
    }
    meshes.push(surface);
    let camera = Camera::look_at(
        Vec3::new(1.9, 2.0, 2.3),
        Vec3::new(0.0, 0.2, 0.0),
        Vec3::Y,
        50.0,
    );
    let lights = vec![Light::Point(PointLight {
        position: LIGHT_POSITION,
        intensity: LIGHT_INTENSITY,
    })];
    Scene::new(
        "pool",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        lights,
        camera,
    )
    .expect("the built-in pool scene is valid")
}
