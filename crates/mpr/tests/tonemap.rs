//! The tone-map pass on the GPU against its CPU twin on a synthetic HDR image: within 1 LSB.

mod support;

use lustre_mpr::GpuContext;
use lustre_mpr::passes::tonemap::{ToneOperator, Tonemap, TonemapPass};
use lustre_mpr::readback::read_rgba8;
use support::gpu_or_skip;

const SIZE: u32 = 64;

/// A 64×64 HDR image: radiance from 1e-4 to 1e4 (log-spaced along x, shifted
/// per channel and row), plus zero, negative, +∞ and NaN texels in row 0.
fn synthetic_hdr() -> Vec<[f32; 4]> {
    let mut image = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let t = (x as f32 + y as f32 / SIZE as f32) / SIZE as f32;
            let l = |shift: f32| 10f32.powf(-4.0 + 8.0 * ((t + shift) % 1.0));
            image.push([l(0.0), l(0.3), l(0.7), 1.0]);
        }
    }
    image[0] = [0.0, -1.0, f32::INFINITY, 1.0];
    image[1] = [f32::NAN, 1e-30, f32::MAX, 1.0];
    image
}

/// Runs the GPU pass on `hdr` into a fresh `format` texture and reads it back.
fn gpu_tonemap(
    ctx: &GpuContext,
    hdr: &[[f32; 4]],
    settings: &Tonemap,
    format: wgpu::TextureFormat,
) -> Vec<[u8; 4]> {
    let size = wgpu::Extent3d {
        width: SIZE,
        height: SIZE,
        depth_or_array_layers: 1,
    };
    let texture = |format, usage| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let input = texture(
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let bytes: Vec<u8> = hdr.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    ctx.queue.write_texture(
        input.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(SIZE * 16),
            rows_per_image: Some(SIZE),
        },
        size,
    );
    let output = texture(
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let pass = TonemapPass::new(ctx, format).unwrap();
    pass.prepare(&ctx.queue, settings).unwrap();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    pass.encode(
        &ctx.device,
        &mut encoder,
        &input.create_view(&Default::default()),
        &output.create_view(&Default::default()),
    );
    ctx.queue.submit([encoder.finish()]);
    read_rgba8(ctx, &output).unwrap()
}

#[test]
fn gpu_tonemap_matches_cpu_within_one_lsb() {
    let Some(ctx) = gpu_or_skip("gpu_tonemap_matches_cpu_within_one_lsb") else {
        return;
    };
    let hdr = synthetic_hdr();
    for operator in [ToneOperator::Clamp, ToneOperator::Reinhard] {
        for exposure in [0.37, 1.0, 8.0] {
            // Shader-side sRGB (Rgba8Unorm) and hardware sRGB (Rgba8UnormSrgb).
            for format in [
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureFormat::Rgba8UnormSrgb,
            ] {
                let settings = Tonemap { exposure, operator };
                let gpu = gpu_tonemap(&ctx, &hdr, &settings, format);
                let cpu = settings.map_image(&hdr);
                let mut worst = 0;
                let mut off_by_one = 0;
                for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
                    for ch in 0..4 {
                        let d = g[ch].abs_diff(c[ch]);
                        assert!(
                            d <= 1,
                            "{operator:?} k={exposure} {format:?} pixel {i} channel {ch}: GPU {} CPU {} (L = {})",
                            g[ch],
                            c[ch],
                            hdr[i][ch]
                        );
                        worst = worst.max(d);
                        off_by_one += usize::from(d == 1);
                    }
                }
                eprintln!(
                    "{operator:?} k={exposure} {format:?}: max |GPU-CPU| = {worst} LSB, {off_by_one} of {} channels differ by 1",
                    gpu.len() * 4
                );
            }
        }
    }
}

#[test]
fn tonemap_rejects_bad_settings_and_formats() {
    let Some(ctx) = gpu_or_skip("tonemap_rejects_bad_settings_and_formats") else {
        return;
    };
    assert!(TonemapPass::new(&ctx, wgpu::TextureFormat::R32Uint).is_err());
    assert!(TonemapPass::new(&ctx, wgpu::TextureFormat::Depth32Float).is_err());
    let pass = TonemapPass::new(&ctx, wgpu::TextureFormat::Rgba8Unorm).unwrap();
    let bad = Tonemap {
        exposure: f32::NAN,
        ..Tonemap::default()
    };
    assert!(pass.prepare(&ctx.queue, &bad).is_err());
}
