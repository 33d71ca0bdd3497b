//! Particle tracing (section 2.1): energy conservation, the white furnace, determinism and incremental refinement.

mod support;

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Mat3, Vec2, Vec3};
use lustre_geometry::sampling::sample_cosine_hemisphere;
use lustre_geometry::{Bvh, Rgb, Scene, builtin};
use lustre_photon::{
    EmissionSampling, NoProgress, PhotonMap, PhotonTracer, TraceOptions, trace_photons,
};

/// Slab test of a ray against the unit cube [-1, 1]³ after the inverse of `x -> m x + t`: distance of entry, if any.
fn hit_oriented_cube(origin: Vec3, dir: Vec3, m: Mat3, t: Vec3) -> Option<f32> {
    let inv = m.inverse();
    let o = inv * (origin - t);
    let d = inv * dir;
    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if o[a].abs() > 1.0 {
                return None;
            }
            continue;
        }
        let (mut ta, mut tb) = ((-1.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
    }
    (t0 <= t1).then_some(t0)
}

/// Matrix from DESIGN.md's rows.
fn rows(r: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array(&[
        r[0][0], r[1][0], r[2][0], r[0][1], r[1][1], r[2][1], r[0][2], r[1][2], r[2][2],
    ])
}

/// Fraction of the Cornell light's power that leaves through the open front (z = +1) on its first flight, by a stratified brute-force ray count against the box as DESIGN.md describes it (walls as planes, boxes by slab tests), independent of the BVH and of the tracer.
fn cornell_escape_fraction(n_pos: usize, n_dir: usize) -> f64 {
    let small = (
        rows([
            [0.286891, 0.0, -0.0877115],
            [0.0, 0.3, 0.0],
            [0.0877115, 0.0, 0.286891],
        ]),
        Vec3::new(0.335, -0.7, 0.38),
    );
    let large = (
        rows([
            [0.28491, 0.0, 0.0939491],
            [0.0, 0.61, 0.0],
            [-0.0939491, 0.0, 0.28491],
        ]),
        Vec3::new(-0.33, -0.4, -0.28),
    );
    let mut escaped = 0u64;
    let mut total = 0u64;
    for i in 0..n_pos {
        for j in 0..n_pos {
            let origin = Vec3::new(
                -0.23 + 0.46 * (i as f32 + 0.5) / n_pos as f32,
                0.99,
                0.01 - 0.19 + 0.38 * (j as f32 + 0.5) / n_pos as f32,
            );
            for a in 0..n_dir {
                for b in 0..n_dir {
                    let u = Vec2::new(
                        (a as f32 + 0.5) / n_dir as f32,
                        (b as f32 + 0.5) / n_dir as f32,
                    );
                    // Cosine lobe around -y.
                    let l = sample_cosine_hemisphere(u);
                    let dir = Vec3::new(l.x, -l.z, l.y);
                    total += 1;
                    // First wall the ray leaves the box through.
                    let mut exit = (f32::INFINITY, usize::MAX);
                    for (axis, face) in [(0usize, 0usize), (1, 1), (2, 2)] {
                        if dir[axis].abs() > 1e-9 {
                            let bound = if dir[axis] > 0.0 { 1.0 } else { -1.0 };
                            let t = (bound - origin[axis]) / dir[axis];
                            let code = face * 2 + usize::from(dir[axis] > 0.0);
                            if t < exit.0 {
                                exit = (t, code);
                            }
                        }
                    }
                    // Face code 5 is z = +1, the open front.
                    if exit.1 != 5 {
                        continue;
                    }
                    let blocked = [small, large].iter().any(|&(m, t)| {
                        hit_oriented_cube(origin, dir, m, t).is_some_and(|d| d < exit.0)
                    });
                    if !blocked {
                        escaped += 1;
                    }
                }
            }
        }
    }
    escaped as f64 / total as f64
}

/// Traces 100,000 photons through `scene` (cornell or its point-lit twin)
/// and holds the first bounce's power to the light's minus the fraction `f`
/// that escapes through the open front on its first flight.
fn check_first_bounce_power(scene: &Scene, f: f64) -> PhotonMap {
    let bvh = Bvh::build(scene);
    let n = 100_000u64;
    let options = TraceOptions {
        photons: n,
        seed: 11,
        ..TraceOptions::default()
    };
    let map = trace_photons(scene, &bvh, &options, &NoProgress).unwrap();
    let phi = scene.total_power();
    let first = map.power_by_bounce()[0];
    // Binomial standard deviation of the escaped fraction; 5 sigma plus the brute-force count's stratification error (generous 1e-3).
    let sigma = (f * (1.0 - f) / n as f64).sqrt();
    for c in 0..3 {
        let expected = f64::from(phi[c]) * (1.0 - f);
        let got = f64::from(first[c]);
        let tolerance = f64::from(phi[c]) * (5.0 * sigma + 1e-3);
        eprintln!(
            "channel {c}: first-bounce power {got:.4} W, expected {expected:.4} W (escape fraction {f:.5}, tolerance {tolerance:.4})"
        );
        assert!((got - expected).abs() <= tolerance);
    }
    map
}

#[test]
fn first_bounce_power_equals_light_power_minus_escape() {
    let scene = builtin("cornell").unwrap();
    check_first_bounce_power(&scene, cornell_escape_fraction(16, 96));
}

