//! The headless device, render targets and readback on whatever adapter exists (lavapipe in CI).

mod support;

use lustre_mpr::readback::{read_depth, read_rgba_f32, read_u32};
use lustre_mpr::target::{NO_SURFACE, REVERSE_Z_CLEAR};
use lustre_mpr::{GpuContext, MprError, RenderTargets};
use support::gpu_or_skip;

#[test]
fn context_reports_adapter_and_hdr_format() {
    let Some(ctx) = gpu_or_skip("context_reports_adapter_and_hdr_format") else {
        return;
    };
    assert!(!ctx.adapter().name.is_empty());
    assert!(ctx.adapter().to_string().contains(&ctx.adapter().name));
    assert_eq!(ctx.needs_16bit_fallback(), !ctx.float32_blendable());
    assert!(ctx.is_blendable(ctx.hdr_format()), "{:?}", ctx.hdr_format());
    assert!(ctx.is_blendable(wgpu::TextureFormat::Rgba16Float));
    assert_eq!(
        ctx.is_blendable(wgpu::TextureFormat::Rgba32Float),
        ctx.float32_blendable()
    );
}

#[test]
fn invalid_target_sizes_and_formats_are_errors() {
    let Some(ctx) = gpu_or_skip("invalid_target_sizes_and_formats_are_errors") else {
        return;
    };
    assert!(matches!(
        RenderTargets::new(&ctx, 0, 16),
        Err(MprError::InvalidSize { .. })
    ));
    assert!(matches!(
        RenderTargets::new(&ctx, 16, u32::MAX),
        Err(MprError::InvalidSize { .. })
    ));
    assert!(matches!(
        RenderTargets::with_hdr_format(&ctx, 16, 16, wgpu::TextureFormat::Rgba8Unorm),
        Err(MprError::UnsupportedFormat { .. })
    ));
}

/// Clears every target of `targets` (HDR to `color`, depth, ids) and reads them back.
fn clear_and_read(ctx: &GpuContext, targets: &RenderTargets, color: [f64; 4]) -> Vec<[f32; 4]> {
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let attachment = |view, clear| {
        Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: wgpu::StoreOp::Store,
            },
        })
    };
    let [r, g, b, a] = color;
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &[
            attachment(&targets.hdr.view, wgpu::Color { r, g, b, a }),
            attachment(
                &targets.surface_id.view,
                wgpu::Color {
                    r: f64::from(NO_SURFACE),
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                },
            ),
        ],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth.view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(REVERSE_Z_CLEAR),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    ctx.queue.submit([encoder.finish()]);
    let n = (targets.width * targets.height) as usize;
    let ids = read_u32(ctx, &targets.surface_id.texture).unwrap();
    assert_eq!(ids, vec![NO_SURFACE; n]);
    let depth = read_depth(ctx, &targets.depth.texture).unwrap();
    assert_eq!(depth, vec![REVERSE_Z_CLEAR; n]);
    read_rgba_f32(ctx, &targets.hdr.texture).unwrap()
}

#[test]
fn targets_of_both_hdr_formats_clear_and_read_back_with_row_padding() {
    let Some(ctx) = gpu_or_skip("targets_of_both_hdr_formats_clear_and_read_back_with_row_padding")
    else {
        return;
    };
    // 13 × 7: rows of 208 (f32) and 104 (f16) bytes, padded to 256.
    let formats = if ctx.float32_blendable() {
        vec![
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureFormat::Rgba16Float,
        ]
    } else {
        vec![wgpu::TextureFormat::Rgba16Float]
    };
    for format in formats {
        let targets = RenderTargets::with_hdr_format(&ctx, 13, 7, format).unwrap();
        assert_eq!(targets.hdr_format(), format);
        // Values exact in f16 as well as f32.
        let pixels = clear_and_read(&ctx, &targets, [0.5, 2.0, 1000.0, 1.0]);
        assert_eq!(pixels.len(), 13 * 7);
        for p in pixels {
            assert_eq!(p, [0.5, 2.0, 1000.0, 1.0], "{format:?}");
        }
    }
}

#[test]
fn software_preference_gives_a_cpu_adapter_or_a_clear_error() {
    // A machine with only a hardware GPU has no software adapter: that is the typed error, not a failure.
    match GpuContext::new(lustre_mpr::AdapterPreference::Software) {
        Ok(ctx) => {
            eprintln!("software adapter: {}", ctx.adapter());
            assert!(ctx.adapter().is_software(), "{}", ctx.adapter());
        }
        Err(e @ MprError::NoAdapter { .. }) => {
            assert!(e.to_string().contains("mesa-vulkan-drivers"), "{e}");
            eprintln!("no software adapter: {e}");
        }
        Err(e) => panic!("{e}"),
    }
}
