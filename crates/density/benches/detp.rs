//! DETP estimate times on the subdivided Cornell box (sections 2.6–2.9): brute force against the ray cache (sorted and unsorted queries), disc indexing and the segment grid, each with every pre-intersection test (section 2.8, table 2.5); the disc-index leaf-size sweep per radius in the form of table 2.2; and the mobile object's discs (section 2.5.2).
//!
//! Sizes: by default the Cornell box subdivided to 0.1 m edges (6 499
//! vertices) and 20 000 photons, so that the whole bench takes a few
//! minutes. `DETP_BENCH_FULL=1` uses the paper-sized setting: 0.05 m edges
//! (23 979 vertices) and 100 000 photons (262 574 segments), where brute
//! force is timed once outside criterion (an iteration takes minutes on two
//! cores): over every disc without pre-test, over every 8th disc (times 8)
//! with one. `DETP_BENCH_EDGE` and `DETP_BENCH_PHOTONS` override either.
//! A positional filter (`cargo bench --bench detp -- leaf_`) also skips the
//! other groups' setup, or `DETP_BENCH_GROUPS=detp_r,mobile` (group name
//! prefixes) selects the groups whatever the filter; `DETP_BENCH_BRUTE`
//! (pre-test names, e.g. `none,plucker`) limits the full-size brute-force
//! runs.
//!
//! Groups:
//! - `detp_r0.050`: the full estimate (`DiscSet::accumulate` over every
//!   segment) for each acceleration × pre-test at radius 0.05;
//!   `detp_r0.025`, `detp_r0.100`: the same without pre-tests.
//! - `leaf_r…` (`BENCH_DISC_INDEX`): disc indexing with
//!   `max_per_leaf` ∈ {1, 2, 4, 8, 16, 32, 64} (depth 32) per radius; its
//!   minima give `Acceleration::tuned_disc_index`.
//! - `mobile`: the discs of the tall box moved each frame (`update_discs`
//!   then a full estimate), and the persistent segment grid
//!   (`accumulate_grid`) with its per-frame maintenance.

//!
//! Medians with `DETP_BENCH_FULL=1` on the 2-core Xeon (23 979 discs,
//! 262 574 segments; brute force single runs, the ×8 ones over every 8th
//! disc; machine shared, so a few percent of noise):
//!
//! | r = 0.05 | none | Badouel | Plücker | Möller |
//! |---|---|---|---|---|
//! | brute force | 37.6 s | 67.6 s | 77.9 s | 73.1 s |
//! | ray cache, sorted | 1.10 s | 1.32 s | 1.39 s | 1.44 s |
//! | ray cache, unsorted | 12.8 s | | | |
//! | disc index (leaf 16) | 0.330 s | 0.418 s | 0.411 s | 0.416 s |
//! | segment grid, cells 2r | 0.745 s | 0.913 s | 0.954 s | 0.955 s |
//! | segment grid, cells 4r | 1.30 s | 1.67 s | 1.74 s | 1.77 s |
//!
//! | no pre-test | r = 0.025 | r = 0.05 | r = 0.1 |
//! |---|---|---|---|
//! | brute force | 37.5 s | 37.6 s | 37.4 s |
//! | ray cache, sorted | 0.892 s | 1.10 s | 3.48 s |
//! | ray cache, unsorted | 11.7 s | 12.8 s | 28 s |
//! | disc index (tuned) | 0.221 s (leaf 8) | 0.330 s (16) | 0.568 s (16) |
//! | segment grid, cells 2r | 0.618 s | 0.745 s | 2.57 s |
//! | segment grid, cells 4r | 0.509 s | 1.30 s | 6.4 s |
//!
//! `BENCH_DISC_INDEX`, disc index time (ms) by leaf size (depth 32; the
//! paper's table 2.2 b):
//!
//! | leaf | 1 | 2 | 4 | 8 | 16 | 32 | 64 |
//! |---|---|---|---|---|---|---|---|
//! | r = 0.025 | 271 | 253 | 235 | **223** | **223** | 241 | 296 |
//! | r = 0.05 | 435 | 391 | 349 | 327 | **320** | 337 | 392 |
//! | r = 0.1 | 867 | 758 | 646 | 594 | **562** | 586 | 674 |
//!
//! The same sweep after the leaves were tested eight discs at a time and
//! the nodes given normal cones (2026-12-07, a 2-core Intel Xeon with
//! AVX-512, its L3 shared with other machines):
//!
//! | leaf | 1 | 2 | 4 | 8 | 16 | 32 | 64 |
//! |---|---|---|---|---|---|---|---|
//! | r = 0.025 | 186 | 179 | 161 | 142 | 130 | **125** | 126 |
//! | r = 0.05 | 302 | 275 | 265 | 227 | 220 | **202** | 205 |
//! | r = 0.1 | 681 | 586 | 473 | 390 | 359 | **331** | 337 |
//!
//! Mobile object (5 046 discs of the tall box, moved each frame), per frame:
//! `update_discs` + full estimate 7.90 s brute force, 1.06 s ray cache,
//! 68 ms disc index, 205 ms per-call segment grid; a persistent grid of
//! 0.1 m cells answers in 206 ms, is built in 222 ms and replaces 5 % of
//! its segments in 31 ms.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DVec3, Quat, Vec3};
use lustre_density::accel::{scene_discs, scene_slack};
use lustre_density::{
    Acceleration, Disc, DiscSet, DiscSetOptions, PreTest, RaySegment, RaySetOptions, SegmentGrid,
    trace_ray_set,
};
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Aabb, Bvh, Scene, builtin};

