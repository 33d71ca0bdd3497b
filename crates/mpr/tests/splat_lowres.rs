//! Splats at a lower resolution (`passes::splat_lowres`): the GPU guide and
//! joint bilateral upsampling against their CPU twins, a uniformly lit
//! surface upsampled to itself with nothing across a surface-id edge, the
//! low-resolution splat image against the full-resolution one, and the full
//! resolution unchanged.

mod support;

use lustre_geometry::{Bvh, Scene, builtin};
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::depth::DepthPass;
use lustre_mpr::passes::splat::{KernelFiltering, Restriction, SplatBuffers, SplatPass};
use lustre_mpr::passes::splat_lowres::{
    AUTO_MIN_RADIUS, SplatResolution, guides_cpu, upsample_cpu,
};
use lustre_mpr::readback::{read_depth, read_rgba_f32, read_texture_bytes, read_u32};
use lustre_mpr::{GpuContext, NO_SURFACE, RenderTargets, SceneBuffers};
use lustre_photon::{
    BounceSelection, Edges, EstimatorOptions, Kernel, NoProgress, SplatEstimator, Support,
    TraceOptions, trace_photons,
};
use support::gpu_or_skip;

/// Not a multiple of 4 either way: the partial last low-resolution row and column are exercised.
const WIDTH: u32 = 90;
const HEIGHT: u32 = 70;

/// What one splat frame left on the GPU, read back.
struct Frame {
    /// The HDR target after the splat pass (rgb).
    hdr: Vec<[f32; 3]>,
    /// Full-resolution surface ids and depth.
    ids: Vec<u32>,
    depth: Vec<f32>,
    /// Low-resolution radiance, ids and depth (empty at full resolution).
    low_radiance: Vec<[f32; 3]>,
    low_ids: Vec<u32>,
    low_depth: Vec<f32>,
}

fn estimator(scene: &Scene) -> SplatEstimator {
    let bvh = Bvh::build(scene);
    let options = TraceOptions {
        photons: 20_000,
        seed: 7,
        ..TraceOptions::default()
    };
    let map = trace_photons(scene, &bvh, &options, &NoProgress).unwrap();
    SplatEstimator::build(
        scene,
        &map,
        EstimatorOptions {
            kernel: Kernel::Silverman,
            support: Support::Scaled(16.0),
            selection: BounceSelection::All,
            edges: Edges::Normalised,
        },
    )
    .unwrap()
}

/// Depth pre-pass then the splats of `splats` at `resolution` ([`SplatPass::encode_at`]), or through [`SplatPass::encode`] with `old`.
fn render(
    ctx: &GpuContext,
    scene: &Scene,
    splats: &SplatBuffers,
    resolution: SplatResolution,
    old: bool,
) -> Frame {
    let camera = scene.camera().with_aspect(WIDTH as f32 / HEIGHT as f32);
    let targets = RenderTargets::new(ctx, WIDTH, HEIGHT).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let depth = DepthPass::new(ctx).unwrap();
    let pass = SplatPass::new(ctx, targets.hdr_format(), Kernel::Silverman).unwrap();
    let (views, slot) = lustre_mpr::ViewBuffer::for_camera(ctx, &camera).unwrap();
    pass.prepare(&ctx.queue, KernelFiltering::PixelCentre);
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    lustre_mpr::frame::clear_hdr(&mut encoder, &targets);
    depth.encode(&mut encoder, &buffers, &targets, &views, slot, true);
    let low = if old {
        pass.encode(
            &ctx.device,
            &mut encoder,
            &buffers,
            splats,
            &targets,
            Restriction::SurfaceId,
            &views,
            slot,
        )
        .unwrap();
        None
    } else {
        pass.encode_at(
            ctx,
            &mut encoder,
            &buffers,
            splats,
            &targets,
            Restriction::SurfaceId,
            resolution,
            &views,
            slot,
        )
        .unwrap()
    };
    ctx.queue.submit([encoder.finish()]);
    let rgb = |v: Vec<[f32; 4]>| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let (low_radiance, low_ids, low_depth) = match &low {
        Some(low) => (
            rgb(read_rgba_f32(ctx, &low.radiance.texture).unwrap()),
            read_u32(ctx, &low.ids.texture).unwrap(),
            read_texture_bytes(ctx, &low.depth.texture, wgpu::TextureAspect::All)
                .unwrap()
                .chunks_exact(4)
                .map(|t| f32::from_le_bytes([t[0], t[1], t[2], t[3]]))
                .collect(),
        ),
        None => Default::default(),
    };
    Frame {
        hdr: rgb(read_rgba_f32(ctx, &targets.hdr.texture).unwrap()),
        ids: read_u32(ctx, &targets.surface_id.texture).unwrap(),
        depth: read_depth(ctx, &targets.depth.texture).unwrap(),
        low_radiance,
        low_ids,
        low_depth,
    }
}

