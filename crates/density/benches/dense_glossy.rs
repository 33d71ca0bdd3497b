//! DETP on a dense glossy model as a user brings one (issue 15): a procedural
//! bumpy blob of 71,820 triangles with a glossy Phong material and a small
//! mobile ball beside it, loaded from OBJ text without a light so that it gets
//! the default studio, meshed and estimated with `lustre render`'s defaults
//! (disc radius 2.5 % and mesh edge 5 % of the model's size, glossy radius 3 ×
//! the radius, the QuadTree glossy estimate, artifact control).
//!
//! `dense_glossy/first_frame`: the ray set, every vertex's estimate and the
//! glossy radiance towards the camera (everything of a `lustre render
//! --technique detp` frame but the GPU). `dense_glossy/frame`: one
//! quasi-static frame as the ball rolls round the blob (photosimulation update,
//! radiosity recalculation and the glossy radiance). The split (medians over
//! the first loop of the ball's path, the same 32 frames whatever number of
//! frames criterion runs), the vertex counts and the memory go to
//! `target/criterion/dense_glossy/<config>.json`.
//! `LUSTRE_BENCH_DENSE_PHOTONS` sets the photon count (default 1,000,000),
//! `LUSTRE_BENCH_DENSE_GLOSSY_FACTOR` the glossy radius over the disc radius
//! (default 3, `lustre render`'s; 1 is the paper's one disc for both).

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

mod common;

use std::f32::consts::PI;
use std::fmt::Write as _;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Quat, Vec3};
use lustre_density::artifact::ArtifactOptions;
use lustre_density::glossy::GlossyMode;
use lustre_density::quadtree::QuadTreeOptions;
use lustre_density::{Estimator, FrameStats, QuasiStatic, QuasiStaticOptions, vertex_lit_scene};
use lustre_geometry::ObjectId;
use lustre_geometry::animation::{Keyframe, ObjectPath, PathEnd};
use lustre_geometry::obj::load_obj;

use common::{median, ms};

/// Rings and segments of the blob's sphere (71,820 triangles).
const RINGS: usize = 190;
/// Frames per loop of the ball's path.
const FRAMES: usize = 32;

/// The OBJ and MTL text of the blob and the ball: no light.
fn model() -> (String, String) {
    let mut obj = String::from("mtllib dense.mtl\no blob\nusemtl glossy\n");
    let (rings, segments) = (RINGS, RINGS);
    for i in 0..=rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = 2.0 * PI * j as f32 / segments as f32;
            let r = 1.0
                + 0.08 * (5.0 * theta).sin() * (7.0 * phi).cos()
                + 0.04 * (13.0 * phi + 3.0 * theta).sin();
            let _ = writeln!(
                obj,
                "v {} {} {}",
                r * theta.sin() * phi.cos(),
                1.1 + r * theta.cos(),
                r * theta.sin() * phi.sin()
            );
        }
    }
    let index = |i: usize, j: usize| i * segments + j % segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            if i > 0 {
                let _ = writeln!(obj, "f {a} {c} {b}");
            }
            if i < rings - 1 {
                let _ = writeln!(obj, "f {a} {d} {c}");
            }
        }
    }
    // A 0.3 m cube, the mobile ball, resting on the ground in front of the blob.
    let first = (rings + 1) * segments + 1;
    obj.push_str("o ball\nusemtl white\n");
    for k in 0..8 {
        let corner = |bit: usize| if k & bit != 0 { 0.15 } else { -0.15 };
        let _ = writeln!(
            obj,
            "v {} {} {}",
            corner(1),
            0.15 + corner(2),
            1.6 + corner(4)
        );
    }
    for quad in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        let [a, b, c, d] = quad.map(|q| q + first);
        let _ = writeln!(obj, "f {a} {b} {c}\nf {a} {c} {d}");
    }
    let mtl = "newmtl glossy\nKd 0.3 0.25 0.2\nKs 0.5 0.5 0.5\nNs 200\n\
               newmtl white\nKd 0.7 0.7 0.7\n"
        .to_owned();
    (obj, mtl)
}

/// The ball's path: once round the blob's vertical axis at 1.6 m.
fn ball_path() -> ObjectPath {
    let keys = (0..=8)
        .map(|k| {
            let angle = 2.0 * PI * k as f32 / 8.0;
            let rotation = Quat::from_rotation_y(angle);
            Keyframe::new(k as f32, rotation * Vec3::new(0.0, 0.15, 1.6), rotation)
        })
        .collect();
    ObjectPath::new(keys, PathEnd::Loop)
        .and_then(|p| p.with_pivot(Vec3::new(0.0, 0.15, 1.6)))
        .expect("the ball's path is valid")
}