/// The bench's sizes: mesh edge and photons.
fn sizes() -> (f32, u64, bool) {
    let full = std::env::var("DETP_BENCH_FULL").is_ok_and(|v| v == "1");
    let (mut edge, mut photons) = if full { (0.05, 100_000) } else { (0.1, 20_000) };
    if let Some(e) = std::env::var("DETP_BENCH_EDGE")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        edge = e;
    }
    if let Some(p) = std::env::var("DETP_BENCH_PHOTONS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        photons = p;
    }
    (edge, photons, full)
}

/// Whether a group is selected by the positional filters given to the bench (criterion's filters, matched here as plain substrings, `|` separating alternatives), so that unselected groups skip their setup and their single runs.
fn wanted(group: &str) -> bool {
    if let Ok(groups) = std::env::var("DETP_BENCH_GROUPS") {
        return groups.split(',').any(|g| group.starts_with(g.trim()));
    }
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    filters.is_empty()
        || filters
            .iter()
            .flat_map(|f| f.split('|'))
            .any(|f| group.contains(f) || f.starts_with(group))
}

/// The subdivided Cornell box and its ray set, traced once.
fn setup() -> &'static (Scene, Vec<RaySegment>, f32, bool) {
    static SHARED: std::sync::OnceLock<(Scene, Vec<RaySegment>, f32, bool)> =
        std::sync::OnceLock::new();
    SHARED.get_or_init(trace)
}

/// Builds the subdivided Cornell box and traces its ray set.
fn trace() -> (Scene, Vec<RaySegment>, f32, bool) {
    let (edge, photons, full) = sizes();
    let scene = builtin("cornell").expect("cornell is built in");
    let meshes = scene
        .meshes()
        .iter()
        .map(|m| subdivide(m, edge).expect("subdivides"))
        .collect();
    let scene = scene.with_meshes(meshes).expect("same meshes");
    let bvh = Bvh::build(&scene);
    let rays = trace_ray_set(
        &scene,
        &bvh,
        &RaySetOptions {
            photons,
            seed: 1,
            max_segments: 64,
            extension: 0.0,
        },
    )
    .expect("traces");
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    (scene, segments, edge, full)
}

/// Short name of a pre-test.
fn pretest_name(p: PreTest) -> &'static str {
    match p {
        PreTest::None => "none",
        PreTest::Badouel => "badouel",
        PreTest::Plucker => "plucker",
        PreTest::MollerTrumbore => "moller",
    }
}