#[test]
fn gpu_guides_and_upsampling_match_the_cpu() {
    let Some(ctx) = gpu_or_skip("gpu_guides_and_upsampling_match_the_cpu") else {
        return;
    };
    let scene = builtin::glosbox();
    let estimator = estimator(&scene);
    let splats = SplatBuffers::new(&ctx, &scene, &estimator, GlossyModel::Exact).unwrap();
    for resolution in [SplatResolution::Half, SplatResolution::Quarter] {
        let frame = render(&ctx, &scene, &splats, resolution, false);
        let (lw, lh) = resolution.low_size(WIDTH, HEIGHT);
        assert_eq!(frame.low_ids.len(), (lw * lh) as usize);
        let (ids, depth) = guides_cpu(&frame.ids, &frame.depth, WIDTH, HEIGHT, resolution);
        assert_eq!(ids, frame.low_ids, "{resolution:?}: surface-id guide");
        assert_eq!(depth, frame.low_depth, "{resolution:?}: depth guide");
        assert!(
            ids.contains(&NO_SURFACE),
            "the partial last row and column hold no surface"
        );
        let cpu = upsample_cpu(
            &frame.low_radiance,
            &ids,
            &depth,
            &frame.ids,
            &frame.depth,
            WIDTH,
            HEIGHT,
            resolution,
        );
        let mut lit = 0;
        for (i, (gpu, cpu)) in frame.hdr.iter().zip(&cpu).enumerate() {
            let cpu = cpu.unwrap_or([0.0; 3]);
            for c in 0..3 {
                let tolerance = 1e-5 * cpu[c].abs().max(1e-3);
                assert!(
                    (gpu[c] - cpu[c]).abs() <= tolerance,
                    "{resolution:?} pixel {i} channel {c}: GPU {} CPU {}",
                    gpu[c],
                    cpu[c]
                );
            }
            lit += usize::from(cpu.iter().any(|&v| v > 0.0));
        }
        assert!(
            lit > (WIDTH * HEIGHT / 2) as usize,
            "{resolution:?}: {lit} lit pixels"
        );
    }
}

