//! Shadow volumes on the GPU (Diefenbach & Badler 1997, sections 4.1, 4.4,
//! 7.3) on `cornell` at 96×96: the lit mask (stencil == SHAD_ZERO after the
//! z-fail count) against BVH shadow rays from the visible point of each
//! pixel, for a camera outside every volume and one inside the large box's
//! shadow, and, with a jittered light, against the CPU z-fail twin with the
//! central silhouette. Pixels within 2 px of a change of the CPU mask are
//! not compared (rasterisation of a boundary is decided at the pixel centre
//! by the GPU's rules, not by the exact test); ≥ 99.5 % of the rest agree.
//! Then the frame graph's direct light under shadow volumes (sections 4.1,
//! 4.4, 7.2) with cornell's area light as jittered point lights, against the
//! CPU twin with BVH shadow rays and against shadow maps, and after an
//! object moves (section 4.3).

mod support;

use glam::{Vec2, Vec3};
use lustre_geometry::light::{jittered_point_lights, paired_rotation, pivot_point_lights};
use lustre_geometry::shadow_volume::{ShadowVolumeSet, light_position, shadow_count};
use lustre_geometry::{Bvh, Camera, Light, Ray, Scene, builtin};
use lustre_mpr::material::{GlossyModel, scene_materials};
use lustre_mpr::passes::depth::DepthPass;
use lustre_mpr::passes::direct::{DirectLights, DirectPixel, direct_pixels_cpu_with_lights};
use lustre_mpr::passes::shadow::ShadowSettings;
use lustre_mpr::passes::shadow_volume::{ShadowVolumeBuffers, ShadowVolumePass, VolumeLights};
use lustre_mpr::passes::shadowed_direct::VolumeJitter;
use lustre_mpr::readback::read_rgba8;
use lustre_mpr::{FrameGraph, GpuContext, NO_SURFACE, RenderTargets, SceneBuffers, ViewBuffer};
use support::gpu_or_skip;

const SIZE: u32 = 96;

fn gpu_mask(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    set: &ShadowVolumeSet,
    light: Vec3,
) -> Vec<bool> {
    let targets = RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let depth = DepthPass::new(ctx).unwrap();
    let (views, slot) = ViewBuffer::for_camera(ctx, camera).unwrap();
    let pass = ShadowVolumePass::new(ctx, wgpu::TextureFormat::Rgba8Unorm).unwrap();
    // Light 1 is the one tested; light 0 (elsewhere) checks the dynamic offset.
    let mut lights = VolumeLights::new(ctx, &pass, 1);
    lights
        .write(ctx, &pass, &[Vec3::new(9.0, 9.0, 9.0), light])
        .unwrap();
    let volumes = ShadowVolumeBuffers::upload(ctx, set.volumes_for_light(0)).unwrap();
    let mask = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("mask"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = mask.create_view(&Default::default());
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    // Clears the mask.
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear-mask"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    depth.encode(&mut encoder, &buffers, &targets, &views, slot, true);
    {
        let mut render = ShadowVolumePass::begin_pass(&mut encoder, &targets, &view, "mask");
        pass.record_begin(&mut render, slot.stencil_reference)
            .unwrap();
        pass.record_volumes(&mut render, &views, slot, &lights, 1, &volumes)
            .unwrap();
        pass.record_lit_mask(&mut render);
        pass.record_end(&mut render, slot.stencil_reference)
            .unwrap();
    }
    ctx.queue.submit([encoder.finish()]);
    read_rgba8(ctx, &mask)
        .unwrap()
        .iter()
        .map(|t| t[0] > 127)
        .collect()
}

/// Per pixel: the visible point and its geometric normal, if any.
fn visible(bvh: &Bvh, camera: &Camera) -> Vec<Option<(Vec3, Vec3)>> {
    (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray = camera.primary_ray(Camera::pixel_ndc(x, y, SIZE, SIZE, Vec2::splat(0.5)));
            bvh.closest_hit(&ray)
                .map(|h| (h.position, h.geometric_normal))
        })
        .collect()
}

