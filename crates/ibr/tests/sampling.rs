//! Bastos et al. 1999, section 8.1.3: reflector elements, hemisphere cameras and their off-axis frusta.

use glam::{Vec2, Vec3};
use lustre_geometry::{Plane, builtin};
use lustre_ibr::sampling::hemisphere_directions;
use lustre_ibr::{Reflector, SampleCamera, SamplingSettings};

fn square(half: f32) -> Reflector {
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let c = [
        Vec3::new(-half, 0.0, -half),
        Vec3::new(half, 0.0, -half),
        Vec3::new(half, 0.0, half),
        Vec3::new(-half, 0.0, -half),
        Vec3::new(half, 0.0, half),
        Vec3::new(-half, 0.0, half),
    ];
    Reflector::from_points(0, plane, &c).unwrap()
}

#[test]
fn arc_steps_give_the_camera_counts_of_table_1() {
    // 60°, 45° and 30° arcs: the living floor's 6, the music floor's 7 and the door mirrors' 17 maps per hemisphere.
    for (step, count) in [(60.0f32, 6), (45.0, 7), (30.0, 17)] {
        let d = hemisphere_directions(step.to_radians(), 85f32.to_radians());
        assert_eq!(d.len(), count, "arc step {step}°");
    }
}

#[test]
fn cameras_lie_on_the_hemisphere_behind_their_element() {
    let r = square(0.5);
    let elements = r.elements(3, 2).unwrap();
    assert_eq!(elements.len(), 6);
    // The elements tile the reflector: their areas sum to its area.
    let area: f32 = elements.iter().map(|e| 4.0 * e.half_u * e.half_v).sum();
    assert!((area - r.area()).abs() < 1e-5);
    let cams =
        lustre_ibr::sampling::sample_cameras(&elements, &SamplingSettings::default()).unwrap();
    assert_eq!(cams.len(), 6 * 17);
    for c in &cams {
        let e = &c.element;
        let radius = e.hemisphere_radius();
        assert!((c.position.distance(e.centre) - radius).abs() < 1e-5);
        // Behind the reflector: the side opposite its normal.
        assert!(r.plane.signed_distance(c.position) < 0.0);
        assert!(c.height() > 0.0);
        // The element's corners lie on the hemisphere's base circle.
        for corner in e.corners() {
            assert!((corner.distance(e.centre) - radius).abs() < 1e-5);
        }
    }
}

#[test]
fn reflector_of_the_cornell_floor_is_its_rectangle() {
    let scene = builtin("cornell").unwrap();
    let (id, _) = scene
        .surfaces()
        .iter()
        .enumerate()
        .find(|(_, s)| matches!(s.kind, lustre_geometry::SurfaceKind::Planar(p) if p.normal.y > 0.99 && s.area > 3.0))
        .expect("the floor");
    let r = Reflector::from_surface(&scene, id as u32).unwrap();
    let s = &scene.surfaces()[id];
    // Its bounding rectangle is the floor itself: same area.
    assert!(
        (r.area() - s.area).abs() < 1e-3 * s.area,
        "{} vs {}",
        r.area(),
        s.area
    );
    assert!((r.plane.normal - Vec3::Y).length() < 1e-5);
}

#[test]
fn project_inverts_unproject_and_the_pinhole_matches_texels() {
    let r = square(0.4);
    let e = r.elements(1, 1).unwrap()[0];
    for (polar, azimuth) in [(0.0f32, 0.0f32), (0.5, 1.0), (1.2, 4.0)] {
        let c = SampleCamera::new(0, e, polar, azimuth);
        let (w, h) = (16, 8);
        let pin = c.pinhole(w, h);
        for (i, j) in [(0, 0), (15, 7), (5, 3)] {
            let st = SampleCamera::texel_st(i, j, w, h);
            for z in [c.height() * 1.5, c.height() * 40.0] {
                let x = c.unproject(st, z);
                let (st2, z2) = c.project(x).unwrap();
                assert!((st2 - st).length() < 1e-4, "{st2} vs {st}");
                assert!((z2 - z).abs() < 1e-4 * z);
                // The pinhole images texel (i, j)'s point at its pixel centre.
                let (px, zp) = pin.project(x).unwrap();
                assert!(
                    (px - Vec2::new(i as f32 + 0.5, j as f32 + 0.5)).length() < 2e-3,
                    "{px}"
                );
                assert!((zp - z).abs() < 1e-4 * z);
            }
        }
        // Nothing at or before the near plane (the element) is seen.
        assert!(c.project(c.element_point(0.2, 0.2)).is_none());
        assert!(c.project(c.position + Vec3::Y * 0.01).is_none());
    }
}

#[test]
fn bad_settings_are_refused() {
    let e = square(0.5).elements(1, 1).unwrap();
    for s in [
        SamplingSettings {
            arc_step_degrees: 0.0,
            ..Default::default()
        },
        SamplingSettings {
            max_polar_degrees: 90.0,
            ..Default::default()
        },
        SamplingSettings {
            map_resolution: (0, 4),
            ..Default::default()
        },
        SamplingSettings {
            planar_resolution: (0, 1),
            ..Default::default()
        },
    ] {
        assert!(
            lustre_ibr::sampling::sample_cameras(&e, &s).is_err(),
            "{s:?}"
        );
    }
}