fn bench(c: &mut Criterion) {
    let photons: u64 = std::env::var("LUSTRE_BENCH_DENSE_PHOTONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let glossy_factor: f32 = std::env::var("LUSTRE_BENCH_DENSE_GLOSSY_FACTOR")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|f: &f32| *f >= 1.0 && f.is_finite())
        .unwrap_or(3.0);
    let dir = std::env::temp_dir().join(format!("lustre-dense-glossy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let (obj, mtl) = model();
    std::fs::write(dir.join("dense.obj"), obj).expect("write the OBJ");
    std::fs::write(dir.join("dense.mtl"), mtl).expect("write the MTL");
    let loaded = load_obj(&dir.join("dense.obj")).expect("the dense model loads");
    let _ = std::fs::remove_dir_all(&dir);
    let size = loaded.studio.expect("a studio").model_size;
    let (radius, edge) = (0.025 * size, 0.05 * size);
    let scene = vertex_lit_scene(
        &loaded.scene.with_mobile("ball", ball_path()).expect("ball"),
        edge,
    )
    .expect("meshed scene");
    let ball: ObjectId = scene.object_by_name("ball").expect("ball");
    let poses = scene.mobile_objects()[0].path.frames(FRAMES);
    let eye = scene.camera().position;
    let mut options = QuasiStaticOptions::new(Estimator::Detp { radius }, photons);
    options.rays.seed = 1;
    options.artifact = Some(ArtifactOptions::default());
    options.glossy = Some(GlossyMode::QuadTree {
        options: QuadTreeOptions::default(),
        tolerance: 0.01,
    });
    options.glossy_radius = Some(glossy_factor * radius);

    let out = common::results_dir("dense_glossy");

    let mut group = c.benchmark_group("dense_glossy");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(1));
    let mut firsts: Vec<(FrameStats, Duration)> = Vec::new();
    group.bench_function(format!("first_frame-{photons}"), |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let t = Instant::now();
                let sim = QuasiStatic::new(scene.clone(), &[ball], options).expect("first frame");
                let glossy_start = Instant::now();
                let radiance = sim.glossy_radiance(eye).expect("glossy radiance");
                let glossy = glossy_start.elapsed();
                std::hint::black_box(radiance);
                total += t.elapsed();
                firsts.push((sim.first_frame(), glossy));
            }
            total
        })
    });
    let mut sim = QuasiStatic::new(scene.clone(), &[ball], options).expect("first frame");
    let mut frame = 0usize;
    let mut stats: Vec<(FrameStats, Duration)> = Vec::new();
    // Old and New Rays held deferred on glossy vertices facing away from the eye, after each frame.
    let mut deferred: Vec<f64> = Vec::new();
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    // One frame: the ball to its next pose, then the glossy radiance; the time of both.
    let ran = std::cell::Cell::new(0usize);
    let mut step = || {
        ran.set(ran.get() + 1);
        frame = (frame + 1) % FRAMES;
        let t = Instant::now();
        let s = sim.set_pose(&[(ball, poses[frame])]).expect("frame");
        let glossy_start = Instant::now();
        std::hint::black_box(sim.glossy_radiance(eye).expect("glossy radiance"));
        let glossy = glossy_start.elapsed();
        let total = t.elapsed();
        stats.push((s, glossy));
        deferred.push(sim.deferred_glossy_rays() as f64);
        total
    };
    group.bench_function(format!("frame-{photons}"), |b| {
        b.iter_custom(|iters| (0..iters).map(|_| step()).sum())
    });
    group.finish();
    // The split over the first loop of the ball's path, the same frames whatever number criterion ran:
    // a slow machine that ran fewer finishes the loop here.
    while ran.get() < FRAMES {
        step();
    }
    let split = &stats[..FRAMES];
    let (ray_bytes, state_bytes) = sim.memory_bytes();
    let info = serde_json::json!({
        "photons": photons,
        "triangles": scene.triangle_count(),
        "estimation_points": sim.points().points.len(),
        "segments": sim.rays().segments().count(),
        "model_size": size,
        "radius": radius,
        "glossy_radius": glossy_factor * radius,
        "mesh_edge": edge,
        "first_frame_photosimulation_ms": median(firsts.iter().map(|(s, _)| ms(s.photosimulation)).collect()),
        "first_frame_radiosity_ms": median(firsts.iter().map(|(s, _)| ms(s.radiosity)).collect()),
        "first_frame_glossy_radiance_ms": median(firsts.iter().map(|(_, g)| ms(*g)).collect()),
        "median_photosimulation_update_ms": median(split.iter().map(|(s, _)| ms(s.photosimulation)).collect()),
        "median_radiosity_ms": median(split.iter().map(|(s, _)| ms(s.radiosity)).collect()),
        "median_glossy_radiance_ms": median(split.iter().map(|(_, g)| ms(*g)).collect()),
        "median_recalculated_paths": median(split.iter().map(|(s, _)| s.recalculated as f64).collect()),
        "median_deferred_glossy_rays": median(deferred[..split.len()].to_vec()),
        "split_frames": split.len(),
        "frames_measured": stats.len(),
        "ray_set_bytes": ray_bytes,
        "state_bytes": state_bytes,
    });
    let _ = std::fs::write(
        out.join(format!("{photons}.json")),
        serde_json::to_string_pretty(&info).unwrap_or_default(),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