/// Agreement of the GPU mask with `lit` over pixels with a visible point,
/// clear of the light's own quad and at least 3 px from a change of `lit`.
fn agreement(gpu: &[bool], lit: &[Option<bool>]) -> (usize, usize) {
    let (mut agree, mut total) = (0, 0);
    let s = SIZE as i32;
    for y in 0..s {
        for x in 0..s {
            let Some(l) = lit[(y * s + x) as usize] else {
                continue;
            };
            let near_boundary = (-2..=2).any(|dy| {
                (-2..=2).any(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    (0..s).contains(&u)
                        && (0..s).contains(&v)
                        && lit[(v * s + u) as usize].is_some_and(|o| o != l)
                })
            });
            if near_boundary {
                continue;
            }
            total += 1;
            agree += usize::from(gpu[(y * s + x) as usize] == l);
        }
    }
    (agree, total)
}

fn cornell_light() -> (Scene, Vec3) {
    let scene = builtin::cornell();
    let light = scene
        .lights()
        .iter()
        .find(|l| matches!(l, Light::Area(_)))
        .map(light_position)
        .unwrap();
    (scene, light)
}

fn cameras(scene: &Scene) -> [Camera; 2] {
    // Behind the large box, low, in its shadow (checked below with the BVH).
    let inside = Camera::look_at(
        Vec3::new(-0.9, -0.9, -0.9),
        Vec3::new(0.3, -0.4, 0.6),
        Vec3::Y,
        70.0,
    );
    [*scene.camera(), inside]
}

#[test]
fn lit_mask_agrees_with_bvh_shadow_rays() {
    let Some(ctx) = gpu_or_skip("lit_mask_agrees_with_bvh_shadow_rays") else {
        return;
    };
    let (scene, light) = cornell_light();
    let bvh = Bvh::build(&scene);
    let set = ShadowVolumeSet::new(&scene, &[light]).unwrap();
    let occluded = |p: Vec3| {
        let d = light - p;
        let len = d.length();
        bvh.any_hit(&Ray::segment(p, d / len, 1e-4, len - 1e-3))
    };
    for (i, camera) in cameras(&scene).iter().enumerate() {
        if i == 1 {
            assert!(
                occluded(camera.position),
                "the second eye must be in shadow"
            );
        }
        let eye = camera.position;
        let lit: Vec<Option<bool>> = visible(&bvh, camera)
            .into_iter()
            .map(|v| {
                let (p, n) = v?;
                let facing_light = n.dot(light - p);
                // The light's own quad has the light in its plane.
                if facing_light.abs() < 1e-3 * light.distance(p) {
                    return None;
                }
                let same_side = (n.dot(eye - p) > 0.0) == (facing_light > 0.0);
                Some(same_side && !occluded(p))
            })
            .collect();
        let gpu = gpu_mask(&ctx, &scene, camera, &set, light);
        let (agree, total) = agreement(&gpu, &lit);
        let lit_count = lit.iter().filter(|l| **l == Some(true)).count();
        eprintln!("camera {i}: {agree}/{total} pixels agree ({lit_count} lit)");
        assert!(total > (SIZE * SIZE / 2) as usize);
        assert!(lit_count > 200 && lit_count < total - 200);
        assert!(
            agree as f64 >= 0.995 * total as f64,
            "camera {i}: {agree}/{total}"
        );
    }
}

#[test]
fn jittered_light_matches_the_cpu_pivot_count() {
    let Some(ctx) = gpu_or_skip("jittered_light_matches_the_cpu_pivot_count") else {
        return;
    };
    let (scene, light) = cornell_light();
    let bvh = Bvh::build(&scene);
    let set = ShadowVolumeSet::new(&scene, &[light]).unwrap();
    let jitter = Vec3::new(0.15, 0.0, 0.1);
    for (i, camera) in cameras(&scene).iter().enumerate() {
        let eye = camera.position;
        let lj = light + jitter;
        let lit: Vec<Option<bool>> = visible(&bvh, camera)
            .into_iter()
            .map(|v| {
                let (p, n) = v?;
                if n.dot(lj - p).abs() < 1e-3 * lj.distance(p) {
                    return None;
                }
                Some(shadow_count(set.volumes(), jitter, eye, p) == 0)
            })
            .collect();
        let gpu = gpu_mask(&ctx, &scene, camera, &set, lj);
        let (agree, total) = agreement(&gpu, &lit);
        eprintln!("jittered, camera {i}: {agree}/{total} pixels agree");
        assert!(
            agree as f64 >= 0.995 * total as f64,
            "camera {i}: {agree}/{total}"
        );
    }
}

// --- The frame graph's direct light under shadow volumes (sections 4.1, 4.4, 7.2). ---