/// The accelerations compared at one radius.
fn accelerations(radius: f32, edge: f32) -> Vec<(&'static str, Acceleration)> {
    vec![
        ("ray_cache_sorted", Acceleration::RayCache { sorted: true }),
        (
            "ray_cache_unsorted",
            Acceleration::RayCache { sorted: false },
        ),
        (
            "disc_index_tuned",
            Acceleration::tuned_disc_index(radius, edge),
        ),
        (
            "segment_grid_2r",
            Acceleration::SegmentGrid {
                cell_size: 2.0 * radius,
            },
        ),
        (
            "segment_grid_4r",
            Acceleration::SegmentGrid {
                cell_size: 4.0 * radius,
            },
        ),
    ]
}

/// A disc set over `discs`.
fn set(discs: &[Disc], slack: f32, acceleration: Acceleration, pretest: PreTest) -> DiscSet {
    DiscSet::new(
        discs.to_vec(),
        DiscSetOptions {
            slack,
            acceleration,
            pretest,
        },
    )
    .expect("valid options")
}

/// One full estimate.
fn estimate(set: &DiscSet, segments: &[RaySegment]) -> f64 {
    let mut out = vec![DVec3::ZERO; set.len()];
    set.accumulate(segments, 1.0, &mut out)
        .expect("sizes match");
    out.iter().map(|v| v.x).sum()
}

fn detp(c: &mut Criterion) {
    for radius in [0.05f32, 0.025, 0.1] {
        let name = format!("detp_r{radius:.3}");
        if !wanted(&name) {
            continue;
        }
        let (scene, segments, edge, full) = setup();
        let (edge, full) = (*edge, *full);
        let slack = scene_slack(scene);
        let (discs, _) = scene_discs(scene, radius);
        eprintln!(
            "{name}: {} discs, {} segments, edge {edge}",
            discs.len(),
            segments.len()
        );
        let pretests: &[PreTest] = if radius == 0.05 {
            &PreTest::ALL
        } else {
            &[PreTest::None]
        };
        let mut group = c.benchmark_group(&name);
        group.sample_size(10);
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(3));
        for &pretest in pretests {
            let brute_wanted = std::env::var("DETP_BENCH_BRUTE").map_or(true, |v| {
                v.split(',').any(|p| p.trim() == pretest_name(pretest))
            });
            if full && !brute_wanted {
                // Skipped (`DETP_BENCH_BRUTE` lists the pre-tests to time brute force with).
            } else if full {
                // One run; with a pre-test, on every 8th disc only, scaled by 8.
                let (subset, scale): (Vec<Disc>, f64) = if pretest == PreTest::None {
                    (discs.clone(), 1.0)
                } else {
                    (discs.iter().step_by(8).copied().collect(), 8.0)
                };
                let brute = set(&subset, slack, Acceleration::BruteForce, pretest);
                let t = Instant::now();
                black_box(estimate(&brute, segments));
                eprintln!(
                    "{name}/brute_force/{}: {:.2} s (single run{})",
                    pretest_name(pretest),
                    t.elapsed().as_secs_f64() * scale,
                    if scale > 1.0 {
                        ", 1/8 of the discs, x8"
                    } else {
                        ""
                    }
                );
            } else {
                let brute = set(&discs, slack, Acceleration::BruteForce, pretest);
                group.bench_function(format!("brute_force/{}", pretest_name(pretest)), |b| {
                    b.iter(|| black_box(estimate(&brute, segments)))
                });
            }
            for (label, acceleration) in accelerations(radius, edge) {
                if full && pretest != PreTest::None && label == "ray_cache_unsorted" {
                    // Seconds per iteration at full size: measured without pre-test only.
                    continue;
                }
                let s = set(&discs, slack, acceleration, pretest);
                group.bench_function(format!("{label}/{}", pretest_name(pretest)), |b| {
                    b.iter(|| black_box(estimate(&s, segments)))
                });
            }
        }
        group.finish();
    }
}

/// `BENCH_DISC_INDEX`: the leaf-size sweep of table 2.2 b, per radius.
fn leaf_sweep(c: &mut Criterion) {
    for radius in [0.025f32, 0.05, 0.1] {
        let name = format!("leaf_r{radius:.3}");
        if !wanted(&name) {
            continue;
        }
        let (scene, segments, _, _) = setup();
        let slack = scene_slack(scene);
        let (discs, _) = scene_discs(scene, radius);
        let mut group = c.benchmark_group(&name);
        group.sample_size(10);
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(2));
        for leaf in [1usize, 2, 4, 8, 16, 32, 64] {
            let s = set(
                &discs,
                slack,
                Acceleration::DiscIndex {
                    max_per_leaf: leaf,
                    max_depth: 32,
                },
                PreTest::None,
            );
            group.bench_function(format!("leaf_{leaf:02}"), |b| {
                b.iter(|| black_box(estimate(&s, segments)))
            });
        }
        group.finish();
    }
}