/// The same with cornell's light replaced by its cosine point light at the
/// centroid (section 3): the point sits on the emitter, which stays as
/// geometry, and its photons must leave it, not hit it at t = 0 (they did,
/// and were trapped between the emitter and the ceiling).
#[test]
fn point_light_photons_leave_their_emitter() {
    let scene = builtin("cornell")
        .unwrap()
        .with_area_lights_as_points()
        .unwrap();
    // The brute-force count from the light's centroid alone.
    let map = check_first_bounce_power(&scene, cornell_escape_fraction(1, 512));
    // And no photon's first hit is its emitter, which lies in the plane it
    // leaves from (later bounces may reach the emitter's face from below).
    let emitter = |s: u32| {
        let material = scene.surfaces()[s as usize].material;
        scene.materials()[material as usize].emission.max_element() > 0.0
    };
    let first_on_emitter = map
        .records()
        .iter()
        .filter(|r| r.bounce == 1 && emitter(r.surface))
        .count();
    assert_eq!(first_on_emitter, 0, "first hits on the emitter");
}

#[test]
fn white_furnace_power_per_bounce_is_geometric() {
    for albedo in [Rgb::splat(0.5), Rgb::new(0.8, 0.5, 0.2)] {
        let scene = support::furnace(albedo, Vec3::new(0.1, 0.2, -0.3));
        let bvh = Bvh::build(&scene);
        let n = 20_000u64;
        let options = TraceOptions {
            photons: n,
            seed: 3,
            max_bounces: 255,
            ..TraceOptions::default()
        };
        let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
        let phi = scene.total_power();
        let by_bounce = map.power_by_bounce();
        // Survival per bounce is q = max channel; the count at bounce k is Binomial(n, q^(k-1)).
        let q = f64::from(albedo.max_element());
        for k in 1..=8usize {
            let p = q.powi(k as i32 - 1);
            let rel_sigma = ((1.0 - p) / (p * n as f64)).sqrt();
            for c in 0..3 {
                let expected = f64::from(phi[c]) * f64::from(albedo[c]).powi(k as i32 - 1);
                let got = f64::from(by_bounce.get(k - 1).copied().unwrap_or_default()[c]);
                let tolerance = expected * (5.0 * rel_sigma + 1e-5);
                assert!(
                    (got - expected).abs() <= tolerance,
                    "albedo {albedo}, bounce {k}, channel {c}: {got} vs {expected} ± {tolerance}"
                );
            }
        }
        // Hits per photon: Σ q^(k-1) = 1/(1 - q), i.e. q/(1 - q) reflections.
        let hits = map.len() as f64 / n as f64;
        let expected = 1.0 / (1.0 - q);
        // Variance of a geometric count: q/(1-q)².
        let sigma = (q / (1.0 - q).powi(2) / n as f64).sqrt();
        eprintln!(
            "albedo {albedo}: {hits:.4} hits per photon, expected {expected:.4} ± {sigma:.4}"
        );
        assert!((hits - expected).abs() <= 5.0 * sigma);
    }
}

#[test]
fn result_does_not_depend_on_thread_count() {
    let scene = builtin("glosbox").unwrap();
    let bvh = Bvh::build(&scene);
    for emission in [EmissionSampling::Random, EmissionSampling::Sobol] {
        let options = TraceOptions {
            photons: 5_000,
            seed: 42,
            emission,
            ..TraceOptions::default()
        };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| trace_photons(&scene, &bvh, &options, &NoProgress).unwrap())
        };
        let one = run(1);
        let two = run(2);
        assert!(one.len() > 5_000);
        assert_eq!(one, two, "{emission:?}");
    }
}

#[test]
fn incremental_refinement_keeps_earlier_records() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).unwrap();
    let options = TraceOptions {
        photons: 3_000,
        seed: 5,
        ..TraceOptions::default()
    };
    let first = tracer.trace(&options, &NoProgress).unwrap();
    let mut map = first.clone();
    let reported = AtomicU64::new(0);
    let progress = |n: u64| {
        reported.fetch_add(n, Ordering::Relaxed);
    };
    tracer
        .trace_more(
            &mut map,
            &TraceOptions {
                photons: 2_000,
                ..options
            },
            &progress,
        )
        .unwrap();
    assert_eq!(reported.load(Ordering::Relaxed), 2_000);
    assert_eq!(map.emitted(), 5_000);
    assert_eq!(&map.records()[..first.len()], first.records());
    // The new photons are new: no record of the second batch repeats the first.
    assert!(
        map.records()[first.len()..]
            .iter()
            .all(|r| !first.records().contains(r))
    );
    // Equation 1 with the new m_i: one photon's power is Φ / 5000.
    let r = map.records()[0];
    let expected = scene.lights()[0].power() / 5_000.0 * r.rho;
    assert!((map.photon_power(&r) - expected).abs().max_element() <= 1e-6 * expected.max_element());
}

#[test]
fn invalid_options_are_errors() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let options = TraceOptions {
        photons: 10,
        max_bounces: 0,
        ..TraceOptions::default()
    };
    assert!(trace_photons(&scene, &bvh, &options, &NoProgress).is_err());
    let none = TraceOptions {
        photons: 0,
        ..TraceOptions::default()
    };
    assert!(
        trace_photons(&scene, &bvh, &none, &NoProgress)
            .unwrap()
            .is_empty()
    );
}