/// Relative tolerance of GPU against CPU radiance, from `tests/direct.rs`
/// (`RELATIVE_TOLERANCE`: same formula in f32 on both sides, lavapipe within
/// 1.2e-5, 1e-3 leaves room for hardware GPUs' approximate instructions).
const RELATIVE_TOLERANCE: f32 = 1e-3;
/// Absolute tolerance as a fraction of the image's largest CPU radiance, from
/// `tests/direct.rs` (`ABSOLUTE_TOLERANCE`: near-zero grazing values).
const ABSOLUTE_TOLERANCE: f32 = 1e-4;
/// Chebyshev distance (px) to a pixel with another CPU light-visibility mask
/// below which a pixel is a shadow-boundary pixel, from `tests/direct.rs`
/// (`SHADOW_MARGIN`).
const SHADOW_MARGIN: i32 = 2;
/// Number of jittered point lights standing for cornell's area light (section 4.4).
const JITTERED: u32 = 8;

/// The direct light of `lights` through a frame graph, with shadow volumes
/// (`volumes`) or shadow maps; HDR radiance and surface ids.
fn frame_direct(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    volumes: bool,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let hdr = ctx.hdr_format();
    let mut graph = FrameGraph::new(ctx, OUTPUT_FORMAT)
        .unwrap()
        .with_direct(ctx, hdr)
        .unwrap();
    if volumes {
        graph = graph.with_shadow_volumes(ctx, hdr, scene, lights).unwrap();
        // Nothing moved: nothing is rebuilt or re-uploaded (section 4.3).
        assert_eq!(graph.update_shadow_volumes(ctx, scene, lights).unwrap(), 0);
    }
    render_graph(ctx, &graph, scene, camera, lights)
}

const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A frame graph with the direct pass under the shadow volumes of `lights`.
fn volume_graph(ctx: &GpuContext, scene: &Scene, lights: &[Light]) -> FrameGraph {
    let hdr = ctx.hdr_format();
    FrameGraph::new(ctx, OUTPUT_FORMAT)
        .unwrap()
        .with_direct(ctx, hdr)
        .unwrap()
        .with_shadow_volumes(ctx, hdr, scene, lights)
        .unwrap()
}

/// The CPU twin's direct light of `lights` through `camera`, shadowed by BVH shadow rays.
fn cpu_direct(scene: &Scene, lights: &[Light], bvh: &Bvh, camera: &Camera) -> Vec<DirectPixel> {
    direct_pixels_cpu_with_lights(scene, lights, bvh, camera, SIZE, SIZE, GlossyModel::Exact)
        .unwrap()
}

/// One frame of `graph` (shadow maps drawn first where it has no volumes).
fn render_graph(
    ctx: &GpuContext,
    graph: &FrameGraph,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
) -> (Vec<[f32; 4]>, Vec<u32>) {
    support::direct_frame(ctx, graph, scene, camera, lights, SIZE)
}

/// Agreement with the CPU twin (BVH shadow rays): `(agree, compared, agree
/// near shadow boundaries, near shadow boundaries)` over pixels whose 3×3
/// neighbourhood shows one surface on the CPU and the GPU.
fn radiance_agreement(
    gpu: &[[f32; 4]],
    ids: &[u32],
    cpu: &[DirectPixel],
) -> (usize, usize, usize, usize) {
    let max = cpu.iter().flat_map(|p| p.radiance).fold(0.0f32, f32::max);
    let floor = ABSOLUTE_TOLERANCE * max;
    let s = SIZE as i32;
    let around = |x: i32, y: i32, r: i32| {
        (-r..=r).flat_map(move |dy| (-r..=r).map(move |dx| (x + dx, y + dy)))
    };
    let inside = |(u, v): (i32, i32)| (0..s).contains(&u) && (0..s).contains(&v);
    let (mut agree, mut total, mut agree_edge, mut total_edge) = (0, 0, 0, 0);
    for y in 0..s {
        for x in 0..s {
            let i = (y * s + x) as usize;
            let c = &cpu[i];
            if c.surface == NO_SURFACE {
                continue;
            }
            let one_surface = around(x, y, 1).filter(|&p| inside(p)).all(|(u, v)| {
                let j = (v * s + u) as usize;
                cpu[j].surface == c.surface && ids[j] == c.surface
            });
            if !one_surface {
                continue;
            }
            let near_shadow = around(x, y, SHADOW_MARGIN)
                .filter(|&p| inside(p))
                .any(|(u, v)| cpu[(v * s + u) as usize].visible != c.visible);
            let ok = (0..3).all(|k| {
                (gpu[i][k] - c.radiance[k]).abs() <= RELATIVE_TOLERANCE * c.radiance[k] + floor
            });
            if near_shadow {
                total_edge += 1;
                agree_edge += usize::from(ok);
            } else {
                total += 1;
                agree += usize::from(ok);
            }
        }
    }
    (agree, total, agree_edge, total_edge)
}

