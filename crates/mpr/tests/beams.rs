//! The beam pass (Duvenhage et al. 2010, sections 3.1, 4.2, 4.3) against its
//! CPU twin, lustre-beams' `Beam::arrival` through the same BRDFs
//! (`beam_pixels_cpu`), on lavapipe: specular reflected and shadow beams
//! (`cardioid`), glossy reflected beams off a rough conductor under a cosine
//! point light (`glosbox`'s gold box, every split point of figure 12), and
//! refracted beams under a wavy water surface (`pool`, seen from under the
//! water); the hierarchy's traversal against the paper's linear one.

mod support;

use glam::Vec3;
use lustre_beams::{BeamSet, BuildOptions, GlossyVolume, SplitPoint};
use lustre_geometry::{Bvh, Camera, Scene, builtin};
use lustre_mpr::FrameGraph;
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::beams::{Traversal, beam_pixels_cpu};
use lustre_mpr::passes::direct::primary_hits;
use support::{gpu_or_skip, render_frame};

const SIZE: u32 = 64;

/// The beam pass alone (no other light): the HDR radiance of a `SIZE`² frame and its surface ids.
fn gpu_frame(
    ctx: &lustre_mpr::GpuContext,
    scene: &Scene,
    camera: &Camera,
    beams: &BeamSet,
    traversal: Traversal,
) -> (Vec<[f32; 3]>, Vec<u32>) {
    let targets = lustre_mpr::RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = lustre_mpr::SceneBuffers::upload(ctx, scene).unwrap();
    let maps = lustre_mpr::diffuse_map::DiffuseMaps::upload(ctx, scene).unwrap();
    let graph = FrameGraph::new(ctx, wgpu::TextureFormat::Rgba8Unorm)
        .unwrap()
        .with_beams(
            ctx,
            targets.hdr_format(),
            scene,
            GlossyModel::Exact,
            &maps,
            beams,
            traversal,
        )
        .unwrap();
    let (hdr, ids) = render_frame(ctx, &graph, &buffers, camera, &targets, None);
    (hdr.into_iter().map(|p| [p[0], p[1], p[2]]).collect(), ids)
}

/// The surface the ray through each pixel centre hits first (`NO_SURFACE` on a miss), row 0 at the top.
fn cpu_surfaces(bvh: &Bvh, camera: &Camera) -> Vec<u32> {
    primary_hits(bvh, camera, SIZE, SIZE)
        .1
        .iter()
        .map(|h| h.map_or(lustre_mpr::NO_SURFACE, |h| h.surface))
        .collect()
}

/// Pixels of `a` and `b` within `rel` of the frame's largest value plus `rel` of their own.
fn agreeing(a: &[[f32; 3]], b: &[[f32; 3]], rel: f32) -> (usize, f32) {
    let scale = b
        .iter()
        .flatten()
        .fold(0.0f32, |m, &x| m.max(x.abs()))
        .max(1e-12);
    let mut worst = 0.0f32;
    let ok = a
        .iter()
        .zip(b)
        .filter(|(p, q)| {
            let err = (0..3)
                .map(|c| (p[c] - q[c]).abs() / (scale + q[c].abs()))
                .fold(0.0f32, f32::max);
            worst = worst.max(err);
            err <= rel
        })
        .count();
    (ok, worst)
}

/// GPU against the CPU twin over the pixels where the rasteriser and the ray
/// cast see the same surface (at the room's edges they can differ): at least
/// `share` of them within 1e-3 (f32 transcendental functions of lavapipe
/// against Rust's, and the rasterised position against the ray-cast hit, which
/// can put a pixel on the other side of a beam's edge: those pixels are the
/// ones allowed to differ), at least `lit` pixels lit by beams, and the sums
/// within 1 %.
fn check(name: &str, scene: &Scene, camera: &Camera, beams: &BeamSet, share: f64, lit: usize) {
    let Some(ctx) = gpu_or_skip(name) else {
        return;
    };
    let bvh = Bvh::build(scene);
    let surfaces = cpu_surfaces(&bvh, camera);
    for traversal in [Traversal::Linear, Traversal::Hierarchy] {
        let cpu = beam_pixels_cpu(
            scene,
            &bvh,
            camera,
            SIZE,
            SIZE,
            GlossyModel::Exact,
            beams,
            traversal,
        )
        .unwrap();
        let (gpu, ids) = gpu_frame(&ctx, scene, camera, beams, traversal);
        let same: Vec<bool> = ids.iter().zip(&surfaces).map(|(a, b)| a == b).collect();
        assert!(
            same.iter().filter(|&&s| s).count() as f64 >= 0.97 * same.len() as f64,
            "{name}: the GPU sees other surfaces than the ray cast"
        );
        let keep = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
            img.iter()
                .zip(&same)
                .filter(|(_, s)| **s)
                .map(|(p, _)| *p)
                .collect()
        };
        let (gpu, cpu) = (keep(&gpu), keep(&cpu));
        let lit_pixels = cpu.iter().filter(|p| p.iter().any(|&x| x != 0.0)).count();
        let (ok, worst) = agreeing(&gpu, &cpu, 1e-3);
        if std::env::var_os("BEAM_DEBUG").is_some() {
            for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
                if (g[1] - c[1]).abs() > 1e-3 * (c[1].abs() + 0.01) {
                    eprintln!(
                        "  pixel ({}, {}): gpu {:?} cpu {:?}",
                        i as u32 % SIZE,
                        i as u32 / SIZE,
                        g,
                        c
                    );
                }
            }
        }
        let sum = |img: &[[f32; 3]]| img.iter().flatten().map(|&x| f64::from(x)).sum::<f64>();
        let (sg, sc) = (sum(&gpu), sum(&cpu));
        eprintln!(
            "{name} {traversal:?}: {ok}/{} pixels agree (worst {worst:.2e}), {lit_pixels} lit, sums GPU {sg:.4e} CPU {sc:.4e}",
            cpu.len()
        );
        assert!(
            lit_pixels >= lit,
            "{name}: {lit_pixels} pixels lit by beams"
        );
        assert!(
            ok as f64 >= share * cpu.len() as f64,
            "{name} {traversal:?}: only {ok} of {} pixels agree",
            cpu.len()
        );
        assert!(
            (sg - sc).abs() <= 0.01 * sc.abs().max(1e-9),
            "{name} {traversal:?}: sums {sg} against {sc}"
        );
    }
}

