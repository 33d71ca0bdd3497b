//! Antialiasing by jittered accumulation (Diefenbach & Badler 1997, section
//! 7) on the GPU: the emitting rectangle of `cornell`, drawn by the emission
//! pass through [`FrameGraph::render_accumulated`], against its exact
//! coverage of each pixel (the projected quad clipped to the pixel square,
//! the box filter of the reference) and against the fraction of the jitter
//! pattern's points inside it; one sample is the unjittered frame, bit for
//! bit. Emitters drawn apart through more jittered cameras than the frames
//! (`FrameGraph::with_emission_samples`) follow the larger pattern.

mod support;

use glam::{DVec2, Vec2, Vec3};
use lustre_geometry::light::{AreaShape, Light, hammersley_centred};
use lustre_geometry::{Camera, Scene, builtin};
use lustre_mpr::frame::AccumulatedSplats;
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::readback::read_rgba_f32;
use lustre_mpr::{FrameGraph, FrameInputs, GpuContext, RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 96;

/// The light's rectangle in pixel coordinates (x right, y down), counter-clockwise on screen.
fn light_polygon(scene: &Scene, camera: &Camera) -> (Vec<DVec2>, f32) {
    let Some(Light::Area(light)) = scene.lights().first() else {
        panic!("cornell has one area light");
    };
    let mut corners: Vec<Vec3> = match &light.shape {
        AreaShape::Rectangle {
            origin,
            edge_u,
            edge_v,
        } => vec![
            *origin,
            *origin + *edge_u,
            *origin + *edge_u + *edge_v,
            *origin + *edge_v,
        ],
        AreaShape::Triangles { triangles, .. } => triangles.iter().flatten().copied().collect(),
    };
    corners.dedup_by(|a, b| a.distance(*b) < 1e-6);
    let vp = camera.view_projection().as_dmat4();
    let mut points: Vec<DVec2> = corners
        .iter()
        .map(|p| {
            let clip = vp * p.as_dvec3().extend(1.0);
            let ndc = DVec2::new(clip.x / clip.w, clip.y / clip.w);
            DVec2::new(
                (ndc.x + 1.0) * 0.5 * SIZE as f64,
                (1.0 - ndc.y) * 0.5 * SIZE as f64,
            )
        })
        .collect();
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup_by(|a, b| a.distance(*b) < 1e-9);
    let centre = points.iter().copied().sum::<DVec2>() / points.len() as f64;
    points.sort_by(|a, b| {
        let (da, db) = (*a - centre, *b - centre);
        da.y.atan2(da.x).total_cmp(&db.y.atan2(db.x))
    });
    assert_eq!(points.len(), 4, "the light is a quad: {points:?}");
    (points, light.radiance.x)
}

/// Area of a polygon (shoelace), positive for the order of [`light_polygon`].
fn area(polygon: &[DVec2]) -> f64 {
    let n = polygon.len();
    0.5 * (0..n)
        .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
        .sum::<f64>()
}

/// The polygon clipped to the half-plane `dot(p, normal) <= offset` (Sutherland–Hodgman).
fn clip(polygon: &[DVec2], normal: DVec2, offset: f64) -> Vec<DVec2> {
    let mut out = Vec::new();
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        let (da, db) = (a.dot(normal) - offset, b.dot(normal) - offset);
        if da <= 0.0 {
            out.push(a);
        }
        if (da < 0.0) != (db < 0.0) && da != db {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// Exact fraction of pixel `(x, y)` the polygon covers: the box filter.
fn coverage(polygon: &[DVec2], x: u32, y: u32) -> f64 {
    let (x, y) = (f64::from(x), f64::from(y));
    let mut p = polygon.to_vec();
    for (normal, offset) in [
        (DVec2::new(-1.0, 0.0), -x),
        (DVec2::new(1.0, 0.0), x + 1.0),
        (DVec2::new(0.0, -1.0), -y),
        (DVec2::new(0.0, 1.0), y + 1.0),
    ] {
        p = clip(&p, normal, offset);
        if p.len() < 3 {
            return 0.0;
        }
    }
    area(&p).abs()
}

/// Whether a point is inside the convex polygon.
fn inside(polygon: &[DVec2], p: DVec2) -> bool {
    let n = polygon.len();
    let sign = area(polygon).signum();
    (0..n).all(|i| {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        sign * (b - a).perp_dot(p - a) > 0.0
    })
}

/// Fraction of the `n` pattern points of pixel `(x, y)` inside the polygon.
fn pattern_coverage(polygon: &[DVec2], x: u32, y: u32, n: u32) -> f64 {
    let hits = (0..n)
        .filter(|&i| {
            let o = hammersley_centred(i, n).as_dvec2();
            inside(polygon, DVec2::new(f64::from(x), f64::from(y)) + o)
        })
        .count();
    hits as f64 / f64::from(n)
}

/// The emission pass alone through `render_accumulated` with `samples`; HDR radiance.
fn render(ctx: &GpuContext, scene: &Scene, camera: &Camera, samples: u32) -> Vec<[f32; 4]> {
    render_with_emission_samples(ctx, scene, camera, samples, 0)
}

/// [`render`] with the emitters drawn apart through `emission` jittered
/// cameras ([`FrameGraph::with_emission_samples`]).
fn render_with_emission_samples(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    samples: u32,
    emission: u32,
) -> Vec<[f32; 4]> {
    let targets = RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let graph = FrameGraph::new(ctx, format)
        .unwrap()
        .with_emission(ctx, targets.hdr_format(), scene)
        .unwrap()
        .with_emission_samples(emission)
        .with_accumulation(ctx, targets.hdr_format())
        .unwrap();
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("antialias-output"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = output.create_view(&wgpu::TextureViewDescriptor::default());
    let mut calls = 0;
    graph
        .render_accumulated(
            ctx,
            &FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera,
                tonemap: &Tonemap::default(),
                targets: &targets,
                output: &view,
                splats: None,
                direct: None,
                diffuse: None,
            },
            samples,
            AccumulatedSplats::EverySample,
            &mut |_| {
                calls += 1;
                Ok(())
            },
        )
        .unwrap();
    assert_eq!(calls, samples.max(1), "before_sample runs once per sample");
    read_rgba_f32(ctx, &targets.hdr.texture).unwrap()
}

#[test]
fn accumulated_edges_match_the_exact_pixel_coverage_of_the_light() {
    let Some(ctx) = gpu_or_skip("accumulated_edges_match_the_exact_pixel_coverage_of_the_light")
    else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let camera = scene.camera().with_aspect(1.0);
    let (polygon, le) = light_polygon(&scene, &camera);
    // The front and back edges of the quad are horizontal on screen (they
    // run along x, parallel to the image plane): y of the upper and lower pairs.
    let mut ys: Vec<f64> = polygon.iter().map(|p| p.y).collect();
    ys.sort_by(f64::total_cmp);
    let (top, bottom) = (ys[1], ys[2]);
    assert!(
        (ys[1] - ys[0]).abs() < 1e-3 && (ys[3] - ys[2]).abs() < 1e-3,
        "horizontal front and back edges: {ys:?}"
    );
    eprintln!("light quad in pixels: {polygon:?}, Le.r = {le}");
    let mut mean_errors = Vec::new();
    for n in [1u32, 4, 16, 64] {
        let hdr = render(&ctx, &scene, &camera, n);
        let (mut partial, mut off_pattern, mut sum_error, mut max_error) = (0, 0, 0.0, 0.0f64);
        let (mut horizontal, mut max_horizontal) = (0, 0.0f64);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let value = f64::from(hdr[(y * SIZE + x) as usize][0]) / f64::from(le);
                let exact = coverage(&polygon, x, y);
                let pattern = pattern_coverage(&polygon, x, y, n);
                // The GPU samples the pattern: the same fraction, unless a
                // point within rounding of an edge falls the other way.
                let off = (value - pattern).abs();
                assert!(
                    off <= 1.0 / f64::from(n) + 1e-5,
                    "N = {n}: pixel ({x}, {y}) is {value}, the pattern covers {pattern}"
                );
                off_pattern += usize::from(off > 1e-5);
                if exact <= 0.0 || exact >= 1.0 {
                    assert!(
                        (value - exact).abs() <= 1e-5,
                        "N = {n}: pixel ({x}, {y}) wholly in or out of the light is {value}"
                    );
                    continue;
                }
                partial += 1;
                let error = (value - exact).abs();
                sum_error += error;
                max_error = max_error.max(error);
                // Pixels crossed only by the quad's horizontal front or back
                // edge (the clipped quad is a band over the pixel's whole
                // width, bounded by one of those edges): the pattern's y
                // coordinates are stratified in N strata of one point each
                // (N a power of two), so it is at most 1/(2N) off.
                let (y0, y1) = (f64::from(y), f64::from(y) + 1.0);
                let (a, b) = (y0.max(top), y1.min(bottom));
                let eps = 1e-6;
                let band = [a + eps, b - eps].iter().all(|&py| {
                    inside(&polygon, DVec2::new(f64::from(x) + eps, py))
                        && inside(&polygon, DVec2::new(f64::from(x) + 1.0 - eps, py))
                });
                if band && ((a > y0) != (b < y1)) {
                    horizontal += 1;
                    max_horizontal = max_horizontal.max(error);
                    assert!(
                        error <= 0.5 / f64::from(n) + 1e-4,
                        "N = {n}: pixel ({x}, {y}) on a horizontal edge is {value}, covered {exact}"
                    );
                }
            }
        }
        let mean = sum_error / partial as f64;
        eprintln!(
            "N = {n}: {partial} partly covered pixels, mean |value - coverage| {mean:.4}, max \
             {max_error:.4}; {horizontal} on horizontal edges, max {max_horizontal:.4} (bound \
             {:.4}); {off_pattern} pixels off the pattern's count",
            0.5 / f64::from(n)
        );
        assert!(
            partial >= 20,
            "N = {n}: the light's edges cross {partial} pixels"
        );
        assert!(
            horizontal >= 8,
            "N = {n}: {horizontal} horizontal-edge pixels"
        );
        assert!(
            off_pattern * 20 <= partial,
            "N = {n}: {off_pattern} of {partial} pixels differ from the pattern's count"
        );
        mean_errors.push(mean);
    }
    // Stratified jittered sampling converges at least as N^(-3/4) for edges:
    // 16 times the samples, at least 8 times smaller mean error.
    assert!(
        mean_errors[3] * 8.0 <= mean_errors[1],
        "mean error {:.4} at N = 64 vs {:.4} at N = 4",
        mean_errors[3],
        mean_errors[1]
    );
}

#[test]
fn emitters_drawn_apart_follow_their_own_larger_pattern() {
    let Some(ctx) = gpu_or_skip("emitters_drawn_apart_follow_their_own_larger_pattern") else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let camera = scene.camera().with_aspect(1.0);
    let (polygon, le) = light_polygon(&scene, &camera);
    // Four jittered frames, the emitters through 64 cameras of their own.
    let (frames, apart) = (4u32, 64u32);
    let graph_check = FrameGraph::new(&ctx, wgpu::TextureFormat::Rgba8Unorm)
        .unwrap()
        .with_emission_samples(apart);
    assert_eq!(
        graph_check.emission_samples(lustre_mpr::GraphTerms::ALL, frames),
        frames,
        "without an emission pass nothing is drawn apart"
    );
    let hdr = render_with_emission_samples(&ctx, &scene, &camera, frames, apart);
    let plain = render(&ctx, &scene, &camera, frames);
    let (mut partial, mut off_pattern, mut sum_apart, mut sum_plain) = (0, 0, 0.0, 0.0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let i = (y * SIZE + x) as usize;
            let value = f64::from(hdr[i][0]) / f64::from(le);
            let exact = coverage(&polygon, x, y);
            let pattern = pattern_coverage(&polygon, x, y, apart);
            let off = (value - pattern).abs();
            assert!(
                off <= 1.0 / f64::from(apart) + 1e-5,
                "pixel ({x}, {y}) is {value}, the 64-point pattern covers {pattern}"
            );
            off_pattern += usize::from(off > 1e-5);
            if exact <= 0.0 || exact >= 1.0 {
                assert!((value - exact).abs() <= 1e-5, "pixel ({x}, {y}) is {value}");
                continue;
            }
            partial += 1;
            sum_apart += (value - exact).abs();
            sum_plain += (f64::from(plain[i][0]) / f64::from(le) - exact).abs();
        }
    }
    let (mean_apart, mean_plain) = (sum_apart / partial as f64, sum_plain / partial as f64);
    eprintln!(
        "{partial} partly covered pixels: mean |value - coverage| {mean_apart:.4} apart, \
         {mean_plain:.4} in the 4 frames; {off_pattern} off the pattern's count"
    );
    assert!(partial >= 20 && off_pattern * 20 <= partial);
    assert!(
        mean_apart * 8.0 <= mean_plain,
        "apart {mean_apart:.4}, in the frames {mean_plain:.4}"
    );
}

