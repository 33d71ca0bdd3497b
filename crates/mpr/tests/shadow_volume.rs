//! Shadow volumes on the GPU (Diefenbach & Badler 1997, sections 4.1, 4.4,
//! 7.3) on `cornell` at 96×96: the lit mask (stencil == SHAD_ZERO after the
//! z-fail count) against BVH shadow rays from the visible point of each
//! pixel, for a camera outside every volume and one inside the large box's
//! shadow, and, with a jittered light, against the CPU z-fail twin with the
//! central silhouette. Pixels within 2 px of a change of the CPU mask are
//! not compared (rasterisation of a boundary is decided at the pixel centre
//! by the GPU's rules, not by the exact test); ≥ 99.5 % of the rest agree.

mod support;

use glam::{Vec2, Vec3};
use lustre_geometry::shadow_volume::{ShadowVolumeSet, light_position, shadow_count};
use lustre_geometry::{Bvh, Camera, Light, Ray, Scene, builtin};
use lustre_mpr::passes::depth::DepthPass;
use lustre_mpr::passes::shadow_volume::{ShadowVolumeBuffers, ShadowVolumePass, VolumeLights};
use lustre_mpr::readback::read_rgba8;
use lustre_mpr::{GpuContext, RenderTargets, SceneBuffers, ViewBuffer};
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
