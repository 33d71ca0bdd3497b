//! Diffuse texture maps in the per-vertex estimators (equation 2.2 with `ρ ⊙ t(uv)`): on the same impacts, a Phong plane whose map is a uniform `c` has the radiance of the untextured plane with `kd ⊙ c` under Impact Count and Photon Maps, and the per-vertex reflectances are the map's samples times `kd`.

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use lustre_density::{
    RaySetOptions, impact_count_radiance, photon_maps_radiance, trace_ray_set, vertex_reflectances,
};
use lustre_geometry::light::PointLight;
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{
    Bvh, Camera, Light, Material, MaterialModel, Mesh, Object, Rgb, Scene, Texture,
};

/// The eye, off to the side of the plane.
const EYE: Vec3 = Vec3::new(-2.0, 1.2, 0.5);

/// Phong's model with diffuse reflectance `kd`.
fn phong(kd: Rgb) -> MaterialModel {
    MaterialModel::Phong {
        diffuse: kd,
        specular: Rgb::splat(0.4),
        exponent: 10.0,
    }
}

/// The plane y = 0, [-2, 2]², subdivided to 0.25 m edges, UVs `(x + 2)/4, (z + 2)/4`, of `material`, under a point light.
fn plane(material: Material) -> Scene {
    let p = [
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(-2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, -2.0),
    ];
    let uvs: Vec<Vec2> = p
        .iter()
        .map(|q| Vec2::new((q.x + 2.0) / 4.0, (q.z + 2.0) / 4.0))
        .collect();
    let mesh = Mesh::flat_with_uvs("plane", &p, &uvs, &[[0, 1, 2], [2, 3, 0]], 0);
    let mesh = subdivide(&mesh, 0.25).unwrap();
    Scene::new(
        "textured-plane",
        vec![mesh],
        vec![material],
        vec![Object {
            name: "plane".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        vec![Light::Point(PointLight {
            position: Vec3::new(0.3, 1.0, -0.2),
            intensity: Rgb::ONE,
        })],
        Camera::look_at(EYE, Vec3::ZERO, Vec3::Y, 40.0),
    )
    .unwrap()
}

#[test]
fn uniform_map_radiance_equals_the_scaled_reflectance() {
    let kd = Rgb::new(0.5, 0.3, 0.2);
    let c = Rgb::new(0.4, 0.9, 0.6);
    let map = Arc::new(Texture::new("uniform", 1, 1, vec![c]).unwrap());
    let textured = plane(Material::new("plane", phong(kd)).with_diffuse_map(map));
    let scaled = plane(Material::new("plane", phong(kd * c)));
    // One set of impacts for both: the estimators' weights alone differ.
    let bvh = Bvh::build(&scaled);
    let options = RaySetOptions {
        photons: 20_000,
        seed: 4,
        max_segments: 2,
        extension: 0.0,
    };
    let rays = trace_ray_set(&scaled, &bvh, &options).unwrap();
    let pairs = [
        (
            impact_count_radiance(&textured, &rays, EYE).unwrap(),
            impact_count_radiance(&scaled, &rays, EYE).unwrap(),
        ),
        (
            photon_maps_radiance(&textured, &rays, 50, EYE).unwrap(),
            photon_maps_radiance(&scaled, &rays, 50, EYE).unwrap(),
        ),
    ];
    for (estimator, (a, b)) in ["impact count", "photon maps"].iter().zip(pairs) {
        assert!(!a[0].is_empty());
        let mut lit = 0;
        for (v, (x, y)) in a[0].iter().zip(&b[0]).enumerate() {
            let d = (*x - *y).abs().max_element();
            assert!(
                d <= 1e-5 * y.max_element().max(1e-3),
                "{estimator}, vertex {v}: {x} vs {y}"
            );
            lit += usize::from(y.max_element() > 0.0);
        }
        assert!(lit > a[0].len() / 2, "{estimator}: {lit} lit vertices");
    }
}

#[test]
fn vertex_reflectances_sample_the_map() {
    let kd = Rgb::new(0.8, 0.5, 0.25);
    let map = Arc::new(
        Texture::new("ramp", 2, 2, vec![Rgb::X, Rgb::Y, Rgb::Z, Rgb::splat(0.5)]).unwrap(),
    );
    let scene = plane(Material::diffuse("plane", kd).with_diffuse_map(map.clone()));
    let rho = vertex_reflectances(&scene, 0);
    let mesh = &scene.meshes()[0];
    assert_eq!(rho.len(), mesh.positions.len());
    for (r, uv) in rho.iter().zip(&mesh.uvs) {
        assert_eq!(*r, kd * map.sample(*uv));
    }
    // Untextured: the model's reflectance at every vertex.
    let plain = plane(Material::diffuse("plane", kd));
    assert!(vertex_reflectances(&plain, 0).iter().all(|&r| r == kd));
    assert!(vertex_reflectances(&plain, 7).is_empty());
}