/// The mobile object's discs (section 2.5.2): the tall box's vertices, moved each frame.
fn mobile(c: &mut Criterion) {
    if !wanted("mobile") {
        return;
    }
    let (scene, segments, edge, _) = setup();
    let (segments, edge) = (&segments[..], *edge);
    let slack = scene_slack(scene);
    let radius = 0.05;
    let (discs, starts) = scene_discs(scene, radius);
    let m = starts.len() - 2;
    let box_discs: Vec<Disc> = discs[starts[m]..starts[m + 1]].to_vec();
    let centre = box_discs.iter().map(|d| d.centre).sum::<Vec3>() / box_discs.len() as f32;
    let frames: Vec<Vec<Disc>> = (0..8)
        .map(|f| {
            let q = Quat::from_rotation_y(0.05 * f as f32);
            let shift = Vec3::new(0.01 * f as f32, 0.0, 0.0);
            box_discs
                .iter()
                .map(|d| Disc {
                    centre: q * (d.centre - centre) + centre + shift,
                    normal: (q * d.normal).normalize_or_zero(),
                    ..*d
                })
                .collect()
        })
        .collect();
    let mut group = c.benchmark_group(format!("mobile_{}discs", box_discs.len()));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for (name, acceleration) in [
        ("brute_force", Acceleration::BruteForce),
        ("ray_cache_sorted", Acceleration::RayCache { sorted: true }),
        (
            "disc_index_tuned",
            Acceleration::tuned_disc_index(radius, edge),
        ),
        (
            "segment_grid_2r",
            Acceleration::SegmentGrid {
                cell_size: 2.0 * radius,
            },
        ),
    ] {
        let mut s = set(&box_discs, slack, acceleration, PreTest::None);
        let mut f = 0;
        group.bench_function(format!("update_and_estimate/{name}"), |b| {
            b.iter(|| {
                f = (f + 1) % frames.len();
                s.update_discs(&frames[f]).expect("same count");
                black_box(estimate(&s, segments))
            })
        });
    }
    let b = scene.bounds();
    let bounds = Aabb {
        min: b.min - 0.01,
        max: b.max + 0.01,
    };
    for cell in [2.0 * radius, 4.0 * radius] {
        let grid = SegmentGrid::from_segments(bounds, cell, slack, segments).expect("grid");
        let mut s = set(&box_discs, slack, Acceleration::BruteForce, PreTest::None);
        let mut f = 0;
        group.bench_function(
            format!("persistent_grid_{cell:.2}/update_and_estimate"),
            |bch| {
                bch.iter(|| {
                    f = (f + 1) % frames.len();
                    s.update_discs(&frames[f]).expect("same count");
                    let mut out = vec![DVec3::ZERO; s.len()];
                    s.accumulate_grid(&grid, 1.0, &mut out).expect("grid");
                    black_box(out)
                })
            },
        );
        group.bench_function(format!("persistent_grid_{cell:.2}/build"), |bch| {
            bch.iter(|| {
                black_box(
                    SegmentGrid::from_segments(bounds, cell, slack, segments)
                        .expect("grid")
                        .registrations(),
                )
            })
        });
        // A frame's maintenance: 5 % of the segments replaced (OldRays out, NewRays in).
        let mut grid = grid;
        let n = segments.len();
        let mut round = 0usize;
        group.bench_function(format!("persistent_grid_{cell:.2}/replace_5pct"), |bch| {
            bch.iter(|| {
                round += 1;
                for j in (round % 20..n).step_by(20) {
                    grid.remove(j as u32);
                    grid.insert(j as u32, &segments[(j + round) % n]);
                }
                black_box(grid.len())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, detp, leaf_sweep, mobile);
criterion_main!(benches);
