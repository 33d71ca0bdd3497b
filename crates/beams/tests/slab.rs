//! A closed glass slab (a dielectric cuboid, like `bathroom`'s shower door)
//! sends one beam through: its near face as a thin slab, its far face
//! nothing (`Scatterer::slab_face`). Under the slab the beams' irradiance is
//! the point light's times the slab's transmittance with every internal
//! reflection summed, `(1 - F)² Σ F^{2k} = (1 - F) / (1 + F)` at the ray's
//! own incidence, and the shadow beams take the direct light out once.

mod support;

use glam::Vec3;
use lustre_beams::{BeamKind, BeamSet, BuildOptions, ScatterMaterial};
use lustre_geometry::light::PointLight;
use lustre_geometry::{Camera, Light, Material, MaterialModel, Mesh, Object, Rgb, Scene};
use support::Rng;

const IOR: f32 = 1.5;
const LIGHT: Vec3 = Vec3::new(0.2, 3.0, 0.1);
const INTENSITY: f32 = 10.0;
/// Cells along each side of the slab's large faces.
const GRID: u32 = 16;
/// The slab: x and z in [-1, 1], y in [1, 1.01].
const BOTTOM: f32 = 1.0;
const TOP: f32 = 1.01;

/// A closed, outward-wound glass cuboid with its large faces tessellated
/// into `GRID²` cells, over a diffuse floor at y = 0.
fn slab_scene() -> Scene {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut quad = |corners: [Vec3; 4]| {
        let base = positions.len() as u32;
        positions.extend(corners);
        indices.push([base, base + 1, base + 2]);
        indices.push([base, base + 2, base + 3]);
    };
    let at = |i: u32| -1.0 + 2.0 * i as f32 / GRID as f32;
    for i in 0..GRID {
        for j in 0..GRID {
            let (x0, x1, z0, z1) = (at(i), at(i + 1), at(j), at(j + 1));
            // Top, normal +y: counter-clockwise seen from above.
            quad([
                Vec3::new(x0, TOP, z0),
                Vec3::new(x0, TOP, z1),
                Vec3::new(x1, TOP, z1),
                Vec3::new(x1, TOP, z0),
            ]);
            // Bottom, normal -y.
            quad([
                Vec3::new(x0, BOTTOM, z0),
                Vec3::new(x1, BOTTOM, z0),
                Vec3::new(x1, BOTTOM, z1),
                Vec3::new(x0, BOTTOM, z1),
            ]);
        }
    }
    let (b, t) = (BOTTOM, TOP);
    for [p, q] in [
        [Vec3::new(1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0)],
        [Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0)],
        [Vec3::new(-1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, -1.0)],
        [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0)],
    ] {
        // Sides, outward: p -> q runs counter-clockwise seen from above.
        quad([
            p + Vec3::Y * b,
            p + Vec3::Y * t,
            q + Vec3::Y * t,
            q + Vec3::Y * b,
        ]);
    }
    let slab = Mesh::flat("slab", &positions, &indices, 0);
    let floor = Mesh::flat(
        "floor",
        &[
            Vec3::new(-4.0, 0.0, -4.0),
            Vec3::new(-4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, -4.0),
        ],
        &[[0, 1, 2], [0, 2, 3]],
        1,
    );
    let meshes = vec![slab, floor];
    let objects = Object::one_per_mesh(&meshes);
    Scene::new(
        "closed-slab",
        meshes,
        vec![
            Material::new(
                "glass",
                MaterialModel::Dielectric {
                    ior: IOR,
                    transmittance: Rgb::ONE,
                },
            ),
            Material::diffuse("floor", Rgb::splat(0.5)),
        ],
        objects,
        vec![Light::Point(PointLight {
            position: LIGHT,
            intensity: Rgb::splat(INTENSITY),
        })],
        Camera::look_at(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO, Vec3::Y, 50.0),
    )
    .unwrap()
}

/// Unpolarised Fresnel reflectance from air into glass of index `eta` at incidence `cos_i` (the textbook s and p amplitudes).
fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / eta;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn a_closed_slab_is_one_thin_slab_lit_from_outside() {
    let scene = slab_scene();
    let set = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let face_cells = (2 * GRID * GRID) as usize;
    // Every scatterer is a slab face turned into a thin slab.
    let input = lustre_beams::BeamInput::from_scene(&scene).unwrap();
    assert_eq!(input.scatterers.len(), 2 * face_cells + 8);
    assert!(input.scatterers.iter().all(|s| s.slab_face
        && matches!(s.material, ScatterMaterial::ThinSlab { ior, .. } if ior == IOR)));
    // Only the top face, lit from outside, scatters: the bottom and the
    // sides see the light from inside the glass.
    let of_kind = |k: BeamKind| set.beams().iter().filter(|b| b.kind == k).count();
    assert_eq!(of_kind(BeamKind::Transmitted), face_cells);
    assert_eq!(of_kind(BeamKind::Reflected), face_cells);
    assert_eq!(of_kind(BeamKind::Shadow), face_cells);
    assert_eq!(of_kind(BeamKind::Refracted), 0);
    assert_eq!(set.stats().back_facing, face_cells + 4 * 2);
    for b in set.beams() {
        assert!(b.vertices.iter().all(|v| v.y == TOP), "{:?}", b.vertices);
    }

    let mut rng = Rng::new(7);
    let mut worst = 0.0f64;
    for _ in 0..300 {
        let p = Vec3::new(rng.range(-0.8, 0.8), 0.0, rng.range(-0.8, 0.8));
        let (mut through, mut shadow) = (0.0f64, 0.0f64);
        for b in set.beams() {
            let e = f64::from(b.irradiance(p, Vec3::Y).y);
            match b.kind {
                BeamKind::Transmitted => through += e,
                BeamKind::Shadow => shadow += e,
                _ => assert_eq!(e, 0.0, "{:?} reaches under the slab", b.kind),
            }
        }
        let to_light = (LIGHT - p).as_dvec3();
        let d2 = to_light.length_squared();
        let cos = to_light.y / d2.sqrt();
        let direct = f64::from(INTENSITY) * cos / d2;
        let f = fresnel(cos, f64::from(IOR));
        let expected = direct * (1.0 - f) / (1.0 + f);
        let err = (through / expected - 1.0).abs();
        worst = worst.max(err);
        // The beams take F at each cell's centroid and a flux density
        // constant over each flux triangle: within 1 % for cells of 0.125 m
        // seen from 2 m.
        assert!(err < 0.01, "{p}: {through} against {expected}");
        // One shadow beam over every point: the direct light taken out once.
        assert!(
            (shadow + direct).abs() < 0.01 * direct,
            "{p}: shadow {shadow} against direct {direct}"
        );
    }
    println!("closed slab: worst |transmitted/expected - 1| = {worst:.2e}");
}