/// A low-resolution image of two uniformly lit surfaces meeting along a
/// slanted edge upsamples to the same two radiances, each exactly on its own
/// surface's pixels (relative 1e-6), at both factors.
#[test]
fn uniform_surfaces_upsample_to_themselves_without_bleeding() {
    let (width, height) = (37u32, 29u32);
    let a = [2.0f32, 1.0, 0.5];
    let b = [0.0f32, 3.0, 0.25];
    // Surface 0 left of the slanted edge, 1 right of it, a corner that sees nothing.
    let id_at = |x: u32, y: u32| {
        if x + y < 4 {
            NO_SURFACE
        } else if 3 * x < 2 * y + 30 {
            0
        } else {
            1
        }
    };
    let ids: Vec<u32> = (0..height)
        .flat_map(|y| (0..width).map(move |x| id_at(x, y)))
        .collect();
    // A tilted plane's reverse-Z depth, with a step at the edge.
    let depth: Vec<f32> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| 0.2 + 0.001 * x as f32 + 0.002 * y as f32 + 0.05 * id_at(x, y).min(1) as f32)
        .collect();
    for resolution in [SplatResolution::Half, SplatResolution::Quarter] {
        let (low_ids, low_depth) = guides_cpu(&ids, &depth, width, height, resolution);
        let radiance: Vec<[f32; 3]> = low_ids
            .iter()
            .map(|&id| match id {
                0 => a,
                1 => b,
                _ => [1e3; 3],
            })
            .collect();
        let up = upsample_cpu(
            &radiance, &low_ids, &low_depth, &ids, &depth, width, height, resolution,
        );
        for (i, (&id, value)) in ids.iter().zip(&up).enumerate() {
            match (id, value) {
                (NO_SURFACE, None) => {}
                (NO_SURFACE, Some(v)) => panic!("{resolution:?} pixel {i}: {v:?} on no surface"),
                (_, None) => panic!("{resolution:?} pixel {i} of surface {id}: no sample"),
                (_, Some(v)) => {
                    let want = if id == 0 { a } else { b };
                    for c in 0..3 {
                        assert!(
                            (v[c] - want[c]).abs() <= 1e-6 * want[c].max(1.0),
                            "{resolution:?} pixel {i} of surface {id}: {v:?} vs {want:?}"
                        );
                    }
                }
            }
        }
    }
}

/// The splats of one surface alone, at low resolution: every pixel of
/// another surface stays exactly zero, and the surface's own pixels are lit.
#[test]
fn no_splat_light_crosses_a_surface_id_edge() {
    let Some(ctx) = gpu_or_skip("no_splat_light_crosses_a_surface_id_edge") else {
        return;
    };
    let scene = builtin::glosbox();
    let estimator = estimator(&scene);
    let all = estimator.splats();
    // The surface with the most splats.
    let mut counts = vec![0usize; scene.surfaces().len()];
    for s in &all {
        counts[s.surface as usize] += 1;
    }
    let surface = (0..counts.len()).max_by_key(|&s| counts[s]).unwrap() as u32;
    let one: Vec<_> = all.into_iter().filter(|s| s.surface == surface).collect();
    let splats = SplatBuffers::from_splats(&ctx, &scene, &one, GlossyModel::Exact).unwrap();
    for resolution in [SplatResolution::Half, SplatResolution::Quarter] {
        let frame = render(&ctx, &scene, &splats, resolution, false);
        let mut own = 0;
        for (i, (&id, v)) in frame.ids.iter().zip(&frame.hdr).enumerate() {
            if id == surface {
                own += usize::from(v.iter().any(|&c| c > 0.0));
            } else {
                assert_eq!(
                    *v, [0.0; 3],
                    "{resolution:?} pixel {i} of surface {id} got surface {surface}'s light"
                );
            }
        }
        assert!(
            own > 100,
            "{resolution:?}: {own} lit pixels of surface {surface}"
        );
    }
}

