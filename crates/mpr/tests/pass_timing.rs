//! Per-pass GPU times (timestamps between the passes): every pass of a frame is named, none is negative, and together they fit inside the wall-clock time the frame took, measured on the CPU around it.

mod support;

use std::time::Instant;

use lustre_geometry::builtin;
use lustre_geometry::light::jittered_point_lights;
use lustre_mpr::FrameGraph;
use support::{direct_frame, gpu_or_skip};

#[test]
fn pass_times_name_every_pass_and_fit_in_the_frame() {
    let Some(ctx) = gpu_or_skip("pass_times_name_every_pass_and_fit_in_the_frame") else {
        return;
    };
    if !ctx.has_timestamps() {
        eprintln!(
            "SKIPPED pass timing: adapter {} has no timestamp queries inside encoders",
            ctx.adapter()
        );
        return;
    }
    let scene = builtin("glosbox").unwrap();
    let graph = FrameGraph::new(&ctx, wgpu::TextureFormat::Rgba8Unorm)
        .unwrap()
        .with_emission(&ctx, ctx.hdr_format(), &scene)
        .unwrap()
        .with_direct(&ctx, ctx.hdr_format())
        .unwrap()
        .with_pass_timing(&ctx);
    assert!(graph.pass_times(&ctx).unwrap().unwrap().is_empty());
    let lights = jittered_point_lights(scene.lights(), 4, glam::Vec2::ZERO);
    let start = Instant::now();
    let _ = direct_frame(&ctx, &graph, &scene, scene.camera(), &lights, 64);
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    let times = graph.pass_times(&ctx).unwrap().unwrap();
    let names: Vec<&str> = times.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["depth", "emission", "direct light", "tone map"]);
    let total: f64 = times.iter().map(|(_, ms)| ms).sum();
    for (name, ms) in &times {
        assert!(*ms >= 0.0 && ms.is_finite(), "{name}: {ms} ms");
    }
    assert!(total > 0.0, "{times:?}");
    assert!(
        total <= wall_ms,
        "passes {total:.3} ms in a frame of {wall_ms:.3} ms wall: {times:?}"
    );
}
