//! The Gouraud pass (García Hernández, Ureña & Lastra 2003, section 2.4) on
//! the GPU against its CPU twin on a subdivided `cornell` lit by Impact Count,
//! and against closed forms: a constant per-corner radiance gives a constant
//! image, and an affine function of world position is reproduced exactly
//! (perspective-correct interpolation is linear in world space).

mod support;

use glam::Vec3;
use lustre_density::{RaySetOptions, impact_count, trace_ray_set};
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Bvh, Camera, Scene, builtin};
use lustre_mpr::diffuse_map::DiffuseMaps;
use lustre_mpr::passes::depth::{DepthPass, depth_pass_cpu};
use lustre_mpr::passes::emission::emission_pass_cpu;
use lustre_mpr::passes::gouraud::{
    GouraudPass, corner_layers, corner_radiance, gouraud_pass_cpu, gouraud_pass_cpu_tinted,
};
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::readback::{read_rgba_f32, read_u32};
use lustre_mpr::{FrameGraph, FrameInputs, GpuContext, NO_SURFACE, RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 96;

/// `cornell` with every mesh subdivided to edges of at most 0.25 m (the per-vertex lighting mesh of section 2.9, coarser).
fn fine_cornell() -> Scene {
    let scene = builtin("cornell").unwrap();
    let meshes = scene
        .meshes()
        .iter()
        .map(|m| subdivide(m, 0.25).unwrap())
        .collect();
    scene.with_meshes(meshes).unwrap()
}

/// Largest relative error the HDR target's format allows on top of f32 interpolation: half an ulp of f16, or a few f32 ulps.
fn format_tolerance(ctx: &GpuContext) -> f32 {
    match ctx.hdr_format() {
        wgpu::TextureFormat::Rgba16Float => 1e-3,
        _ => 0.0,
    }
}

/// Draws depth then Gouraud with `corners` and reads back the HDR target and the surface ids.
fn render(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    corners: &[[f32; 3]],
) -> (Vec<[f32; 4]>, Vec<u32>) {
    render_with_maps(ctx, scene, camera, corners, None)
}

/// [`render`] with the pass reading `maps` at the corners' `layers`.
fn render_with_maps(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    corners: &[[f32; 3]],
    maps: Option<(&DiffuseMaps, &[u32])>,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let targets = RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let depth = DepthPass::new(ctx).unwrap();
    let mut pass = GouraudPass::new(ctx, targets.hdr_format(), &buffers).unwrap();
    assert_eq!(pass.corners() as usize, corners.len());
    pass.set_radiance(&ctx.queue, corners).unwrap();
    if let Some((maps, layers)) = maps {
        pass.set_diffuse_maps(ctx, maps, layers).unwrap();
    }
    let (views, slot) = lustre_mpr::ViewBuffer::for_camera(ctx, camera).unwrap();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    lustre_mpr::frame::clear_hdr(&mut encoder, &targets);
    depth.encode(&mut encoder, &buffers, &targets, &views, slot, true);
    pass.encode(&mut encoder, &buffers, &targets, &views, slot)
        .unwrap();
    ctx.queue.submit([encoder.finish()]);
    (
        read_rgba_f32(ctx, &targets.hdr.texture).unwrap(),
        read_u32(ctx, &targets.surface_id.texture).unwrap(),
    )
}

/// The primary ray through each pixel centre of the `SIZE`² frame, row 0 at the top.
fn centre_rays(camera: &Camera) -> Vec<lustre_geometry::Ray> {
    (0..SIZE * SIZE)
        .map(|i| {
            camera.primary_ray(Camera::pixel_ndc(
                i % SIZE,
                i / SIZE,
                SIZE,
                SIZE,
                glam::Vec2::splat(0.5),
            ))
        })
        .collect()
}

/// Per-corner radiance `ρ/π E` of `scene` lit by Impact Count over 20,000 photons.
fn impact_count_corners(scene: &Scene, bvh: &Bvh) -> Vec<[f32; 3]> {
    let rays = trace_ray_set(
        scene,
        bvh,
        &RaySetOptions {
            photons: 20_000,
            seed: 3,
            ..Default::default()
        },
    )
    .unwrap();
    corner_radiance(scene, &impact_count(scene, &rays)).unwrap()
}

/// Pixels whose surface id agrees between GPU and CPU at the pixel and its four neighbours: away from silhouettes and surface boundaries.
fn interior(gpu_ids: &[u32], cpu_ids: &[u32]) -> Vec<usize> {
    let s = SIZE as usize;
    (0..gpu_ids.len())
        .filter(|&i| {
            let (x, y) = (i % s, i / s);
            if x == 0 || y == 0 || x + 1 == s || y + 1 == s || cpu_ids[i] == NO_SURFACE {
                return false;
            }
            [i, i - 1, i + 1, i - s, i + s]
                .iter()
                .all(|&j| gpu_ids[j] == cpu_ids[i] && cpu_ids[j] == cpu_ids[i])
        })
        .collect()
}

/// Largest `|g - c| / max(|c|, floor)` over `pixels` and channels.
fn max_relative(gpu: &[[f32; 4]], cpu: &[[f32; 3]], pixels: &[usize], floor: f32) -> f32 {
    pixels
        .iter()
        .flat_map(|&i| {
            (0..3).map(move |c| (gpu[i][c] - cpu[i][c]).abs() / cpu[i][c].abs().max(floor))
        })
        .fold(0.0, f32::max)
}

#[test]
fn gpu_gouraud_matches_cpu_on_cornell_lit_by_impact_count() {
    let Some(ctx) = gpu_or_skip("gpu_gouraud_matches_cpu_on_cornell") else {
        return;
    };
    let scene = fine_cornell();
    let bvh = Bvh::build(&scene);
    let camera = scene.camera().with_aspect(1.0);
    let corners = impact_count_corners(&scene, &bvh);
    let (gpu, gpu_ids) = render(&ctx, &scene, &camera, &corners);
    let cpu = gouraud_pass_cpu(&bvh, &camera, SIZE, SIZE, &corners);
    let cpu_ids = depth_pass_cpu(&bvh, &camera, SIZE, SIZE).surface;
    let pixels = interior(&gpu_ids, &cpu_ids);
    assert!(
        pixels.len() * 10 >= (SIZE * SIZE) as usize * 6,
        "{} interior pixels",
        pixels.len()
    );
    // Relative to the pixel's value, with a floor of 1 % of the brightest corner (dark channels of coloured walls).
    let peak = corners.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    let err = max_relative(&gpu, &cpu, &pixels, 0.01 * peak);
    eprintln!(
        "gouraud GPU vs CPU on {} of {} pixels: max relative error {err:.3e} (peak corner radiance {peak})",
        pixels.len(),
        SIZE * SIZE
    );
    assert!(
        err <= 1e-4 + format_tolerance(&ctx),
        "max relative error {err}"
    );
}

#[test]
fn gpu_gouraud_reads_diffuse_maps_per_fragment_as_the_cpu_does() {
    let Some(ctx) = gpu_or_skip("gpu_gouraud_reads_diffuse_maps_per_fragment") else {
        return;
    };
    // The 4 × 4 asymmetric map on every material, magnified over each wall
    // (level 0 on the GPU). The corners hold the untextured ρ/π E; both sides
    // scale the interpolated value by the map at the pixel's uv, the CPU with
    // Texture::sample in f32, the GPU from Rgba16Float with the sampler's
    // sub-texel weights a GPU may keep to 8 bits (the diffuse-texture test's
    // 2e-2; lavapipe here: 2.5e-4), while the map flipped or left out errs by
    // 0.2 or more.
    let scene = support::with_asymmetric_maps(fine_cornell(), "cornell-mapped");
    let bvh = Bvh::build(&scene);
    let camera = scene.camera().with_aspect(1.0);
    let corners = impact_count_corners(&scene, &bvh);
    let maps = DiffuseMaps::upload(&ctx, &scene).unwrap();
    let layers = corner_layers(&scene, &maps, &[]);
    assert!(
        layers.iter().all(|&l| l == 1),
        "one map, layer 1 on every corner"
    );
    let (gpu, gpu_ids) = render_with_maps(&ctx, &scene, &camera, &corners, Some((&maps, &layers)));
    let tint = |h: &lustre_geometry::Hit| scene.materials()[h.material as usize].diffuse_tint(h.uv);
    let cpu = gouraud_pass_cpu_tinted(&bvh, &camera, SIZE, SIZE, &corners, tint);
    let untinted = gouraud_pass_cpu(&bvh, &camera, SIZE, SIZE, &corners);
    let cpu_ids = depth_pass_cpu(&bvh, &camera, SIZE, SIZE).surface;
    // Where the map is magnified (a pixel's step in uv spans at most one of
    // the map's 4 texels), so that the GPU's trilinear read is level 0 too;
    // on the ceiling and floor seen at a grazing angle it is not (a tenth of
    // the tint off on 54 pixels, the next mip level's blur).
    let rays = centre_rays(&camera);
    let uvs: Vec<_> = bvh
        .closest_hits(&rays)
        .iter()
        .map(|h| h.map(|h| h.uv))
        .collect();
    let s = SIZE as usize;
    let magnified = |i: usize| {
        [i + 1, i + s]
            .iter()
            .all(|&j| match (uvs[i], uvs.get(j).copied().flatten()) {
                (Some(a), Some(b)) => ((b - a) * 4.0).abs().max_element() <= 1.0,
                _ => false,
            })
    };
    let pixels: Vec<usize> = interior(&gpu_ids, &cpu_ids)
        .into_iter()
        .filter(|&i| magnified(i))
        .collect();
    assert!(
        pixels.len() * 10 >= (SIZE * SIZE) as usize * 5,
        "{} pixels",
        pixels.len()
    );
    let peak = corners.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    let err = max_relative(&gpu, &cpu, &pixels, 0.01 * peak);
    let err_untinted = max_relative(&gpu, &untinted, &pixels, 0.01 * peak);
    eprintln!(
        "gouraud with diffuse maps, GPU vs CPU on {} pixels: max relative error {err:.3e}; against the map left out {err_untinted:.3e}",
        pixels.len()
    );
    assert!(err <= 2e-2, "max relative error {err}");
    assert!(
        err_untinted >= 0.2,
        "the map changes the image: {err_untinted}"
    );

    // Corners of meshes whose radiance holds the map already take the white layer.
    let all: Vec<u32> = (0..scene.meshes().len() as u32).collect();
    assert!(corner_layers(&scene, &maps, &all).iter().all(|&l| l == 0));
    // Refused: a layer count other than the corners', a layer the maps lack.
    let targets = RenderTargets::new(&ctx, 4, 4).unwrap();
    let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
    let mut pass = GouraudPass::new(&ctx, targets.hdr_format(), &buffers).unwrap();
    assert!(pass.set_diffuse_maps(&ctx, &maps, &layers[1..]).is_err());
    let mut beyond = layers.clone();
    beyond[5] = 2;
    let err = pass
        .set_diffuse_maps(&ctx, &maps, &beyond)
        .unwrap_err()
        .to_string();
    assert!(err.contains("layer 2"), "{err}");
}

#[test]
fn constant_and_affine_corner_radiance_are_reproduced_exactly() {
    let Some(ctx) = gpu_or_skip("constant_and_affine_corner_radiance_are_reproduced") else {
        return;
    };
    let scene = fine_cornell();
    let bvh = Bvh::build(&scene);
    let camera = scene.camera().with_aspect(1.0);
    let positions: Vec<Vec3> = scene
        .world_triangles()
        .iter()
        .flat_map(|t| t.positions)
        .collect();
    let cpu_ids = depth_pass_cpu(&bvh, &camera, SIZE, SIZE).surface;
    let rays = centre_rays(&camera);
    let hits = bvh.closest_hits(&rays);

    // Constant: L = (0.25, 1, 4) at every corner gives exactly that on every covered pixel.
    let constant = [0.25, 1.0, 4.0];
    let (gpu, gpu_ids) = render(&ctx, &scene, &camera, &vec![constant; positions.len()]);
    let covered: Vec<usize> = (0..gpu.len())
        .filter(|&i| gpu_ids[i] != NO_SURFACE)
        .collect();
    assert!(covered.len() * 10 >= (SIZE * SIZE) as usize * 9);
    let expected = vec![constant; gpu.len()];
    let err_constant = max_relative(&gpu, &expected, &covered, 0.0);
    let uncovered_black = (0..gpu.len())
        .filter(|&i| gpu_ids[i] == NO_SURFACE)
        .all(|i| gpu[i][..3] == [0.0; 3]);
    assert!(uncovered_black, "pixels seeing nothing stay black");

    // Affine in world position: L(P) = a + B P, positive in the box [-1, 1]^3.
    let affine = |p: Vec3| {
        [
            2.0 + 0.5 * p.x + 0.3 * p.y - 0.2 * p.z,
            3.0 - 0.7 * p.x + 0.4 * p.z,
            1.5 + 0.6 * p.y + 0.5 * p.z,
        ]
    };
    let corners: Vec<[f32; 3]> = positions.iter().map(|&p| affine(p)).collect();
    let (gpu, gpu_ids) = render(&ctx, &scene, &camera, &corners);
    let pixels = interior(&gpu_ids, &cpu_ids);
    let exact: Vec<[f32; 3]> = hits
        .iter()
        .map(|h| h.map_or([0.0; 3], |h| affine(h.position)))
        .collect();
    let err_affine = max_relative(&gpu, &exact, &pixels, 0.0);
    eprintln!(
        "constant: max relative error {err_constant:.3e} on {} covered pixels; affine: {err_affine:.3e} on {} interior pixels",
        covered.len(),
        pixels.len()
    );
    assert!(
        err_constant <= 1e-6 + format_tolerance(&ctx),
        "{err_constant}"
    );
    assert!(err_affine <= 1e-4 + format_tolerance(&ctx), "{err_affine}");
}

#[test]
fn frame_graph_adds_gouraud_radiance_to_the_emitters() {
    let Some(ctx) = gpu_or_skip("frame_graph_adds_gouraud_radiance_to_the_emitters") else {
        return;
    };
    let scene = fine_cornell();
    let bvh = Bvh::build(&scene);
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
    // Radiance without the pass is refused; a wrong corner count too.
    assert!(graph.set_gouraud_radiance(&ctx, &[]).is_err());
    let graph = graph
        .with_emission(&ctx, targets.hdr_format(), &scene)
        .unwrap()
        .with_gouraud(&ctx, targets.hdr_format(), &buffers)
        .unwrap();
    assert!(graph.set_gouraud_radiance(&ctx, &[[1.0; 3]]).is_err());
    // A smooth, non-affine function of the vertex position: one value per vertex, so continuous across triangle edges.
    let corners: Vec<[f32; 3]> = scene
        .world_triangles()
        .iter()
        .flat_map(|t| t.positions)
        .map(|p| {
            [
                0.5 + 0.4 * (3.0 * p.x).sin() * (2.0 * p.y).cos(),
                0.2 + 0.1 * p.z * p.z,
                0.3,
            ]
        })
        .collect();
    assert_eq!(corners.len(), buffers.vertex_count as usize);
    graph.set_gouraud_radiance(&ctx, &corners).unwrap();
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
    let gpu = read_rgba_f32(&ctx, &targets.hdr.texture).unwrap();
    let gpu_ids = read_u32(&ctx, &targets.surface_id.texture).unwrap();
    let cpu_ids = depth_pass_cpu(&bvh, &camera, SIZE, SIZE).surface;
    let emission = emission_pass_cpu(&scene, &bvh, &camera, SIZE, SIZE);
    let gouraud = gouraud_pass_cpu(&bvh, &camera, SIZE, SIZE, &corners);
    let cpu: Vec<[f32; 3]> = emission
        .iter()
        .zip(&gouraud)
        .map(|(e, g)| [e[0] + g[0], e[1] + g[1], e[2] + g[2]])
        .collect();
    let pixels = interior(&gpu_ids, &cpu_ids);
    let lit = pixels.iter().filter(|&&i| emission[i][0] > 0.0).count();
    assert!(lit >= 10, "{lit} interior pixels see the light");
    let err = max_relative(&gpu, &cpu, &pixels, 0.1);
    eprintln!("frame graph: emission + gouraud max relative error {err:.3e}");
    assert!(err <= 1e-4 + format_tolerance(&ctx), "{err}");
}

#[test]
fn an_empty_radiance_is_refused_and_a_mismatched_scene_is_not_drawn() {
    let Some(ctx) = gpu_or_skip("gouraud_refuses_mismatched_sizes") else {
        return;
    };
    let coarse = builtin("cornell").unwrap();
    let targets = RenderTargets::new(&ctx, 8, 8).unwrap();
    let coarse_buffers = SceneBuffers::upload(&ctx, &coarse).unwrap();
    let fine_buffers = SceneBuffers::upload(&ctx, &fine_cornell()).unwrap();
    let pass = GouraudPass::new(&ctx, targets.hdr_format(), &coarse_buffers).unwrap();
    assert_eq!(pass.corners(), 3 * coarse.triangle_count() as u32);
    let err = pass.set_radiance(&ctx.queue, &[]).unwrap_err().to_string();
    assert!(err.contains("corners"), "{err}");
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let (views, slot) =
        lustre_mpr::ViewBuffer::for_camera(&ctx, &coarse.camera().with_aspect(1.0)).unwrap();
    assert!(
        pass.encode(&mut encoder, &fine_buffers, &targets, &views, slot)
            .is_err()
    );
}