/// The low-resolution splat image against the full-resolution one on
/// glosbox (C = 16 at 20,000 photons, 90×70): every low-resolution sample
/// equals the full-resolution pixel its guide reads (relative 1e-4), and
/// the upsampled image's relMSE (epsilon 0.01) over every pixel stays below
/// 0.002 at half and 0.004 at a quarter (measured 0.0013 and 0.0027 on
/// lavapipe: mostly surfaces thinner than `f` pixels that no sample sees, left unlit).
#[test]
fn low_resolution_splats_stay_close_to_full_resolution() {
    let Some(ctx) = gpu_or_skip("low_resolution_splats_stay_close_to_full_resolution") else {
        return;
    };
    let scene = builtin::glosbox();
    let estimator = estimator(&scene);
    let splats = SplatBuffers::new(&ctx, &scene, &estimator, GlossyModel::Exact).unwrap();
    let full = render(&ctx, &scene, &splats, SplatResolution::Full, false);
    for (resolution, bound) in [
        (SplatResolution::Half, 0.002),
        (SplatResolution::Quarter, 0.004),
    ] {
        let low = render(&ctx, &scene, &splats, resolution, false);
        // Each low-resolution sample is the full-resolution pixel its guide reads.
        let f = resolution.factor();
        let (lw, lh) = resolution.low_size(WIDTH, HEIGHT);
        let mut checked = 0;
        for y in 0..lh {
            for x in 0..lw {
                let (fx, fy) = (f * x + f / 2, f * y + f / 2);
                if fx >= WIDTH || fy >= HEIGHT {
                    continue;
                }
                let (s, p) = ((y * lw + x) as usize, (fy * WIDTH + fx) as usize);
                assert_eq!(low.low_ids[s], full.ids[p]);
                for c in 0..3 {
                    let (l, r) = (low.low_radiance[s][c], full.hdr[p][c]);
                    assert!(
                        (l - r).abs() <= 1e-4 * r.abs().max(1e-2),
                        "{resolution:?} sample ({x}, {y}) channel {c}: {l} vs full {r}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > (lw * lh / 2) as usize);
        let mut sum = 0.0f64;
        for (t, r) in low.hdr.iter().zip(&full.hdr) {
            for c in 0..3 {
                let (t, r) = (f64::from(t[c]), f64::from(r[c]));
                sum += (t - r).powi(2) / (r * r + 0.01);
            }
        }
        let rel = sum / (3 * low.hdr.len()) as f64;
        eprintln!("{resolution:?}: relMSE against full resolution {rel:.6}");
        assert!(
            rel < bound,
            "{resolution:?}: relMSE {rel} against full resolution"
        );
    }
}

/// [`SplatResolution::Full`] is the splat pass as it was: bit for bit the
/// image of [`SplatPass::encode`], with no low-resolution targets.
#[test]
fn full_resolution_is_the_old_pass_bit_for_bit() {
    let Some(ctx) = gpu_or_skip("full_resolution_is_the_old_pass_bit_for_bit") else {
        return;
    };
    let scene = builtin::glosbox();
    let estimator = estimator(&scene);
    let splats = SplatBuffers::new(&ctx, &scene, &estimator, GlossyModel::Exact).unwrap();
    let new = render(&ctx, &scene, &splats, SplatResolution::Full, false);
    let old = render(&ctx, &scene, &splats, SplatResolution::Full, true);
    assert!(new.low_ids.is_empty());
    let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&new.hdr), bits(&old.hdr));
    assert!(new.hdr.iter().any(|p| p[0] > 0.0));
}

/// `auto` picks the coarsest factor whose splats still span
/// [`lustre_mpr::passes::splat_lowres::AUTO_MIN_RADIUS`] low-resolution pixels.
#[test]
fn auto_follows_the_projected_kernel_size() {
    let scene = builtin::glosbox();
    let camera = scene.camera();
    // A splat 2 m in front of the camera: radius h·focal/2 pixels.
    let at = camera.position + 2.0 * (camera.target - camera.position).normalize();
    let focal = 0.5 * 480.0 / (0.5 * camera.fov_y_degrees.to_radians()).tan();
    let with_radius = |pixels: f32| vec![[at.x, at.y, at.z, pixels * 2.0 / focal]; 10];
    let auto = |pixels: f32| SplatResolution::auto(&with_radius(pixels), camera, 480);
    let r = AUTO_MIN_RADIUS;
    assert_eq!(auto(8.2 * r), SplatResolution::Eighth);
    assert_eq!(auto(7.8 * r), SplatResolution::Quarter);
    assert_eq!(auto(4.2 * r), SplatResolution::Quarter);
    assert_eq!(auto(3.8 * r), SplatResolution::Half);
    assert_eq!(auto(2.2 * r), SplatResolution::Half);
    assert_eq!(auto(1.8 * r), SplatResolution::Full);
    assert_eq!(
        SplatResolution::auto(&[], camera, 480),
        SplatResolution::Full
    );
}