#[test]
fn specular_and_shadow_beams_of_the_cardioid_ring_match_the_cpu() {
    let scene = builtin::cardioid();
    let beams = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    assert!(beams.stats().shadow > 0 && beams.stats().scattered > 0);
    let camera = scene.camera().with_aspect(1.0);
    check("cardioid", &scene, &camera, &beams, 0.99, 400);
}

#[test]
fn glossy_beams_of_a_rough_conductor_match_the_cpu_for_every_split_point_and_volume() {
    // glosbox's gold box (Beckmann α = 0.1) lit by the area light's cosine
    // point light: glossy reflected beams on the walls and the floor.
    let scene = builtin::glosbox().with_area_lights_as_points().unwrap();
    let camera = scene.camera().with_aspect(1.0);
    for (split_point, glossy_volume) in [
        (SplitPoint::Rescattered, GlossyVolume::Facets),
        (SplitPoint::Paper, GlossyVolume::Facets),
        (SplitPoint::Domain, GlossyVolume::Facets),
        (SplitPoint::Rescattered, GlossyVolume::Integrated),
    ] {
        let options = BuildOptions {
            split_point,
            glossy_volume,
            shadow_beams: false,
            ..BuildOptions::default()
        };
        let beams = BeamSet::from_scene(&scene, &options).unwrap();
        assert!(beams.beams().iter().all(|b| b.distribution.is_some()));
        check(
            &format!("glosbox {split_point:?} {glossy_volume:?}"),
            &scene,
            &camera,
            &beams,
            0.99,
            1000,
        );
    }
}

/// A camera under `pool`'s water (mean level 0.5 m), looking down at the floor.
fn under_the_pool_water() -> Camera {
    Camera::look_at(
        Vec3::new(-0.6, 0.4, 0.7),
        Vec3::new(0.1, 0.0, -0.1),
        Vec3::Y,
        60.0,
    )
}

#[test]
fn refracted_beams_under_the_pool_water_match_the_cpu() {
    let scene = builtin::pool();
    let beams = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let camera = under_the_pool_water();
    check("pool", &scene, &camera, &beams, 0.99, 1500);
}

#[test]
fn caustics_on_mapped_receivers_match_the_cpu() {
    // The pool with the 4 × 4 asymmetric map on every material: the beams'
    // light on the floor scaled by the map at each pixel's uv on both sides
    // (the CPU adds Material::diffuse_shift to f_r).
    let plain = builtin::pool();
    let scene = support::with_asymmetric_maps(plain.clone(), "pool-mapped");
    let beams = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let camera = under_the_pool_water();
    // The map changes the beams' light, so the comparison below can fail.
    let bvh = Bvh::build(&scene);
    let sum = |s: &Scene| -> f64 {
        beam_pixels_cpu(
            s,
            &bvh,
            &camera,
            SIZE,
            SIZE,
            GlossyModel::Exact,
            &beams,
            Traversal::Hierarchy,
        )
        .unwrap()
        .iter()
        .flatten()
        .map(|&x| f64::from(x))
        .sum()
    };
    let (mapped, unmapped) = (sum(&scene), sum(&plain));
    eprintln!(
        "pool beams' light, mapped over unmapped: {:.3}",
        mapped / unmapped
    );
    assert!(
        (mapped / unmapped - 1.0).abs() > 0.1,
        "{mapped} against {unmapped}"
    );
    check("pool-mapped", &scene, &camera, &beams, 0.99, 1500);
}

#[test]
fn the_hierarchy_draws_what_the_linear_traversal_draws() {
    let Some(ctx) = gpu_or_skip("hierarchy") else {
        return;
    };
    let scene = builtin::cardioid();
    let beams = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let camera = scene.camera().with_aspect(1.0);
    let (linear, _) = gpu_frame(&ctx, &scene, &camera, &beams, Traversal::Linear);
    let (tree, _) = gpu_frame(&ctx, &scene, &camera, &beams, Traversal::Hierarchy);
    // The same beams summed in another order: equal to float rounding.
    let (ok, worst) = agreeing(&tree, &linear, 1e-5);
    eprintln!(
        "hierarchy against linear: {ok}/{} (worst {worst:.2e})",
        linear.len()
    );
    assert_eq!(ok, linear.len(), "worst {worst}");
}
