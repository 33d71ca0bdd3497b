//! Per-frame cost of the quasi-static loop on García et al.'s tree scene (section 2.9): the ball rolls along its path, each iteration is one frame (photosimulation update, figure 2.2, plus radiosity recalculation, equation 2.4 / figure 2.4 / full Photon Maps). Criterion measures the whole frame; the split, the first frame and the memory per photon go to `target/criterion/quasi_static_tree/<config>.json` for `cargo xtask bench`.
//!
//! `LUSTRE_BENCH_DENSITY_MAX` (default 100000) caps the photon counts 10k, 100k, 1M. DETP runs with the tuned disc index, and with each other speed-up (`detp_<speed-up>`, sections 2.6–2.8) up to 100k photons (brute force: 10k).

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

mod common;

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Affine3A;
use lustre_density::{
    Acceleration, Estimator, FrameStats, PreTest, QuasiStatic, QuasiStaticOptions,
};
use lustre_geometry::{ObjectId, builtin};

use common::{median, ms};

/// Frames per loop of the ball's path.
const FRAMES: usize = 32;

fn bench(c: &mut Criterion) {
    let max: u64 = std::env::var("LUSTRE_BENCH_DENSITY_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let scene = builtin("tree").expect("built-in tree");
    let mobile = scene.mobile_objects()[0].clone();
    let poses: Vec<Affine3A> = mobile.path.frames(FRAMES);
    let ids: Vec<ObjectId> = vec![mobile.object];
    let out = common::results_dir("quasi_static_tree");
    let mut group = c.benchmark_group("quasi_static_tree");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for photons in [10_000u64, 100_000, 1_000_000]
        .into_iter()
        .filter(|&p| p <= max)
    {
        for (name, estimator, acceleration, pretest) in CONFIGS {
            // The other speed-ups stop at 100k photons, brute force at 10k (its first frame tests every segment at 83k discs).
            let limit = match acceleration {
                None => u64::MAX,
                Some(Acceleration::BruteForce) => 10_000,
                Some(_) => 100_000,
            };
            if photons > limit {
                continue;
            }
            let mut options = QuasiStaticOptions::new(*estimator, photons);
            options.rays.seed = 1;
            options.acceleration = *acceleration;
            options.pretest = *pretest;
            let mut sim = QuasiStatic::new(scene.clone(), &ids, options).expect("first frame");
            let first = sim.first_frame();
            let mut frame = 0usize;
            let mut stats: Vec<FrameStats> = Vec::new();
            let config = format!("{name}-{photons}");
            group.bench_function(&config, |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        frame = (frame + 1) % FRAMES;
                        let s = sim
                            .set_pose(&[(mobile.object, poses[frame])])
                            .expect("frame");
                        total += s.photosimulation + s.radiosity;
                        stats.push(s);
                    }
                    total
                })
            });
            let (ray_bytes, state_bytes) = sim.memory_bytes();
            let emitted = sim.rays().emitted().max(1);
            let info = serde_json::json!({
                "estimator": name,
                "photons": photons,
                "triangles": sim.scene().triangle_count(),
                "estimation_points": sim.points().points.len(),
                "segments": sim.rays().segments().count(),
                "first_frame_photosimulation_ms": ms(first.photosimulation),
                "first_frame_radiosity_ms": ms(first.radiosity),
                "median_photosimulation_update_ms": median(stats.iter().map(|s| ms(s.photosimulation)).collect()),
                "median_radiosity_ms": median(stats.iter().map(|s| ms(s.radiosity)).collect()),
                "median_recalculated_paths": median(stats.iter().map(|s| s.recalculated as f64).collect()),
                "frames_measured": stats.len(),
                "ray_set_bytes_per_photon": ray_bytes as f64 / emitted as f64,
                "state_bytes": state_bytes,
            });
            let _ = std::fs::write(
                out.join(format!("{config}.json")),
                serde_json::to_string_pretty(&info).unwrap_or_default(),
            );
        }
    }
    group.finish();
}

/// DETP's radius: 1 % of the scene, as the paper's (section 2.9).
const RADIUS: f32 = 0.02;

/// The configurations measured: DETP with the tuned disc index and with each other speed-up (sections 2.6–2.8), Impact Count, Photon Maps.
const CONFIGS: &[(&str, Estimator, Option<Acceleration>, PreTest)] = &[
    (
        "detp",
        Estimator::Detp { radius: RADIUS },
        None,
        PreTest::None,
    ),
    (
        "detp_moller",
        Estimator::Detp { radius: RADIUS },
        None,
        PreTest::MollerTrumbore,
    ),
    (
        "detp_ray_cache",
        Estimator::Detp { radius: RADIUS },
        Some(Acceleration::RayCache { sorted: true }),
        PreTest::None,
    ),
    (
        "detp_segment_grid",
        Estimator::Detp { radius: RADIUS },
        Some(Acceleration::SegmentGrid {
            cell_size: 2.0 * RADIUS,
        }),
        PreTest::None,
    ),
    (
        "detp_brute_force",
        Estimator::Detp { radius: RADIUS },
        Some(Acceleration::BruteForce),
        PreTest::None,
    ),
    ("impact", Estimator::ImpactCount, None, PreTest::None),
    (
        "photonmap",
        Estimator::PhotonMaps { k: 50 },
        None,
        PreTest::None,
    ),
];

criterion_group!(benches, bench);
criterion_main!(benches);
