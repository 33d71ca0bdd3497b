//! Scenes with known answers for the photon tests.
#![allow(dead_code)]

use glam::Vec3;
use lustre_geometry::light::PointLight;
use lustre_geometry::material::MaterialModel;
use lustre_geometry::{Camera, Light, Material, Mesh, Object, Rgb, Scene};

/// A square diffuse floor of half-size `half` in the plane y = 0 facing +y, albedo `rho`, lit by an isotropic point light of intensity `intensity` at height `height` above the origin.
pub fn point_over_plane(half: f32, height: f32, rho: f32, intensity: f32) -> Scene {
    let positions = [
        Vec3::new(-half, 0.0, -half),
        Vec3::new(-half, 0.0, half),
        Vec3::new(half, 0.0, half),
        Vec3::new(half, 0.0, -half),
    ];
    let floor = Mesh::flat("floor", &positions, &[[0, 1, 2], [2, 3, 0]], 0);
    let meshes = vec![floor];
    Scene::new(
        "point-over-plane",
        meshes.clone(),
        vec![Material::diffuse("floor", Rgb::splat(rho))],
        Object::one_per_mesh(&meshes),
        vec![Light::Point(PointLight {
            position: Vec3::new(0.0, height, 0.0),
            intensity: Rgb::splat(intensity),
        })],
        Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0),
    )
    .expect("valid scene")
}

/// A closed box [-1, 1]³ with inward-facing faces of a diffuse albedo, a point light inside (the white furnace of DESIGN.md, with a box for the sphere).
pub fn furnace(albedo: Rgb, light_at: Vec3) -> Scene {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let corners = [
        p(-1.0, -1.0, -1.0),
        p(1.0, -1.0, -1.0),
        p(1.0, 1.0, -1.0),
        p(-1.0, 1.0, -1.0),
        p(-1.0, -1.0, 1.0),
        p(1.0, -1.0, 1.0),
        p(1.0, 1.0, 1.0),
        p(-1.0, 1.0, 1.0),
    ];
    // Quads wound counter-clockwise seen from inside.
    let quads = [
        [0, 1, 2, 3], // back z = -1, normal +z
        [5, 4, 7, 6], // front z = +1, normal -z
        [4, 0, 3, 7], // left x = -1, normal +x
        [1, 5, 6, 2], // right x = +1, normal -x
        [4, 5, 1, 0], // floor y = -1, normal +y
        [3, 2, 6, 7], // ceiling y = +1, normal -y
    ];
    let mut indices = Vec::new();
    for q in quads {
        indices.push([q[0], q[1], q[2]]);
        indices.push([q[2], q[3], q[0]]);
    }
    let mesh = Mesh::flat("furnace", &corners, &indices, 0);
    for t in 0..mesh.indices.len() {
        let n = mesh.geometric_normal(t);
        let c = mesh.triangle(t).iter().sum::<Vec3>() / 3.0;
        assert!(n.dot(-c) > 0.0, "face {t} must face inwards");
    }
    let meshes = vec![mesh];
    Scene::new(
        "furnace",
        meshes.clone(),
        vec![Material::new(
            "wall",
            MaterialModel::Diffuse {
                reflectance: albedo,
            },
        )],
        Object::one_per_mesh(&meshes),
        vec![Light::Point(PointLight {
            position: light_at,
            intensity: Rgb::ONE,
        })],
        Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0),
    )
    .expect("valid scene")
}