/// Cornell's area light as `JITTERED` jittered point lights (section 4.4),
/// each with its own volumes, through `FrameGraph` with shadow volumes and
/// with shadow maps, against the CPU twin with BVH shadow rays: ≥ 99.5 % of
/// the pixels away from shadow boundaries within the direct tests'
/// tolerance (the same 99.5 % as the lit-mask tests above: a handful of
/// pixels where rasterisation and the exact ray disagree at a grazing
/// surface), for the scene camera and for an eye inside the large box's
/// shadow; the volumes agree at least as well as the shadow maps, away from
/// the boundaries and with them.
#[test]
fn frame_direct_light_under_shadow_volumes_matches_bvh_shadow_rays() {
    let Some(ctx) = gpu_or_skip("frame_direct_light_under_shadow_volumes_matches_bvh_shadow_rays")
    else {
        return;
    };
    let scene = builtin::cornell();
    let bvh = Bvh::build(&scene);
    let lights = jittered_point_lights(scene.lights(), JITTERED, Vec2::ZERO);
    assert_eq!(lights.len(), JITTERED as usize);
    let [outside, inside] = cameras(&scene);
    for (name, camera) in [
        ("scene camera", outside.with_aspect(1.0)),
        ("eye in shadow", inside.with_aspect(1.0)),
    ] {
        let cpu = cpu_direct(&scene, &lights, &bvh, &camera);
        if name == "eye in shadow" {
            let eye = camera.position;
            let blocked = lights.iter().filter(|l| {
                let d = light_position(l) - eye;
                bvh.any_hit(&Ray::segment(eye, d.normalize(), 1e-4, d.length() - 1e-3))
            });
            assert!(blocked.count() > 0, "the eye must be inside some volume");
        }
        let mut fractions = Vec::new();
        for volumes in [true, false] {
            let (gpu, ids) = frame_direct(&ctx, &scene, &camera, &lights, volumes);
            let (agree, total, agree_edge, total_edge) = radiance_agreement(&gpu, &ids, &cpu);
            let what = if volumes { "volumes" } else { "shadow maps" };
            eprintln!(
                "{name}, {what}: {agree}/{total} pixels agree away from shadow boundaries, \
                 {agree_edge}/{total_edge} near them"
            );
            assert!(total > (SIZE * SIZE / 3) as usize, "{name}: {total} pixels");
            let fraction = agree as f64 / total as f64;
            assert!(fraction >= 0.995, "{name}, {what}: {agree}/{total}");
            fractions.push((fraction, agree + agree_edge));
        }
        // At least as well away from the boundaries. Within 2 px of a shadow
        // boundary both are decided by rasterisation (the volumes' faces
        // under their depth bias, the maps' texels): measured near-boundary
        // agreement, volumes against maps, 1419 against 1396 of 1419 on
        // lavapipe and 1388 against 1397 on an NVIDIA H100, so no order is
        // asserted there.
        assert!(
            fractions[0].0 >= fractions[1].0,
            "{name}: volumes {:?} vs shadow maps {:?}",
            fractions[0],
            fractions[1]
        );
    }
}

