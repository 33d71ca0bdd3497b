//! Bastos et al. 1999, section 8.1.3: radiance maps reprojected into a reflected view on the GPU agree with the CPU twin (lustre_ibr::reprojection) on the software driver.

mod support;

use lustre_brdf::Fresnel;
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::microfacet::{Distribution, Shadowing};
use lustre_brdf::reflectance_modulation::FlippedRadialReflectance;
use lustre_geometry::material::MicrofacetDistribution;
use lustre_geometry::{Bvh, Ray, Rgb, SurfaceKind, builtin};
use lustre_ibr::ReflectedImage;
use lustre_ibr::glossy::{
    convolve, convolve_by_depth, convolve_in, kernel_radius, modulate, modulate_in, pixel_kernel,
};
use lustre_ibr::resolution::{coarse_mask, upsample};
use lustre_ibr::{
    PinholeView, PointSizing, QuadtreeSettings, Reflector, ReflectorMaps, SamplingSettings,
    SelectionRule, select,
};
use lustre_mpr::passes::glossy_reflection::{Convolution, GlossyReflectionPass, SurfaceMask};
use lustre_mpr::passes::radiance_map::{RadianceMapBuffers, RadianceMapPass, ReflectedTargets};
use lustre_mpr::passes::reflector_blend::ReflectorBlendPass;
use lustre_mpr::readback::{read_depth, read_rgba_f32};
use lustre_mpr::{GpuContext, RenderTargets};

