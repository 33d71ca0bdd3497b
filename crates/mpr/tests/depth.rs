//! The depth pre-pass on the GPU against its CPU twin (BVH ray casts through
//! pixel centres) on `cornell` at 64×64: surface ids agree except within one
//! pixel of a surface-boundary edge; depth agrees within 1e-5.

mod support;

use glam::{Vec2, Vec3};
use lustre_geometry::{Bvh, Camera, WorldTriangle, builtin};
use lustre_mpr::passes::depth::{DepthImage, DepthPass, depth_pass_cpu};
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::readback::{read_depth, read_u32};
use lustre_mpr::{FrameGraph, FrameInputs, GpuContext, NO_SURFACE, RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 64;
/// Pixels whose centre is closer than this (in pixels) to a projected surface-boundary edge are not compared for ids.
const EDGE_MARGIN: f32 = 1.0;
/// Largest allowed |GPU − CPU| reverse-Z depth.
const DEPTH_TOLERANCE: f32 = 1e-5;

/// Triangle edges across which the surface id can change: edges not shared
/// with another triangle of the same surface (a quad's diagonal is dropped,
/// a box's rim is kept, hidden or not).
fn boundary_edges(triangles: &[WorldTriangle], eps: f32) -> Vec<[Vec3; 2]> {
    let same = |a: [Vec3; 2], b: [Vec3; 2]| {
        (a[0].distance(b[0]) <= eps && a[1].distance(b[1]) <= eps)
            || (a[0].distance(b[1]) <= eps && a[1].distance(b[0]) <= eps)
    };
    let edges = |t: &WorldTriangle| {
        let p = t.positions;
        [[p[0], p[1]], [p[1], p[2]], [p[2], p[0]]]
    };
    let mut out = Vec::new();
    for (i, t) in triangles.iter().enumerate() {
        for e in edges(t) {
            let shared = triangles.iter().enumerate().any(|(j, u)| {
                j != i && u.surface == t.surface && edges(u).iter().any(|&f| same(e, f))
            });
            if !shared {
                out.push(e);
            }
        }
    }
    out
}

/// The edge clipped to the camera's near plane and projected to pixel
/// coordinates (x right, y down, pixel centres at +0.5); `None` if behind.
fn project_edge(camera: &Camera, [a, b]: [Vec3; 2], width: u32, height: u32) -> Option<[Vec2; 2]> {
    let view = camera.view_matrix();
    let (mut a, mut b) = (view.transform_point3(a), view.transform_point3(b));
    // In view space the camera looks down −z; keep z ≤ −near.
    let limit = -camera.near;
    match (a.z <= limit, b.z <= limit) {
        (false, false) => return None,
        (true, false) => b = a + (b - a) * ((limit - a.z) / (b.z - a.z)),
        (false, true) => a = b + (a - b) * ((limit - b.z) / (a.z - b.z)),
        (true, true) => {}
    }
    let projection = camera.projection_matrix();
    let to_pixels = |p: Vec3| {
        let ndc = projection.project_point3(p);
        Vec2::new(
            (ndc.x + 1.0) * 0.5 * width as f32,
            (1.0 - ndc.y) * 0.5 * height as f32,
        )
    };
    Some([to_pixels(a), to_pixels(b)])
}

/// Distance from `p` to the segment `[a, b]`.
fn segment_distance(p: Vec2, [a, b]: [Vec2; 2]) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Per pixel: distance in pixels from its centre to the nearest projected surface-boundary edge.
fn edge_distance_image(triangles: &[WorldTriangle], camera: &Camera, eps: f32) -> Vec<f32> {
    let segments: Vec<_> = boundary_edges(triangles, eps)
        .into_iter()
        .filter_map(|e| project_edge(camera, e, SIZE, SIZE))
        .collect();
    (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .map(|c| {
            segments
                .iter()
                .map(|&s| segment_distance(c, s))
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

/// GPU depth pre-pass of `scene` through `camera`: (depth, surface ids).
fn gpu_depth(
    ctx: &GpuContext,
    scene: &lustre_geometry::Scene,
    camera: &Camera,
) -> (Vec<f32>, Vec<u32>) {
    let targets = RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let pass = DepthPass::new(ctx).unwrap();
    let (views, slot) = lustre_mpr::ViewBuffer::for_camera(ctx, camera).unwrap();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    pass.encode(&mut encoder, &buffers, &targets, &views, slot, true);
    ctx.queue.submit([encoder.finish()]);
    (
        read_depth(ctx, &targets.depth.texture).unwrap(),
        read_u32(ctx, &targets.surface_id.texture).unwrap(),
    )
}

/// Compares GPU output with the CPU twin; returns a summary line.
fn compare(cpu: &DepthImage, depth: &[f32], ids: &[u32], edge_distance: &[f32]) -> String {
    let mut excluded = 0;
    let mut excluded_mismatch = 0;
    let mut compared = 0;
    let (mut max_abs, mut max_rel) = (0.0f32, 0.0f32);
    let mut misses = 0;
    let mut worst_mismatch = 0.0f32;
    for i in 0..cpu.surface.len() {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        if edge_distance[i] < EDGE_MARGIN {
            excluded += 1;
            excluded_mismatch += usize::from(ids[i] != cpu.surface[i]);
            if ids[i] != cpu.surface[i] {
                worst_mismatch = worst_mismatch.max(edge_distance[i]);
            } else {
                // Same surface near an edge: the depth must still agree.
                let d = (depth[i] - cpu.depth[i]).abs();
                assert!(
                    d <= DEPTH_TOLERANCE,
                    "pixel ({x}, {y}) near an edge: GPU depth {} vs CPU {}",
                    depth[i],
                    cpu.depth[i]
                );
                max_abs = max_abs.max(d);
                if cpu.depth[i] > 0.0 {
                    max_rel = max_rel.max(d / cpu.depth[i]);
                }
            }
            continue;
        }
        compared += 1;
        misses += usize::from(cpu.surface[i] == NO_SURFACE);
        assert_eq!(
            ids[i], cpu.surface[i],
            "pixel ({x}, {y}) is {:.2} px from the nearest boundary edge: GPU surface {} vs CPU {}",
            edge_distance[i], ids[i], cpu.surface[i]
        );
        let d = (depth[i] - cpu.depth[i]).abs();
        assert!(
            d <= DEPTH_TOLERANCE,
            "pixel ({x}, {y}): GPU depth {} vs CPU {}",
            depth[i],
            cpu.depth[i]
        );
        max_abs = max_abs.max(d);
        if cpu.depth[i] > 0.0 {
            max_rel = max_rel.max(d / cpu.depth[i]);
        }
    }
    format!(
        "{compared} pixels compared ({misses} background), {excluded} within {EDGE_MARGIN} px of a boundary edge \
         ({excluded_mismatch} of those differ, the farthest {worst_mismatch:.4} px from an edge); surface ids agree on all compared; \
         max |Δdepth| where ids agree = {max_abs:.3e} (relative {max_rel:.3e})"
    )
}

#[test]
fn gpu_depth_prepass_matches_cpu_ray_casts_on_cornell() {
    let Some(ctx) = gpu_or_skip("gpu_depth_prepass_matches_cpu_ray_casts_on_cornell") else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let triangles = scene.world_triangles();
    let eps = 1e-5 * scene.bounds().extent().max_element();
    let bvh = Bvh::build(&scene);
    // The scene camera, and one from above and to the side that sees the boxes' tops and the floor at a slant.
    let cameras = [
        scene.camera().with_aspect(1.0),
        Camera::look_at(
            Vec3::new(0.6, 0.7, 2.5),
            Vec3::new(-0.1, -0.6, -0.2),
            Vec3::Y,
            55.0,
        ),
    ];
    for (k, camera) in cameras.iter().enumerate() {
        let (depth, ids) = gpu_depth(&ctx, &scene, camera);
        let cpu = depth_pass_cpu(&bvh, camera, SIZE, SIZE);
        let edge_distance = edge_distance_image(&triangles, camera, eps);
        eprintln!(
            "camera {k}: {}",
            compare(&cpu, &depth, &ids, &edge_distance)
        );
    }
}

#[test]
fn frame_graph_renders_depth_and_black_into_any_view() {
    let Some(ctx) = gpu_or_skip("frame_graph_renders_depth_and_black_into_any_view") else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let camera = scene.camera().with_aspect(1.0);
    let targets = RenderTargets::new(&ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("output"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let graph = FrameGraph::new(&ctx, format).unwrap();
    graph
        .render(
            &ctx,
            &FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera: &camera,
                tonemap: &Tonemap::default(),
                targets: &targets,
                output: &output.create_view(&Default::default()),
                splats: None,
                direct: None,
                diffuse: None,
            },
        )
        .unwrap();
    // No light passes yet: the HDR target stays cleared, so the image is black.
    let pixels = lustre_mpr::readback::read_rgba8(&ctx, &output).unwrap();
    assert!(pixels.iter().all(|&p| p == [0, 0, 0, 255]));
    // The depth pre-pass ran in the same encoder.
    let ids = read_u32(&ctx, &targets.surface_id.texture).unwrap();
    let cpu = depth_pass_cpu(&Bvh::build(&scene), &camera, SIZE, SIZE);
    let agree = ids.iter().zip(&cpu.surface).filter(|(a, b)| a == b).count();
    assert!(
        agree * 100 >= ids.len() * 90,
        "{agree} of {} ids agree",
        ids.len()
    );
}