/// Section 4.4's stored jittered volumes (`store_jittered`): cornell's area
/// light as 16 jittered lights, the volumes first built for its centre (the
/// pivot) and then stored for every jittered position of two sets, the
/// unrotated one and a rotated one (paired jitter's second sample of four).
/// For each set the frame's direct light matches the CPU twin with BVH
/// shadow rays as in the test above (≥ 99.5 % away from shadow boundaries);
/// the pivot volumes of the same lights miss it on more pixels, along the
/// line where the large box's front face's plane, which passes through the
/// light, meets the floor (a face lit from the centre casts for the jittered
/// lights behind its plane), so the comparison tells the two apart. A light
/// whose position was not stored is refused.
#[test]
fn stored_jittered_volumes_shadow_each_light_as_its_shadow_rays() {
    let Some(ctx) = gpu_or_skip("stored_jittered_volumes_shadow_each_light_as_its_shadow_rays")
    else {
        return;
    };
    let scene = builtin::cornell();
    let bvh = Bvh::build(&scene);
    let k = 16;
    let sets = [
        jittered_point_lights(scene.lights(), k, Vec2::ZERO),
        jittered_point_lights(scene.lights(), k, paired_rotation(1, 4, k)),
    ];
    let pivot = volume_graph(&ctx, &scene, &pivot_point_lights(scene.lights(), k));
    let mut stored = volume_graph(&ctx, &scene, &pivot_point_lights(scene.lights(), k));
    assert!(stored.store_jittered_volumes(&ctx, &scene, &sets).unwrap() > 0);
    // Stored once: storing the same sets again builds nothing.
    assert_eq!(
        stored.store_jittered_volumes(&ctx, &scene, &sets).unwrap(),
        0
    );
    let volumes = stored.shadow_volumes.as_ref().unwrap();
    assert_eq!(volumes.jitter(), VolumeJitter::Stored);
    assert_eq!(volumes.positions().0.len(), 2 * k as usize);
    // Until a frame's lights are prepared, each light has its first set's volumes.
    let first: Vec<usize> = (0..k as usize).collect();
    assert_eq!(volumes.positions().1, &first[..]);
    let camera = scene.camera().with_aspect(1.0);
    for (s, lights) in sets.iter().enumerate() {
        let cpu = cpu_direct(&scene, lights, &bvh, &camera);
        let mut agreeing = Vec::new();
        for (what, graph) in [("stored", &stored), ("pivot", &pivot)] {
            let (gpu, ids) = render_graph(&ctx, graph, &scene, &camera, lights);
            let (agree, total, agree_edge, total_edge) = radiance_agreement(&gpu, &ids, &cpu);
            eprintln!(
                "set {s}, {what}: {agree}/{total} pixels agree away from shadow boundaries, \
                 {agree_edge}/{total_edge} near them"
            );
            assert!(total > (SIZE * SIZE / 3) as usize, "{total} pixels");
            agreeing.push((agree, agree + agree_edge, total));
        }
        let (stored_agree, stored_all, total) = agreeing[0];
        assert!(
            stored_agree as f64 >= 0.995 * total as f64,
            "set {s}, stored: {stored_agree}/{total}"
        );
        // Measured on lavapipe: stored 1474/1474 and 1571/1578 near the
        // boundaries for the two sets, pivot 1452/1474 and 1546/1578 (every
        // pixel away from them agrees under both).
        assert!(
            stored_all > agreeing[1].1 && stored_agree >= agreeing[1].0,
            "set {s}: stored {:?} against pivot {:?}",
            agreeing[0],
            agreeing[1]
        );
    }
    // A third set's positions were never stored.
    let unstored = jittered_point_lights(scene.lights(), k, paired_rotation(2, 4, k));
    let pass = stored.direct.as_ref().unwrap();
    let direct = DirectLights::with_settings(
        &ctx,
        pass,
        &unstored,
        &scene_materials(&scene, GlossyModel::Exact).unwrap(),
        ShadowSettings::default(),
    )
    .unwrap();
    let error = volumes
        .prepare(&ctx, pass, &direct)
        .unwrap_err()
        .to_string();
    assert!(error.contains("no stored volumes"), "{error}");
}

