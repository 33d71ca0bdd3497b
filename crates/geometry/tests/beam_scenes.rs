//! The scenes of Duvenhage, Bouatouch & Kourie 2010 (figures 1-3, 13, 14): `cardioid`, `pool` and `stained-glass`.

use glam::Vec3;
use lustre_geometry::builtin::{cardioid, pool, stained_glass};
use lustre_geometry::{Light, MaterialModel, Scene, WorldTriangle, builtin};

fn triangles_of(scene: &Scene, material: &str) -> Vec<WorldTriangle> {
    scene
        .world_triangles()
        .into_iter()
        .filter(|t| {
            scene.materials()[t.material as usize]
                .name
                .starts_with(material)
        })
        .collect()
}

fn face_normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize()
}

fn point_light(scene: &Scene) -> Vec3 {
    match scene.lights() {
        [Light::Point(l)] => l.position,
        other => panic!("{}: {other:?}", scene.name),
    }
}

#[test]
fn cardioid_is_a_ring_of_80_inward_mirror_triangles_on_a_floor() {
    let scene = builtin("cardioid").unwrap();
    let ring = triangles_of(&scene, "ring");
    assert_eq!(ring.len(), 2 * cardioid::RING_SEGMENTS);
    assert_eq!(ring.len(), 80);
    for t in &ring {
        let c = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        let n = face_normal(t.positions);
        // Facing the axis, vertical, on the circle.
        let to_axis = Vec3::new(-c.x, 0.0, -c.z).normalize();
        assert!(n.dot(to_axis) > 0.99, "{n} at {c}");
        for p in t.positions {
            let r = Vec3::new(p.x, 0.0, p.z).length();
            assert!((r - cardioid::RING_RADIUS).abs() < 1e-5);
        }
    }
    assert!(matches!(
        scene.materials()[ring[0].material as usize].model,
        MaterialModel::Mirror { .. }
    ));
    let light = point_light(&scene);
    assert!(Vec3::new(light.x, 0.0, light.z).length() < cardioid::RING_RADIUS);
    assert!(light.y > cardioid::RING_HEIGHT);
}

#[test]
fn pool_is_a_20_by_20_by_2_water_surface_that_moves_with_time() {
    let scene = pool();
    let water = triangles_of(&scene, "water");
    assert_eq!(water.len(), 20 * 20 * 2);
    let light = point_light(&scene);
    for t in &water {
        assert!(face_normal(t.positions).y > 0.9);
        for (p, n) in t.positions.iter().zip(&t.normals) {
            assert!((p.y - pool::water_height(p.x, p.z, 0.0)).abs() < 1e-6);
            assert!((*n - pool::water_normal(p.x, p.z, 0.0)).length() < 1e-5);
            assert!(p.y < light.y);
        }
    }
    // The normal is the gradient's: a finite difference of the height.
    let (x, z, t, h) = (0.3f32, -0.2f32, 0.7f32, 1e-3f32);
    let dx = (pool::water_height(x + h, z, t) - pool::water_height(x - h, z, t)) / (2.0 * h);
    let dz = (pool::water_height(x, z + h, t) - pool::water_height(x, z - h, t)) / (2.0 * h);
    let want = Vec3::new(-dx, 1.0, -dz).normalize();
    assert!((pool::water_normal(x, z, t) - want).length() < 1e-3);
    // Waves move: another time, other heights; the same time, the same scene.
    let later = pool::pool_at(0.5);
    let moved = triangles_of(&later, "water")
        .iter()
        .zip(&water)
        .filter(|(a, b)| (a.positions[0].y - b.positions[0].y).abs() > 1e-4)
        .count();
    assert!(moved > water.len() / 2, "{moved}");
    assert_eq!(
        triangles_of(&pool::pool_at(0.0), "water"),
        water,
        "pool() is pool_at(0)"
    );
    assert!(matches!(
        scene.materials()[water[0].material as usize].model,
        MaterialModel::Dielectric { ior, .. } if ior == pool::WATER_IOR
    ));
}

#[test]
fn stained_glass_panes_face_the_light_with_the_given_roughness() {
    for roughness in [0.0f32, 0.05, 0.3] {
        let scene = stained_glass::stained_glass_with(roughness);
        let panes = triangles_of(&scene, "glass");
        assert_eq!(panes.len(), 2 * stained_glass::PANES * stained_glass::PANES);
        let light = point_light(&scene);
        for t in &panes {
            let c = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
            assert!(face_normal(t.positions).dot(light - c) > 0.0);
            let MaterialModel::Named { model, params } =
                &scene.materials()[t.material as usize].model
            else {
                panic!("panes are thin dielectrics")
            };
            assert_eq!(model, "thin-dielectric");
            assert_eq!(params["roughness"], vec![roughness]);
        }
    }
    assert_eq!(
        stained_glass().materials(),
        stained_glass::stained_glass_with(stained_glass::DEFAULT_ROUGHNESS).materials()
    );
    assert_eq!(builtin("stained-glass").unwrap().name, "stained-glass");
    assert_eq!(cardioid().name, "cardioid");
}

#[test]
fn the_beam_scenes_export_to_mitsuba() {
    use lustre_geometry::mitsuba::{ExportOptions, export};
    let dir = std::env::temp_dir().join(format!("lustre-beam-scenes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // The built-in stained-glass has smooth panes: exported as is.
    for scene in [cardioid(), pool(), stained_glass()] {
        let xml_path = dir.join(&scene.name).join("scene.xml");
        let report = export(&scene, &xml_path, &ExportOptions::default()).unwrap();
        assert!(
            report.warnings.is_empty(),
            "{}: {:?}",
            scene.name,
            report.warnings
        );
        let xml = std::fs::read_to_string(&xml_path).unwrap();
        assert_eq!(
            xml.matches("<emitter type=\"point\"").count(),
            1,
            "{}",
            scene.name
        );
        let (conductor, dielectric, thin) = match scene.name.as_str() {
            "cardioid" => (1, 0, 0),
            "pool" => (0, 1, 0),
            _ => (0, 0, stained_glass::PALETTE.len()),
        };
        assert_eq!(xml.matches("<bsdf type=\"conductor\"").count(), conductor);
        assert_eq!(xml.matches("<bsdf type=\"dielectric\"").count(), dielectric);
        assert_eq!(xml.matches("<bsdf type=\"thindielectric\"").count(), thin);
    }
    // Rough panes: Mitsuba has no rough thin dielectric.
    let rough = stained_glass::stained_glass_with(0.1);
    let xml_path = dir.join("rough").join("scene.xml");
    assert!(export(&rough, &xml_path, &ExportOptions::default()).is_err());
    let options = ExportOptions {
        approximate: true,
        ..ExportOptions::default()
    };
    let report = export(&rough, &xml_path, &options).unwrap();
    assert_eq!(report.warnings.len(), stained_glass::PALETTE.len());
    let _ = std::fs::remove_dir_all(&dir);
}
