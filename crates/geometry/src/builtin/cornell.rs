//! The Cornell box exactly as Mitsuba 3's `cornell_box()`, and the glossy
//! `glosbox` variant of Stürzlinger & Bastos and Bastos et al.

use glam::{Affine3A, Mat3, Quat, Vec2, Vec3};

use crate::animation::{Keyframe, ObjectPath, PathEnd};
use crate::material::{ConductorFresnel, Material, MaterialModel, MicrofacetDistribution};
use crate::{Camera, Mesh, Object, Rgb, Scene};

/// Reflectance of the white walls, floor, ceiling and boxes.
pub const WHITE: Rgb = Rgb::new(0.885809, 0.698859, 0.666422);
/// Reflectance of the left (x = -1) wall.
pub const RED: Rgb = Rgb::new(0.570068, 0.0430135, 0.0443706);
/// Reflectance of the right (x = +1) wall.
pub const GREEN: Rgb = Rgb::new(0.105421, 0.37798, 0.076425);
/// Radiance of the ceiling light.
pub const LIGHT_RADIANCE: Rgb = Rgb::new(18.387, 13.9873, 6.75357);
/// Complex index of refraction of gold (real part) used by `glosbox`.
pub const GOLD_ETA: Rgb = Rgb::new(0.143, 0.374, 1.442);
/// Complex index of refraction of gold (imaginary part) used by `glosbox`.
pub const GOLD_K: Rgb = Rgb::new(3.983, 2.385, 1.603);

/// Centre of the small box, the mobile object, in its rest pose (García et al. 2003, section 2.2.2).
pub const SMALL_BOX_CENTRE: Vec3 = Vec3::new(0.335, -0.7, 0.38);
/// Time the small box takes to go once round its path, in seconds (García et al. 2003, section 2.2.2).
pub const SMALL_BOX_PATH_DURATION: f32 = 8.0;

/// The small box's path: it slides along the floor to the right wall, to
/// the front right, to the front middle and back, turning up to 70° about
/// its vertical axis, looping every 8 s; it stays inside the box and clear of
/// the large box (García et al. 2003, section 2.2.2).
pub fn small_box_path() -> ObjectPath {
    // (time, centre x, centre z, turn in degrees); the centre stays at y = -0.7.
    const KEYS: [(f32, f32, f32, f32); 5] = [
        (0.0, 0.335, 0.38, 0.0),
        (2.0, 0.55, 0.02, 35.0),
        (4.0, 0.56, 0.5, 70.0),
        (6.0, 0.0, 0.56, 45.0),
        (SMALL_BOX_PATH_DURATION, 0.335, 0.38, 0.0),
    ];
    let keys = KEYS
        .iter()
        .map(|&(t, x, z, degrees)| {
            Keyframe::new(
                t,
                Vec3::new(x, SMALL_BOX_CENTRE.y, z),
                Quat::from_rotation_y(degrees.to_radians()),
            )
        })
        .collect();
    ObjectPath::new(keys, PathEnd::Loop)
        .and_then(|path| path.with_pivot(SMALL_BOX_CENTRE))
        .expect("the small box's path is valid")
}

/// Mitsuba's `rectangle`: [-1, 1]² in the z = 0 plane, facing +z, under `xf`.
fn rectangle(name: &str, xf: Affine3A, material: u32) -> Mesh {
    let corners = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let normal = xf.transform_vector3(Vec3::Z).normalize();
    Mesh {
        name: name.to_owned(),
        positions: corners.iter().map(|&p| xf.transform_point3(p)).collect(),
        normals: vec![normal; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        indices: vec![[0, 1, 2], [2, 3, 0]],
        material,
    }
}

/// Mitsuba's `cube`: [-1, 1]³ with outward faces and per-face normals, under `xf`.
fn cube(name: &str, xf: Affine3A, material: u32) -> Mesh {
    let normal_matrix = Mat3::from(xf.matrix3).inverse().transpose();
    let mut mesh = Mesh {
        name: name.to_owned(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        material,
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            // Two tangents with s × t = n, so the quad winds counter-clockwise seen from outside.
            let s = Vec3::AXES[(axis + 1) % 3] * sign;
            let t = n.cross(s);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(xf.transform_point3(n + a * s + b * t));
                mesh.normals.push((normal_matrix * n).normalize());
                mesh.uvs.push(Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0)));
            }
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base + 2, base + 3, base]);
        }
    }
    mesh
}