#[test]
fn one_sample_is_the_unjittered_frame_bit_for_bit() {
    let Some(ctx) = gpu_or_skip("one_sample_is_the_unjittered_frame_bit_for_bit") else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let camera = scene.camera().with_aspect(1.0);
    assert_eq!(hammersley_centred(0, 1), Vec2::splat(0.5));
    assert_eq!(
        camera.with_pixel_offset(Vec2::splat(0.5), SIZE, SIZE),
        camera,
        "the pixel centre is no jitter"
    );
    let accumulated = render(&ctx, &scene, &camera, 1);
    // The plain frame, as before accumulation existed.
    let targets = RenderTargets::new(&ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let graph = FrameGraph::new(&ctx, format)
        .unwrap()
        .with_emission(&ctx, targets.hdr_format(), &scene)
        .unwrap();
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("plain-output"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = output.create_view(&wgpu::TextureViewDescriptor::default());
    graph
        .render(
            &ctx,
            &FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera: &camera,
                tonemap: &Tonemap::default(),
                targets: &targets,
                output: &view,
                splats: None,
                direct: None,
                diffuse: None,
            },
        )
        .unwrap();
    let plain = read_rgba_f32(&ctx, &targets.hdr.texture).unwrap();
    assert!(plain.iter().any(|p| p[0] > 0.0), "the light is in view");
    assert!(
        plain
            .iter()
            .zip(&accumulated)
            .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
        "one accumulated sample differs from the plain frame"
    );
}