/// Moving the small box rebuilds its volume for every light and nothing
/// else (section 4.3), and the frame then matches the BVH shadow rays of the
/// moved scene (same criterion as above).
#[test]
fn moved_object_rebuilds_its_volumes_and_the_frame_follows() {
    let Some(ctx) = gpu_or_skip("moved_object_rebuilds_its_volumes_and_the_frame_follows") else {
        return;
    };
    let mut scene = builtin::cornell();
    let lights = jittered_point_lights(scene.lights(), 4, Vec2::ZERO);
    let mut graph = volume_graph(&ctx, &scene, &lights);
    let object = scene
        .objects()
        .iter()
        .position(|o| o.name == "small-box")
        .unwrap() as u32;
    let moved = glam::Affine3A::from_translation(Vec3::new(-0.2, 0.0, 0.25))
        * scene.objects()[object as usize].transform;
    scene.set_object_transform(object, moved).unwrap();
    assert_eq!(
        graph.update_shadow_volumes(&ctx, &scene, &lights).unwrap(),
        lights.len(),
        "one rebuilt volume per light for the one moved object"
    );
    let camera = scene.camera().with_aspect(1.0);
    let bvh = Bvh::build(&scene);
    let cpu = cpu_direct(&scene, &lights, &bvh, &camera);
    let (gpu, ids) = render_graph(&ctx, &graph, &scene, &camera, &lights);
    let (agree, total, agree_edge, total_edge) = radiance_agreement(&gpu, &ids, &cpu);
    eprintln!(
        "moved box: {agree}/{total} away from shadow boundaries, {agree_edge}/{total_edge} near them"
    );
    assert!(total > (SIZE * SIZE / 3) as usize);
    assert!(agree as f64 >= 0.995 * total as f64, "{agree}/{total}");
}

/// Shadow volumes drawn inside mirror images (mirrored views, clockwise
/// fronts, clip planes) light `mirrors` as the shadow maps do, which the
/// tests above hold to BVH shadow rays: per pixel, the direct light of the
/// ceiling light's centre through two levels of specular images, with volumes
/// and with maps, away from edges of the maps' image (shadow boundaries,
/// where the two legitimately differ by rasterisation, and surface edges).
#[test]
fn shadow_volumes_inside_mirror_images_light_as_the_shadow_maps_do() {
    let Some(ctx) = gpu_or_skip("shadow_volumes_inside_mirror_images_light_as_the_shadow_maps_do")
    else {
        return;
    };
    let scene = builtin::mirrors();
    let camera = scene.camera().with_aspect(1.0);
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let hdr = ctx.hdr_format();
    let render = |volumes: bool| {
        let mut graph = FrameGraph::new(&ctx, OUTPUT_FORMAT)
            .unwrap()
            .with_direct(&ctx, hdr)
            .unwrap()
            .with_specular(
                &ctx,
                hdr,
                &scene,
                lustre_mpr::passes::specular::SpecularSettings {
                    max_depth: 2,
                    limit_radiance: Vec3::ZERO,
                    clip: None,
                },
            )
            .unwrap();
        if volumes {
            graph = graph
                .with_shadow_volumes(&ctx, hdr, &scene, &lights)
                .unwrap();
        }
        render_graph(&ctx, &graph, &scene, &camera, &lights)
    };
    let (with_volumes, ids) = render(true);
    let (with_maps, map_ids) = render(false);
    assert_eq!(ids, map_ids, "both frames see the same surfaces");
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let max = with_maps.iter().map(luminance).fold(0.0f32, f32::max);
    let s = SIZE as i32;
    let mirror_ids: Vec<u32> = lustre_mpr::passes::specular::specular_faces(&scene)
        .iter()
        .map(|f| f.surface)
        .collect();
    let (mut agree, mut compared, mut in_mirrors) = (0usize, 0usize, 0usize);
    for y in 2..s - 2 {
        for x in 2..s - 2 {
            let i = (y * s + x) as usize;
            let l = luminance(&with_maps[i]);
            // An edge of the maps' image within 2 px: left out.
            let edge = (-2..=2).any(|dy| {
                (-2..=2).any(|dx| {
                    let j = ((y + dy) * s + x + dx) as usize;
                    ids[j] != ids[i] || (luminance(&with_maps[j]) - l).abs() > 0.1 * l + 1e-3 * max
                })
            });
            if edge || ids[i] == NO_SURFACE {
                continue;
            }
            compared += 1;
            in_mirrors += usize::from(mirror_ids.contains(&ids[i]));
            // Tolerance of the direct tests: f32 shading, relative 1e-3 plus 1e-4 of the maximum.
            agree += usize::from((0..3).all(|k| {
                (with_volumes[i][k] - with_maps[i][k]).abs() <= 1e-3 * with_maps[i][k] + 1e-4 * max
            }));
        }
    }
    eprintln!("mirrors: {agree}/{compared} pixels agree, {in_mirrors} of them seen in the mirrors");
    assert!(
        in_mirrors > 300,
        "{in_mirrors} compared pixels lie in the mirror images"
    );
    assert!(
        agree as f64 >= 0.995 * compared as f64,
        "{agree} of {compared} pixels agree"
    );
}
