//! Beams of the built-in scenes of Duvenhage et al. 2010 (figures 1-3, 13, 14): what is built, and the hierarchy's sums there.

mod support;

use glam::Vec3;
use lustre_beams::{BeamError, BeamKind, BeamSet, BuildOptions};
use lustre_geometry::builtin::{pool, pool_at, stained_glass_with};
use lustre_geometry::{Rgb, builtin};
use support::Rng;

fn count(set: &BeamSet, kind: BeamKind) -> usize {
    set.beams().iter().filter(|b| b.kind == kind).count()
}

/// Hierarchy and linear traversal agree at random points of the floor (height `y`) of `set`'s bounds; returns how many points any beam reaches.
fn agree_on_floor(set: &BeamSet, seed: u64, y: f32) -> usize {
    let b = set.bounds();
    let mut rng = Rng::new(seed);
    let mut lit = 0;
    for _ in 0..2000 {
        let p = Vec3::new(rng.range(b.min.x, b.max.x), y, rng.range(b.min.z, b.max.z));
        let e = set.irradiance_at_linear(p, Vec3::Y);
        assert_eq!(set.irradiance_at(p, Vec3::Y), e, "{p}");
        if e != Rgb::ZERO {
            lit += 1;
        }
    }
    lit
}

#[test]
fn cardioid_reflects_off_the_ring_onto_the_floor() {
    let scene = builtin("cardioid").unwrap();
    let set = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let stats = set.stats();
    assert_eq!(stats.pairs, 80);
    // The light, inside the ring, sees the front of every triangle but the
    // few beside it it sees edge-on or from behind.
    assert_eq!(
        count(&set, BeamKind::Reflected) + stats.back_facing + stats.edge_on,
        80
    );
    assert!(count(&set, BeamKind::Reflected) >= 70, "{stats:?}");
    assert!(count(&set, BeamKind::Shadow) >= 70);
    let lit = agree_on_floor(&set, 31, 1e-4);
    assert!(lit > 200, "{lit}");
}

#[test]
fn pool_refracts_every_water_triangle_and_changes_with_time() {
    let set = BeamSet::from_scene(&pool(), &BuildOptions::default()).unwrap();
    assert_eq!(count(&set, BeamKind::Refracted), 800);
    assert_eq!(count(&set, BeamKind::Reflected), 800);
    assert_eq!(count(&set, BeamKind::Shadow), 800);
    assert_eq!(set.stats().total_internal_reflection, 0);
    assert!(agree_on_floor(&set, 32, 1e-4) > 1000);
    // The caustic moves with the waves.
    let later = BeamSet::from_scene(&pool_at(0.4), &BuildOptions::default()).unwrap();
    let mut rng = Rng::new(33);
    let changed = (0..200)
        .filter(|_| {
            let p = Vec3::new(rng.range(-0.9, 0.9), 1e-4, rng.range(-0.9, 0.9));
            let (a, b) = (
                set.irradiance_at(p, Vec3::Y),
                later.irradiance_at(p, Vec3::Y),
            );
            (a - b).abs().max_element() > 1e-3 * a.max_element()
        })
        .count();
    assert!(changed > 100, "{changed}");
    // Under the water the shadow beams take the direct light out and the
    // refracted beams bring (1 - F) of it back, bent: over the floor the
    // sum of direct and beam light is positive.
    let mut sum = Rgb::ZERO;
    for _ in 0..400 {
        let p = Vec3::new(rng.range(-0.8, 0.8), 1e-4, rng.range(-0.8, 0.8));
        sum += set.irradiance_at(p, Vec3::Y) + set.direct_irradiance(p, Vec3::Y);
    }
    assert!(sum.min_element() > 0.0, "{sum}");
}

#[test]
fn stained_glass_throws_coloured_glossy_beams() {
    for roughness in [0.0f32, 0.1] {
        let scene = stained_glass_with(roughness);
        let set = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
        assert_eq!(count(&set, BeamKind::Transmitted), 32);
        assert_eq!(count(&set, BeamKind::Reflected), 32);
        assert_eq!(count(&set, BeamKind::Shadow), 32);
        assert!(
            set.beams().iter().all(
                |b| b.distribution.is_some() == (roughness > 0.0 && b.kind != BeamKind::Shadow)
            )
        );
        assert!(agree_on_floor(&set, 34, 1e-4) > 50);
    }
}

#[test]
fn scenes_without_point_lights_are_refused() {
    let scene = builtin("cornell").unwrap();
    assert!(matches!(
        BeamSet::from_scene(&scene, &BuildOptions::default()),
        Err(BeamError::NoPointLight { lights: 1 })
    ));
    // With its area light as a cosine point light it has beams (no
    // scatterers in the Cornell box, though: only diffuse walls).
    let points = scene.with_area_lights_as_points().unwrap();
    let set = BeamSet::from_scene(&points, &BuildOptions::default()).unwrap();
    assert!(set.beams().is_empty());
}

#[test]
fn pool_refracted_beams_tile_the_floor_under_the_water() {
    // The water's vertex normals are smooth, so the refracted field is
    // continuous and, at this wave height, without folds above the floor:
    // every floor point under exactly one water triangle (one shadow beam)
    // lies in exactly one refracted beam, although neighbouring refracted
    // beams, whose rays do not share an apex, test containment against
    // their own flux planes (a point exactly on a shared edge may miss).
    let set = BeamSet::from_scene(&pool(), &BuildOptions::default()).unwrap();
    let mut rng = Rng::new(35);
    let mut checked = 0;
    for _ in 0..20_000 {
        let p = Vec3::new(rng.range(-0.8, 0.8), 1e-4, rng.range(-0.8, 0.8));
        let holding = |kind: BeamKind| {
            set.candidates(p)
                .iter()
                .filter(|&&i| {
                    let b = &set.beams()[i as usize];
                    b.kind == kind && b.contains(p)
                })
                .count()
        };
        if holding(BeamKind::Shadow) != 1 {
            continue;
        }
        assert_eq!(holding(BeamKind::Refracted), 1, "{p}");
        checked += 1;
    }
    assert!(checked > 19_000, "{checked}");
}
