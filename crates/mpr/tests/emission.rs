//! The emission pass on the GPU against its CPU twin on `cornell`: the
//! light's rectangle shows its radiance exactly, from its emitting side only
//! (the light turned upside down shows nothing).

mod support;

use glam::{Affine3A, Vec3};
use lustre_geometry::{Bvh, Camera, builtin};
use lustre_mpr::passes::depth::{DepthPass, depth_pass_cpu};
use lustre_mpr::passes::emission::{EmissionPass, emission_pass_cpu};
use lustre_mpr::readback::{read_rgba_f32, read_u32};
use lustre_mpr::{RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 64;

#[test]
fn gpu_emission_matches_cpu_on_cornell_with_the_light_facing_and_turned_away() {
    let Some(ctx) = gpu_or_skip("gpu_emission_matches_cpu_on_cornell") else {
        return;
    };
    let front = builtin("cornell").unwrap();
    // The same light turned upside down about its centre: the camera sees its back.
    let mut back = front.clone();
    let light_object = back
        .objects()
        .iter()
        .position(|o| {
            o.meshes.iter().any(|&m| {
                back.materials()[back.meshes()[m as usize].material as usize].is_emissive()
            })
        })
        .unwrap();
    let centre = Vec3::new(0.0, 0.99, 0.01);
    let flip = Affine3A::from_translation(centre)
        * Affine3A::from_rotation_x(std::f32::consts::PI)
        * Affine3A::from_translation(-centre);
    back.set_object_transform(light_object as u32, flip)
        .unwrap();
    for (name, scene) in [("front", front), ("back", back)] {
        let bvh = Bvh::build(&scene);
        let camera = scene.camera().with_aspect(1.0);
        let targets = RenderTargets::new(&ctx, SIZE, SIZE).unwrap();
        let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
        let depth = DepthPass::new(&ctx).unwrap();
        let pass = EmissionPass::new(&ctx, targets.hdr_format(), &scene).unwrap();
        let (views, slot) = lustre_mpr::ViewBuffer::for_camera(&ctx, &camera).unwrap();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        lustre_mpr::frame::clear_hdr(&mut encoder, &targets);
        depth.encode(&mut encoder, &buffers, &targets, &views, slot, true);
        pass.encode(&mut encoder, &buffers, &targets, &views, slot);
        ctx.queue.submit([encoder.finish()]);
        let gpu = read_rgba_f32(&ctx, &targets.hdr.texture).unwrap();
        let ids = read_u32(&ctx, &targets.surface_id.texture).unwrap();
        let cpu = emission_pass_cpu(&scene, &bvh, &camera, SIZE, SIZE);
        let cpu_ids = depth_pass_cpu(&bvh, &camera, SIZE, SIZE).surface;
        let (mut compared, mut lit) = (0, 0);
        for i in 0..gpu.len() {
            // Where both see the same surface, the value is copied from the material: exact.
            if ids[i] != cpu_ids[i] {
                continue;
            }
            compared += 1;
            lit += usize::from(cpu[i][0] > 0.0);
            for c in 0..3 {
                assert_eq!(gpu[i][c], cpu[i][c], "{name}: pixel {i} channel {c}");
            }
        }
        // Pixels that see the light's rectangle at all, from either side.
        let emitter_pixels = (0..SIZE * SIZE)
            .filter(|&i| {
                let ndc = Camera::pixel_ndc(i % SIZE, i / SIZE, SIZE, SIZE, glam::Vec2::splat(0.5));
                bvh.closest_hit(&camera.primary_ray(ndc))
                    .is_some_and(|h| scene.materials()[h.material as usize].is_emissive())
            })
            .count();
        assert!(emitter_pixels >= 10, "{name}: the light is in view");
        eprintln!(
            "{name}: {compared} pixels compared, {emitter_pixels} see the light, {lit} its emitting side"
        );
        match name {
            "front" => assert!(lit >= 10, "the scene camera sees the light"),
            _ => assert_eq!(lit, 0, "the light's back is dark"),
        }
    }
}
