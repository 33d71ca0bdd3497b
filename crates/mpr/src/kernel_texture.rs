//! The kernel texture of Stürzlinger & Bastos 1997, section 3.2: "a texture of
//! 64×64 pixels", a regular sampling of the unit-volume kernel over
//! `[-1, 1]²`, with mip-maps "for filtering of small triangles".
//!
//! Texel values are the kernel at texel centres, scaled so that their sum
//! times the texel area `(2/size)²` is exactly one: the bilinear
//! reconstruction then keeps the kernel's unit volume up to the
//! interpolation error. Each mip level is the 2×2 box average of the one
//! above, which keeps that sum. Stored as `R16Float` (filterable on every
//! device; relative rounding 2⁻¹¹).

use half::f16;
use lustre_photon::Kernel;

use crate::{GpuContext, MprError, Result};

/// Side of the kernel texture in the paper (section 3.2).
pub const KERNEL_TEXTURE_SIZE: u32 = 64;

/// Format of the kernel texture.
pub const KERNEL_TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// The mip chain of a `size × size` kernel texture, level 0 first, each level row-major.
pub fn kernel_mips(kernel: Kernel, size: u32) -> Result<Vec<Vec<f32>>> {
    if size == 0 || !size.is_power_of_two() {
        return Err(MprError::InvalidSetting {
            what: "kernel texture size",
            message: format!("{size} is not a power of two"),
        });
    }
    let mut level = kernel.texture(size as usize);
    let texel_area = (2.0 / size as f64).powi(2);
    let volume: f64 = level.iter().map(|&v| f64::from(v)).sum::<f64>() * texel_area;
    for v in &mut level {
        *v = (f64::from(*v) / volume) as f32;
    }
    let mut mips = vec![level];
    let mut side = size as usize;
    while side > 1 {
        let above = mips.last().unwrap();
        let half_side = side / 2;
        let mut next = Vec::with_capacity(half_side * half_side);
        for j in 0..half_side {
            for i in 0..half_side {
                let at = |x: usize, y: usize| above[y * side + x];
                next.push(
                    0.25 * (at(2 * i, 2 * j)
                        + at(2 * i + 1, 2 * j)
                        + at(2 * i, 2 * j + 1)
                        + at(2 * i + 1, 2 * j + 1)),
                );
            }
        }
        mips.push(next);
        side = half_side;
    }
    Ok(mips)
}

/// Uploads the mip chain of `kernel` as a [`KERNEL_TEXTURE_FORMAT`] texture.
pub fn kernel_texture(ctx: &GpuContext, kernel: Kernel, size: u32) -> Result<wgpu::Texture> {
    let mips = kernel_mips(kernel, size)?;
    ctx.checked("kernel texture", || {
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("splat-kernel"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: mips.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: KERNEL_TEXTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (level, texels) in mips.iter().enumerate() {
            let side = size >> level;
            let halves: Vec<f16> = texels.iter().map(|&v| f16::from_f32(v)).collect();
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&halves),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(2 * side),
                    rows_per_image: Some(side),
                },
                wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: 1,
                },
            );
        }
        texture
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mip_level_has_unit_volume() {
        for kernel in [Kernel::Silverman, Kernel::Gaussian] {
            let mips = kernel_mips(kernel, KERNEL_TEXTURE_SIZE).unwrap();
            assert_eq!(mips.len(), 7);
            for (level, texels) in mips.iter().enumerate() {
                let side = (KERNEL_TEXTURE_SIZE >> level) as f64;
                let volume: f64 =
                    texels.iter().map(|&v| f64::from(v)).sum::<f64>() * (2.0 / side).powi(2);
                assert!(
                    (volume - 1.0).abs() < 1e-5,
                    "{kernel:?} level {level}: {volume}"
                );
            }
        }
    }

    #[test]
    fn level_zero_is_the_kernel_within_its_midpoint_rule_error() {
        // Silverman's K2 integrates to 1; its 64x64 midpoint sum differs by
        // well under 1 %, so the rescaled texels stay within 1 % of K.
        let mips = kernel_mips(Kernel::Silverman, 64).unwrap();
        let raw = Kernel::Silverman.texture(64);
        let peak = raw.iter().cloned().fold(0.0, f32::max);
        for (a, b) in mips[0].iter().zip(&raw) {
            assert!((a - b).abs() <= 0.01 * peak, "{a} vs {b}");
        }
    }

    #[test]
    fn sizes_that_are_not_powers_of_two_are_refused() {
        assert!(kernel_mips(Kernel::Silverman, 48).is_err());
        assert!(kernel_mips(Kernel::Silverman, 0).is_err());
    }
}
