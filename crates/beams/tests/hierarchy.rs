//! The beam hierarchy (beyond the paper: Duvenhage et al. 2010, section 5.2, future work) gives exactly the linear traversal's sums.

mod support;

use std::f32::consts::TAU;

use glam::Vec3;
use lustre_beams::{BeamSet, BuildOptions, PointSource, ScatterMaterial, Scatterer};
use lustre_geometry::{Aabb, Rgb};
use support::Rng;

/// A ring of mirror quads (two triangles each), a wavy refracting water grid and rough glass panes: specular, refracted, glossy and shadow beams together.
fn mixed_scatterers() -> Vec<Scatterer> {
    let mut out = Vec::new();
    let mirror = ScatterMaterial::Reflector {
        reflectance: Rgb::splat(0.9),
        conductor: None,
        roughness: 0.0,
    };
    let n = 40;
    for i in 0..n {
        let (a0, a1) = (TAU * i as f32 / n as f32, TAU * (i + 1) as f32 / n as f32);
        let p = |a: f32, y: f32| Vec3::new(2.0 * a.cos(), y, 2.0 * a.sin());
        // Facing the ring's centre.
        let (q0, q1, q2, q3) = (p(a0, 0.0), p(a1, 0.0), p(a1, 0.4), p(a0, 0.4));
        out.push(Scatterer::flat([q0, q2, q1], mirror));
        out.push(Scatterer::flat([q0, q3, q2], mirror));
    }
    let water = ScatterMaterial::Interface {
        ior: 1.33,
        transmittance: Rgb::ONE,
        roughness: 0.0,
    };
    let m = 10;
    let h = |x: f32, z: f32| 1.0 + 0.03 * (3.0 * x).sin() * (2.0 * z).cos();
    for i in 0..m {
        for j in 0..m {
            let (x0, z0) = (
                -1.0 + 2.0 * i as f32 / m as f32,
                -1.0 + 2.0 * j as f32 / m as f32,
            );
            let d = 2.0 / m as f32;
            let v = |x: f32, z: f32| Vec3::new(x, h(x, z), z);
            let (a, b, c, e) = (v(x0, z0), v(x0 + d, z0), v(x0 + d, z0 + d), v(x0, z0 + d));
            out.push(Scatterer::flat([a, e, c], water));
            out.push(Scatterer::flat([a, c, b], water));
        }
    }
    let glass = ScatterMaterial::ThinSlab {
        ior: 1.5,
        transmittance: Rgb::new(0.8, 0.3, 0.2),
        roughness: 0.1,
    };
    for k in 0..6 {
        let x = -1.5 + 0.5 * k as f32;
        out.push(Scatterer::flat(
            [
                Vec3::new(x, 1.5, -2.5),
                Vec3::new(x + 0.4, 1.5, -2.5),
                Vec3::new(x + 0.2, 2.2, -2.5),
            ],
            glass,
        ));
    }
    out
}

#[test]
fn hierarchy_equals_linear_traversal() {
    let lights = [
        PointSource::isotropic(Vec3::new(0.3, 3.0, 0.1), Rgb::splat(20.0)),
        PointSource::isotropic(Vec3::new(-0.5, 2.0, -3.5), Rgb::new(5.0, 4.0, 3.0)),
    ];
    let bounds = Aabb {
        min: Vec3::new(-3.0, -0.5, -4.0),
        max: Vec3::new(3.0, 3.5, 3.0),
    };
    let set = BeamSet::build(
        &lights,
        &mixed_scatterers(),
        bounds,
        &BuildOptions::default(),
    )
    .unwrap();
    let beams = set.beams().len();
    assert!(beams > 400, "{beams}");
    let mut rng = Rng::new(21);
    let (mut candidates, mut inside, mut lit, points) = (0usize, 0usize, 0usize, 5000);
    for _ in 0..points {
        let p = Vec3::new(
            rng.range(bounds.min.x, bounds.max.x),
            rng.range(bounds.min.y, bounds.max.y),
            rng.range(bounds.min.z, bounds.max.z),
        );
        let n = rng.unit_vector();
        let offered = set.candidates(p);
        // Every beam whose support holds p is offered.
        for (i, b) in set.beams().iter().enumerate() {
            if b.support(p) {
                inside += 1;
                assert!(offered.binary_search(&(i as u32)).is_ok(), "{p}: beam {i}");
            }
        }
        candidates += offered.len();
        let (h, l) = (set.irradiance_at(p, n), set.irradiance_at_linear(p, n));
        assert_eq!(h, l, "{p}");
        if l != Rgb::ZERO {
            lit += 1;
        }
    }
    let mean = candidates as f64 / points as f64;
    let mean_inside = inside as f64 / points as f64;
    println!(
        "hierarchy: {beams} beams, {mean:.1} offered and {mean_inside:.1} holding the point on average, {lit} of {points} points lit"
    );
    assert!(lit > points / 10, "{lit}");
    // A regression guard on the pruning (28 of 1420 when written).
    assert!(mean < beams as f64 / 10.0, "{mean}");
    // Outside the bounds the linear traversal is used.
    let far = Vec3::new(10.0, 1.0, 0.0);
    assert_eq!(set.candidates(far).len(), beams);
}

mod random_scenes {
    use super::*;
    use proptest::prelude::{ProptestConfig, prop, prop_assert, prop_assert_eq, proptest};
    use support::Rng;

    fn material(kind: u8, roughness: f32) -> ScatterMaterial {
        match kind % 3 {
            0 => ScatterMaterial::Reflector {
                reflectance: Rgb::splat(0.8),
                conductor: None,
                roughness,
            },
            1 => ScatterMaterial::Interface {
                ior: 1.4,
                transmittance: Rgb::ONE,
                roughness,
            },
            _ => ScatterMaterial::ThinSlab {
                ior: 1.5,
                transmittance: Rgb::splat(0.7),
                roughness,
            },
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        #[test]
        fn hierarchy_equals_linear_traversal_for_random_scatterers(
            seed in 0u64..1_000_000,
            triangles in 1usize..40,
            rough in prop::bool::ANY,
        ) {
            let mut rng = Rng::new(seed);
            let bounds = Aabb { min: Vec3::splat(-2.0), max: Vec3::splat(2.0) };
            let point = |rng: &mut Rng| Vec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
            let scatterers: Vec<Scatterer> = (0..triangles)
                .map(|k| {
                    let c = point(&mut rng) * 0.8;
                    let size = rng.range(0.05, 0.6);
                    let v = [0, 1, 2].map(|_| c + rng.unit_vector() * size);
                    let roughness = if rough { rng.range(0.0, 0.3) } else { 0.0 };
                    Scatterer::flat(v, material(k as u8, roughness))
                })
                .collect();
            let lights = [PointSource::isotropic(point(&mut rng), Rgb::splat(3.0))];
            let set = BeamSet::build(&lights, &scatterers, bounds, &BuildOptions::default()).unwrap();
            for _ in 0..300 {
                let p = point(&mut rng);
                let n = rng.unit_vector();
                prop_assert_eq!(set.irradiance_at(p, n), set.irradiance_at_linear(p, n));
                // Every beam's irradiance is finite, non-negative for light
                // it adds and non-positive for light a shadow beam removes.
                for b in set.beams() {
                    let e = b.irradiance(p, n);
                    prop_assert!(e.is_finite(), "{:?} at {}: {}", b.kind, p, e);
                    if b.kind == lustre_beams::BeamKind::Shadow {
                        prop_assert!(e.max_element() <= 0.0);
                    } else {
                        prop_assert!(e.min_element() >= 0.0);
                    }
                }
            }
        }
    }
}
