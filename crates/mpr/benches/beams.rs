//! Frame times of the beam pass (Duvenhage et al. 2010, sections 4.3 and
//! 5.2) at 640×480 against the number of scatterer triangles, the paper's
//! linear traversal beside the beam hierarchy, on the adapter
//! `GpuContext::new(AdapterPreference::Hardware)` gives (printed).
//!
//! Scenes: `cardioid` with its ring of mirrors cut into 80, 800 or 10,000
//! triangles (the ring's shape unchanged), so every count lights the same
//! floor with the same caustic; and `pool`'s 800 water triangles. One frame
//! is the depth pre-pass and the beam pass alone (no direct light, no
//! splats), encode + submit + `device.poll(wait)`, beams and hierarchy built
//! and uploaded before timing. Building the beams on the CPU is timed
//! separately (`build-*`). The beams are those `lustre render --technique
//! beams` draws: scattered beams only (the direct pass's shadows stand for
//! the shadow beams).
//!
//! In the cardioid every ring facet throws a wide beam across the whole
//! ring, so a floor fragment lies in the boxes of most beams and the
//! hierarchy cannot cull; under the pool's water each fragment lies in a
//! few refracted beams. On a software adapter the frames are 320×240 and
//! the slowest configurations are left out (ten frames of them would take
//! from a quarter of an hour to hours on two cores): the linear traversal
//! of 800 cardioid triangles and every configuration of 10,000.
//! Criterion times at least 10 frames per configuration. Without an adapter
//! the bench prints why and measures nothing.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use lustre_beams::{BeamSet, BuildOptions};
use lustre_geometry::{Scene, builtin};
use lustre_mpr::frame::FrameInputs;
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::beams::Traversal;
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::{
    AdapterPreference, FrameGraph, GpuContext, MprError, RenderTargets, SceneBuffers,
};

/// Image size on a hardware adapter.
const SIZE: (u32, u32) = (640, 480);
/// Image size on a software adapter.
const SOFTWARE_SIZE: (u32, u32) = (320, 240);
/// Scatterer triangles of each cardioid configuration.
const COUNTS: [usize; 3] = [80, 800, 10_000];

/// `cardioid` with its ring cut into `triangles` mirror triangles, its camera's aspect that of `size`.
fn ring_scene(triangles: usize, (width, height): (u32, u32)) -> Scene {
    let mut scene = builtin::cardioid::cardioid_with(triangles / 2);
    scene.set_camera(scene.camera().with_aspect(width as f32 / height as f32));
    scene
}

fn beams(c: &mut Criterion) {
    let ctx = match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => ctx,
        Err(e @ MprError::NoAdapter { .. }) => {
            eprintln!("beams bench: {e}; nothing measured");
            return;
        }
        Err(e) => panic!("beams bench: {e}"),
    };
    eprintln!("beams bench on {}", ctx.adapter());
    let software = ctx.adapter().is_software();
    let (width, height) = if software { SOFTWARE_SIZE } else { SIZE };
    eprintln!("frames of {width}x{height}");
    let targets = RenderTargets::new(&ctx, width, height).unwrap();
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("beams-bench-output"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let output_view = output.create_view(&Default::default());
    let mut group = c.benchmark_group("beams");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    let mut pool = builtin::pool();
    pool.set_camera(pool.camera().with_aspect(width as f32 / height as f32));
    let scenes = COUNTS
        .iter()
        .map(|&n| (format!("cardioid-{n}"), n, ring_scene(n, (width, height))))
        .chain([("pool-800".to_owned(), 800, pool)]);
    for (label, count, scene) in scenes {
        if software && count > 1000 {
            eprintln!("{label}: left out on a software adapter (module docs)");
            continue;
        }
        let options = BuildOptions {
            shadow_beams: false,
            ..BuildOptions::default()
        };
        group.bench_function(format!("build-{label}"), |b| {
            b.iter(|| BeamSet::from_scene(&scene, &options).unwrap())
        });
        let set = BeamSet::from_scene(&scene, &options).unwrap();
        let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
        let maps = lustre_mpr::diffuse_map::DiffuseMaps::upload(&ctx, &scene).unwrap();
        let camera = *scene.camera();
        for traversal in [Traversal::Linear, Traversal::Hierarchy] {
            if software && traversal == Traversal::Linear && label == "cardioid-800" {
                eprintln!("{label} linear: left out on a software adapter (module docs)");
                continue;
            }
            let graph = FrameGraph::new(&ctx, format)
                .unwrap()
                .with_beams(
                    &ctx,
                    targets.hdr_format(),
                    &scene,
                    GlossyModel::Exact,
                    &maps,
                    &set,
                    traversal,
                )
                .unwrap();
            let frame = FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera: &camera,
                tonemap: &Tonemap::default(),
                targets: &targets,
                output: &output_view,
                splats: None,
                direct: None,
                diffuse: None,
            };
            graph.render(&ctx, &frame).unwrap();
            ctx.wait().unwrap();
            eprintln!(
                "{label}: {} beams ({} scattered, {} shadow), {} hierarchy boxes, {} bytes on the GPU",
                set.beams().len(),
                set.stats().scattered,
                set.stats().shadow,
                set.hierarchy().len(),
                graph.beams.as_ref().map_or(0, |b| b.byte_size())
            );
            let name = match traversal {
                Traversal::Linear => format!("frame-{label}-linear"),
                Traversal::Hierarchy => format!("frame-{label}-hierarchy"),
            };
            group.bench_function(name, |b| {
                b.iter(|| {
                    graph.render(&ctx, &frame).unwrap();
                    ctx.wait().unwrap();
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, beams);
criterion_main!(benches);