/// An affine transform from its 3×4 matrix rows, as DESIGN.md writes them.
fn affine_rows(rows: [[f32; 4]; 3]) -> Affine3A {
    Affine3A::from_cols_array(&[
        rows[0][0], rows[1][0], rows[2][0], rows[0][1], rows[1][1], rows[2][1], rows[0][2],
        rows[1][2], rows[2][2], rows[0][3], rows[1][3], rows[2][3],
    ])
}

/// Mitsuba's `T().translate(t).rotate(axis, degrees)` applied to Mitsuba's rectangle.
fn placed(t: Vec3, axis: Vec3, degrees: f32) -> Affine3A {
    Affine3A::from_translation(t)
        * Affine3A::from_quat(Quat::from_axis_angle(axis, degrees.to_radians()))
}

/// The Cornell box parts with the materials of each part given by the caller.
fn box_scene(
    name: &str,
    materials: Vec<Material>,
    large_box_material: u32,
    floor_material: u32,
) -> Scene {
    let (white, red, green, light) = (0, 1, 2, 3);
    let meshes = vec![
        rectangle(
            "floor",
            placed(Vec3::new(0.0, -1.0, 0.0), Vec3::X, -90.0),
            floor_material,
        ),
        rectangle(
            "ceiling",
            placed(Vec3::new(0.0, 1.0, 0.0), Vec3::X, 90.0),
            white,
        ),
        rectangle(
            "back",
            placed(Vec3::new(0.0, 0.0, -1.0), Vec3::X, 0.0),
            white,
        ),
        rectangle(
            "green-wall",
            placed(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, -90.0),
            green,
        ),
        rectangle(
            "red-wall",
            placed(Vec3::new(-1.0, 0.0, 0.0), Vec3::Y, 90.0),
            red,
        ),
        rectangle(
            "light",
            placed(Vec3::new(0.0, 0.99, 0.01), Vec3::X, 90.0)
                * Affine3A::from_scale(Vec3::new(0.23, 0.19, 0.19)),
            light,
        ),
        cube(
            "small-box",
            affine_rows([
                [0.286891, 0.0, -0.0877115, 0.335],
                [0.0, 0.3, 0.0, -0.7],
                [0.0877115, 0.0, 0.286891, 0.38],
            ]),
            white,
        ),
        cube(
            "large-box",
            affine_rows([
                [0.28491, 0.0, 0.0939491, -0.33],
                [0.0, 0.61, 0.0, -0.4],
                [-0.0939491, 0.0, 0.28491, -0.28],
            ]),
            large_box_material,
        ),
    ];
    let objects = Object::one_per_mesh(&meshes);
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y, 39.3077);
    Scene::new(name, meshes, materials, objects, Vec::new(), camera)
        .and_then(|scene| scene.with_mobile("small-box", small_box_path()))
        .expect("the built-in Cornell box is valid")
}

fn cornell_materials() -> Vec<Material> {
    vec![
        Material::diffuse("white", WHITE),
        Material::diffuse("red", RED),
        Material::diffuse("green", GREEN),
        // Mitsuba's light rectangle reflects like the white walls and emits.
        Material::diffuse("light", WHITE).with_emission(LIGHT_RADIANCE),
    ]
}

/// `cornell`: exactly Mitsuba 3's `cornell_box()` (DESIGN.md), with the
/// small box mobile along [`small_box_path`] (at its rest pose at time 0).
pub fn cornell() -> Scene {
    box_scene("cornell", cornell_materials(), 0, 0)
}

/// `glosbox`: `cornell` with a rough gold large box (Beckmann, alpha 0.1) and a
/// floor blending 0.7 of the white diffuse with 0.3 of a rough mirror
/// (Beckmann, alpha 0.05, F = 1) — Stürzlinger's "Glosbox" with Bastos' glossy
/// floor; the small box is mobile as in `cornell`.
pub fn glosbox() -> Scene {
    let mut materials = cornell_materials();
    materials.push(Material::new(
        "gold",
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha: 0.1,
            fresnel: ConductorFresnel::Complex {
                eta: GOLD_ETA,
                k: GOLD_K,
            },
            specular: Rgb::ONE,
        },
    ));
    materials.push(Material::new(
        "glossy-floor",
        MaterialModel::Blend {
            weight: 0.3,
            first: Box::new(MaterialModel::Diffuse { reflectance: WHITE }),
            second: Box::new(MaterialModel::RoughConductor {
                distribution: MicrofacetDistribution::Beckmann,
                alpha: 0.05,
                fresnel: ConductorFresnel::None,
                specular: Rgb::ONE,
            }),
        },
    ));
    box_scene("glosbox", materials, 4, 5)
}
