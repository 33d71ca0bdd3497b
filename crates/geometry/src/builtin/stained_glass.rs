//! `stained-glass`: a stained-glass window lit from behind by a point light, throwing coloured glossy beams onto the floor of a room; the panes' roughness is a parameter (Duvenhage, Bouatouch & Kourie 2010, figures 1, 13 and 14: "a stained glass window lit from behind with varying roughness of the glass").
//!
//! Geometry, in metres (+y up):
//!
//! - Room: floor x ∈ [-2, 2], z ∈ [0, 4] at y = 0 (diffuse, facing up); the
//!   window wall in the plane z = 0 facing +z (into the room), 3 m high,
//!   with a hole for the window.
//! - Window: x ∈ [-0.6, 0.6], y ∈ [1.0, 2.2] in the plane z = 0, a
//!   [`PANES`] × [`PANES`] grid of square panes (two triangles each, facing
//!   the light at -z), each a thin glass slab (`Named` model
//!   `thin-dielectric`: `ior` 1.5, `roughness` Beckmann α of both faces,
//!   0 in the built-in scene ([`DEFAULT_ROUGHNESS`]) and any value through
//!   [`stained_glass_with`], `transmittance` one of [`PALETTE`]).
//! - Light: an isotropic point light outside at [`LIGHT_POSITION`], so
//!   that the light through the window falls on the floor about z ∈ [1, 3].
//! - Camera inside the room looking back at the window and the floor.

use std::collections::BTreeMap;

use glam::Vec3;

use super::parts::quad;
use crate::Object;
use crate::light::PointLight;
use crate::{Camera, Light, Material, MaterialModel, Mesh, Rgb, Scene};

/// Panes along each side of the window.
pub const PANES: usize = 4;
/// The window's corner (smallest x and y) and size.
pub const WINDOW: (Vec3, f32) = (Vec3::new(-0.6, 1.0, 0.0), 1.2);
/// The glass colours, used in turn.
pub const PALETTE: [Rgb; 5] = [
    Rgb::new(0.85, 0.15, 0.1),
    Rgb::new(0.1, 0.3, 0.85),
    Rgb::new(0.9, 0.75, 0.1),
    Rgb::new(0.15, 0.7, 0.2),
    Rgb::new(0.6, 0.2, 0.7),
];
/// Index of refraction of the glass.
pub const GLASS_IOR: f32 = 1.5;
/// The roughness (Beckmann α) of the panes of the built-in `stained-glass`: smooth, so that every renderer and the Mitsuba export (which has no rough thin dielectric) see the same scene; the glossy variants of figures 1, 13 and 14 come from [`stained_glass_with`].
pub const DEFAULT_ROUGHNESS: f32 = 0.0;
/// Where the point light is (outside, behind the window).
pub const LIGHT_POSITION: Vec3 = Vec3::new(0.2, 3.4, -2.0);
/// Its intensity, W/sr.
pub const LIGHT_INTENSITY: Rgb = Rgb::new(20.0, 20.0, 20.0);

/// `stained-glass` with the default roughness ([`DEFAULT_ROUGHNESS`]).
pub fn stained_glass() -> Scene {
    stained_glass_with(DEFAULT_ROUGHNESS)
}

/// `stained-glass` with panes of Beckmann roughness `roughness` (0 is smooth glass; Duvenhage et al. 2010, figure 13 raises it from left to right).
pub fn stained_glass_with(roughness: f32) -> Scene {
    let mut materials = vec![
        Material::diffuse("floor", Rgb::splat(0.7)),
        Material::diffuse("wall", Rgb::new(0.75, 0.72, 0.68)),
    ];
    for (i, colour) in PALETTE.iter().enumerate() {
        let mut params = BTreeMap::new();
        params.insert("ior".to_owned(), vec![GLASS_IOR]);
        params.insert("roughness".to_owned(), vec![roughness]);
        params.insert(
            "transmittance".to_owned(),
            vec![colour.x, colour.y, colour.z],
        );
        materials.push(Material::new(
            format!("glass-{i}"),
            MaterialModel::Named {
                model: crate::material::THIN_DIELECTRIC.into(),
                params,
            },
        ));
    }
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let (floor, wall) = (0, 1);
    let (corner, size) = WINDOW;
    let top = 3.0;
    let mut meshes = vec![
        quad("floor", Vec3::new(-2.0, 0.0, 0.0), 4.0 * z, 4.0 * x, floor),
        // The window wall round the hole, facing +z.
        quad(
            "wall-below",
            Vec3::new(-2.0, 0.0, 0.0),
            4.0 * x,
            corner.y * y,
            wall,
        ),
        quad(
            "wall-above",
            Vec3::new(-2.0, corner.y + size, 0.0),
            4.0 * x,
            (top - corner.y - size) * y,
            wall,
        ),
        quad(
            "wall-left",
            Vec3::new(-2.0, corner.y, 0.0),
            (2.0 + corner.x) * x,
            size * y,
            wall,
        ),
        quad(
            "wall-right",
            Vec3::new(corner.x + size, corner.y, 0.0),
            (2.0 - corner.x - size) * x,
            size * y,
            wall,
        ),
    ];
    let step = size / PANES as f32;
    for j in 0..PANES {
        for i in 0..PANES {
            let material = 2 + ((i + 2 * j) % PALETTE.len()) as u32;
            let c = corner + Vec3::new(i as f32 * step, j as f32 * step, 0.0);
            // Facing -z, towards the light.
            let pane: Mesh = quad(&format!("pane-{i}-{j}"), c, step * y, step * x, material);
            meshes.push(pane);
        }
    }
    let camera = Camera::look_at(
        Vec3::new(1.2, 1.7, 4.2),
        Vec3::new(-0.1, 0.8, 0.8),
        Vec3::Y,
        55.0,
    );
    let lights = vec![Light::Point(PointLight {
        position: LIGHT_POSITION,
        intensity: LIGHT_INTENSITY,
    })];
    Scene::new(
        "stained-glass",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        lights,
        camera,
    )
    .expect("the built-in stained-glass scene is valid")
}