#[test]
fn gpu_reprojection_matches_the_cpu_twin() {
    let Some(ctx) = support::gpu_or_skip("gpu_reprojection_matches_the_cpu_twin") else {
        return;
    };
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let (floor, _) = scene
        .surfaces()
        .iter()
        .enumerate()
        .find(
            |(_, s)| matches!(s.kind, SurfaceKind::Planar(p) if p.normal.y > 0.99 && s.area > 3.0),
        )
        .expect("the floor");
    let reflector = Reflector::from_surface(&scene, floor as u32).unwrap();
    // A distinct radiance per surface, so that any misplaced point shows.
    let trace = |o, d| {
        let hit = bvh.closest_hit(&Ray::segment(o, d, 1e-4, f32::INFINITY))?;
        let h = hit.surface.wrapping_mul(2_654_435_761);
        let c = |s: u32| 0.1 + ((h >> s) & 0xff) as f32 / 255.0;
        Some((Rgb::new(c(0), c(8), c(16)), hit.t))
    };
    let sampling = SamplingSettings {
        planar_resolution: (2, 2),
        arc_step_degrees: 45.0,
        map_resolution: (64, 64),
        ..Default::default()
    };
    let maps = ReflectorMaps::capture(
        &reflector,
        &sampling,
        &QuadtreeSettings::default(),
        &trace,
        &mut |_, _| {},
    )
    .unwrap();
    let (w, h) = (160u32, 120u32);
    let eye = scene.camera().with_aspect(w as f32 / h as f32);
    let view = PinholeView::mirrored(&eye, &reflector.plane, w, h);
    let selected = select(&maps.cameras(), view.eye, 2, SelectionRule::MinimalAngle);
    let cpu = maps.reflected_image(&view, 2, SelectionRule::MinimalAngle, PointSizing::PerNode);

    let pass = RadianceMapPass::new(&ctx).unwrap();
    let buffers = RadianceMapBuffers::upload(&ctx, &maps).unwrap();
    let targets = ReflectedTargets::new(&ctx, w, h).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let drawn = pass
        .encode(
            &ctx,
            &mut encoder,
            &maps,
            &buffers,
            &selected,
            &view,
            &targets,
        )
        .unwrap();
    ctx.queue.submit([encoder.finish()]);
    let color = read_rgba_f32(&ctx, &targets.color).unwrap();
    let depth = read_depth(&ctx, &targets.depth).unwrap();
    assert!(drawn > 1000, "{drawn} boxes");
    // IBR_DUMP=DIR writes both images as raw f32 RGB for inspection.
    if let Ok(dir) = std::env::var("IBR_DUMP") {
        let gpu: Vec<u8> = color
            .iter()
            .flat_map(|c| c[..3].to_vec())
            .flat_map(f32::to_le_bytes)
            .collect();
        let cpu_bytes: Vec<u8> = cpu
            .radiance
            .iter()
            .flat_map(|c| c.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        std::fs::write(format!("{dir}/gpu.bin"), gpu).unwrap();
        std::fs::write(format!("{dir}/cpu.bin"), cpu_bytes).unwrap();
    }

    let (mut covered, mut coverage_differs, mut radiance_differs, mut depth_differs) = (0, 0, 0, 0);
    for (k, (c, z)) in color.iter().zip(&depth).enumerate() {
        let gpu_covered = *z > 0.0;
        let cpu_covered = cpu.depth[k].is_finite();
        covered += usize::from(cpu_covered);
        if gpu_covered != cpu_covered {
            coverage_differs += 1;
        } else if cpu_covered {
            let g = Rgb::new(c[0], c[1], c[2]);
            if (g - cpu.radiance[k]).abs().max_element() > 1e-3 {
                radiance_differs += 1;
            } else {
                // The same point: its reverse-Z depth is near / z.
                let want = lustre_mpr::passes::radiance_map::REFLECTED_NEAR / cpu.depth[k];
                // Boxes overlap their neighbours; where a box edge falls on a
                // pixel centre within rounding, a neighbouring texel of the
                // same surface may win instead, a little nearer or farther.
                if (z - want).abs() > 1e-5 * want {
                    depth_differs += 1;
                    assert!(
                        (z - want).abs() < 0.02 * want,
                        "pixel {k}: depth {z} vs {want}"
                    );
                }
            }
        }
    }
    eprintln!(
        "{covered} pixels covered on the CPU; coverage differs at {coverage_differs}, radiance at {radiance_differs}, only depth at {depth_differs}"
    );
    assert!(covered > 2000, "{covered} pixels covered");
    // Box edges that fall on pixel centres within rounding may go either way.
    assert!(
        coverage_differs * 500 < covered,
        "coverage differs at {coverage_differs}"
    );
    assert!(
        radiance_differs * 500 < covered,
        "radiance differs at {radiance_differs}"
    );
    assert!(
        depth_differs * 50 < covered,
        "another point of the same radiance at {depth_differs}"
    );

    // (M * K) R of the GPU's own M, on the GPU and by the CPU twin.
    let mut m = ReflectedImage::new(w, h);
    for (k, (c, z)) in color.iter().zip(&depth).enumerate() {
        if *z > 0.0 {
            m.radiance[k] = Rgb::new(c[0], c[1], c[2]);
            m.depth[k] = lustre_mpr::passes::radiance_map::REFLECTED_NEAR / z;
        }
    }
    let beckmann = Distribution::new(MicrofacetDistribution::Beckmann, 0.05, "floor").unwrap();
    let kernel = KernelTexture::new(&beckmann, Shadowing::Smith, 33).unwrap();
    let radius = kernel_radius(&m, &view, &reflector.plane, kernel.half_angle);
    assert!(radius > 1.0, "a kernel of {radius} pixels blurs nothing");
    let taps = pixel_kernel(&kernel, radius);
    let table = FlippedRadialReflectance::new(&Fresnel::Dielectric { eta: 1.5 }, 256).unwrap();
    let cpu_term = modulate(&convolve(&m, &taps), &view, &reflector.plane, &table);
    let glossy = GlossyReflectionPass::new(&ctx).unwrap();
    let out = GlossyReflectionPass::output(&ctx, w, h).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    glossy
        .encode(
            &ctx,
            &mut encoder,
            &targets,
            &view,
            &reflector.plane,
            Convolution::SpaceInvariant(&taps),
            &table,
            None,
            &out,
        )
        .unwrap();
    ctx.queue.submit([encoder.finish()]);
    let gpu_term = read_rgba_f32(&ctx, &out).unwrap();
    if let Ok(dir) = std::env::var("IBR_DUMP") {
        let bytes: Vec<u8> = gpu_term
            .iter()
            .flat_map(|c| c[..3].to_vec())
            .flat_map(f32::to_le_bytes)
            .collect();
        std::fs::write(format!("{dir}/glossy.bin"), bytes).unwrap();
    }
    let mut lit = 0;
    for (k, (g, c)) in gpu_term.iter().zip(&cpu_term).enumerate() {
        let g = Rgb::new(g[0], g[1], g[2]);
        assert!(
            (g - *c).abs().max_element() <= 1e-4 * c.max_element().max(1e-3),
            "pixel {k}: GPU {g} vs CPU {c}"
        );
        lit += usize::from(c.max_element() > 0.0);
    }
    // Every covered pixel lit, none beyond: the term stays inside the stencilled region.
    assert_eq!(lit, depth.iter().filter(|z| **z > 0.0).count());

    // Masked by a surface-id texture (the reflector's pixels: the image's
    // lower half, so that uncovered pixels there are cracks or void), with
    // both kernels: the GPU against convolve_in / convolve_by_depth.
    let surface = 7u32;
    let mask: Vec<bool> = (0..w * h).map(|k| k / w >= h / 2).collect();
    let ids: Vec<u32> = mask.iter().map(|&m| if m { surface } else { 0 }).collect();
    let id_texture = ids_texture(&ctx, &ids, w, h);
    // The same on M's grid twice as coarse as the frame's ids
    // (lustre_ibr::resolution): ids of 2w × 2h pixels with a ragged edge,
    // read at each M pixel's centre frame pixel.
    let fine: Vec<bool> = (0..4 * w * h)
        .map(|k| (k / (2 * w)) + (k % (2 * w)) % 3 >= h)
        .collect();
    let fine_ids: Vec<u32> = fine.iter().map(|&m| if m { surface } else { 0 }).collect();
    let fine_texture = ids_texture(&ctx, &fine_ids, 2 * w, 2 * h);
    let coarse = coarse_mask(&fine, 2 * w, 2 * h, 2);
    assert_ne!(coarse, mask, "the ragged edge shows on the coarse grid");
    let scale = view.focal.y * kernel.half_angle.tan();
    let mean_ratio = radius / scale;
    let mut coarse_term = Vec::new();
    for (by_depth, ids, mask, mask_scale) in [
        (false, &id_texture, &mask, 1),
        (true, &id_texture, &mask, 1),
        (false, &fine_texture, &coarse, 2),
    ] {
        let blurred = if by_depth {
            convolve_by_depth(&m, Some(mask), &kernel, &view, &reflector.plane, mean_ratio)
        } else {
            convolve_in(&m, Some(mask), &taps)
        };
        let cpu_term = modulate_in(&blurred, Some(mask), &view, &reflector.plane, &table);
        let convolution = if by_depth {
            Convolution::ByDepth {
                kernel: &kernel,
                mean_ratio,
            }
        } else {
            Convolution::SpaceInvariant(&taps)
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        glossy
            .encode(
                &ctx,
                &mut encoder,
                &targets,
                &view,
                &reflector.plane,
                convolution,
                &table,
                Some(SurfaceMask {
                    ids,
                    surface,
                    scale: mask_scale,
                }),
                &out,
            )
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        let gpu_term = read_rgba_f32(&ctx, &out).unwrap();
        let (mut lit, mut uncovered_lit) = (0, 0);
        for (k, (g, c)) in gpu_term.iter().zip(&cpu_term).enumerate() {
            let g = Rgb::new(g[0], g[1], g[2]);
            assert!(
                (g - *c).abs().max_element() <= 1e-4 * c.max_element().max(1e-3),
                "by depth {by_depth}, mask scale {mask_scale}, pixel {k}: GPU {g} vs CPU {c}"
            );
            lit += usize::from(c.max_element() > 0.0);
            uncovered_lit += usize::from(c.max_element() > 0.0 && !(depth[k] > 0.0));
        }
        eprintln!("by depth {by_depth}: {lit} pixels lit, {uncovered_lit} of them uncovered by M");
        // The mask's uncovered pixels beside M (cracks, and the void's rim within the kernel's reach) are filled.
        assert!(uncovered_lit > 0);
        if mask_scale == 2 {
            coarse_term = gpu_term;
        }
    }

    // The blend of the coarse term into a frame twice as fine, against
    // lustre_ibr::resolution::upsample of the same term: k_s times the
    // bilinear mean over the valid coarse pixels at the reflector's pixels,
    // nothing elsewhere.
    let frame = RenderTargets::new(&ctx, 2 * w, 2 * h).unwrap();
    write_ids(&ctx, &frame.surface_id.texture, &fine_ids, 2 * w, 2 * h);
    let ks = Rgb::new(0.5, 0.25, 1.0);
    let blend = ReflectorBlendPass::new(&ctx, frame.hdr_format()).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    blend
        .encode(&ctx, &mut encoder, &frame, &out, surface, ks, 2)
        .unwrap();
    ctx.queue.submit([encoder.finish()]);
    let blended = read_rgba_f32(&ctx, &frame.hdr.texture).unwrap();
    let term: Vec<Rgb> = coarse_term
        .iter()
        .map(|t| Rgb::new(t[0], t[1], t[2]))
        .collect();
    let valid: Vec<bool> = coarse_term.iter().map(|t| t[3] > 0.5).collect();
    let mut added = 0;
    for y in 0..2 * h {
        for x in 0..2 * w {
            let k = (y * 2 * w + x) as usize;
            let expected = if fine[k] {
                upsample(&term, &valid, w, 2, x, y) * ks
            } else {
                Rgb::ZERO
            };
            let g = Rgb::new(blended[k][0], blended[k][1], blended[k][2]);
            assert!(
                (g - expected).abs().max_element() <= 2e-3 * expected.max_element().max(1e-2),
                "blend at ({x}, {y}): GPU {g} vs CPU {expected}"
            );
            added += usize::from(expected.max_element() > 0.0);
        }
    }
    assert!(added > 0, "the blend added nothing");
}

/// A surface-id texture of `width × height` holding `ids` (row-major).
fn ids_texture(ctx: &GpuContext, ids: &[u32], width: u32, height: u32) -> wgpu::Texture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test-ids"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: lustre_mpr::target::SURFACE_ID_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    write_ids(ctx, &texture, ids, width, height);
    texture
}

/// Writes `ids` (row-major, `width × height`) into `texture`.
fn write_ids(ctx: &GpuContext, texture: &wgpu::Texture, ids: &[u32], width: u32, height: u32) {
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(ids),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * width),
            rows_per_image: Some(height),
        },
        texture.size(),
    );
}
