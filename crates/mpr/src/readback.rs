//! Synchronous texture readback: copy into a buffer with rows padded to
//! 256 bytes (`COPY_BYTES_PER_ROW_ALIGNMENT`), map it, strip the padding and
//! decode texels (linear f32 RGBA, u32 ids, depth, 8-bit RGBA).

use crate::{GpuContext, MprError, Result};

/// Bytes per row of a `width`-texel row padded to wgpu's 256-byte copy alignment.
pub fn padded_bytes_per_row(width: u32, bytes_per_texel: u32) -> u32 {
    let unpadded = width * bytes_per_texel;
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// Copies one aspect of mip 0 of `texture` to the CPU, rows tightly packed.
pub fn read_texture_bytes(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>> {
    let format = texture.format();
    let bytes_per_texel = format
        .block_copy_size(Some(aspect))
        .filter(|_| format.block_dimensions() == (1, 1))
        .ok_or(MprError::UnsupportedFormat {
            what: "texture readback",
            format,
        })?;
    let (width, height) = (texture.width(), texture.height());
    let padded = padded_bytes_per_row(width, bytes_per_texel);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.checked("texture readback copy", || {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            texture.size(),
        );
        ctx.queue.submit([encoder.finish()]);
    })?;
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        // The receiver outlives the poll below; a send error cannot happen.
        let _ = sender.send(result);
    });
    ctx.wait()?;
    let label = || format!("{format:?} {width}x{height}");
    receiver
        .recv()
        .map_err(|e| MprError::Readback {
            what: label(),
            message: e.to_string(),
        })?
        .map_err(|e| MprError::Readback {
            what: label(),
            message: e.to_string(),
        })?;
    let data = slice.get_mapped_range().map_err(|e| MprError::Readback {
        what: label(),
        message: e.to_string(),
    })?;
    let row = (width * bytes_per_texel) as usize;
    let mut out = Vec::with_capacity(row * height as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        out.extend_from_slice(&data[start..start + row]);
    }
    Ok(out)
}

/// Decodes an IEEE 754 binary16 value (all cases: zero, subnormal, normal, infinity, NaN).
pub fn f16_to_f32(bits: u16) -> f32 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let mantissa = f32::from(bits & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Reads an `Rgba32Float` or `Rgba16Float` texture as linear f32 RGBA, row 0 at the top.
pub fn read_rgba_f32(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<[f32; 4]>> {
    let bytes = read_texture_bytes(ctx, texture, wgpu::TextureAspect::All)?;
    match texture.format() {
        wgpu::TextureFormat::Rgba32Float => Ok(bytes
            .chunks_exact(16)
            .map(|t| {
                std::array::from_fn(|c| {
                    f32::from_le_bytes([t[4 * c], t[4 * c + 1], t[4 * c + 2], t[4 * c + 3]])
                })
            })
            .collect()),
        wgpu::TextureFormat::Rgba16Float => Ok(bytes
            .chunks_exact(8)
            .map(|t| {
                std::array::from_fn(|c| f16_to_f32(u16::from_le_bytes([t[2 * c], t[2 * c + 1]])))
            })
            .collect()),
        format => Err(MprError::UnsupportedFormat {
            what: "read_rgba_f32",
            format,
        }),
    }
}

/// Reads an 8-bit RGBA texture (`Rgba8Unorm` or `Rgba8UnormSrgb`) as stored.
pub fn read_rgba8(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<[u8; 4]>> {
    match texture.format() {
        wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => {
            let bytes = read_texture_bytes(ctx, texture, wgpu::TextureAspect::All)?;
            Ok(bytes
                .chunks_exact(4)
                .map(|t| [t[0], t[1], t[2], t[3]])
                .collect())
        }
        format => Err(MprError::UnsupportedFormat {
            what: "read_rgba8",
            format,
        }),
    }
}

/// Reads an `R32Uint` texture (surface ids).
pub fn read_u32(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u32>> {
    match texture.format() {
        wgpu::TextureFormat::R32Uint => {
            let bytes = read_texture_bytes(ctx, texture, wgpu::TextureAspect::All)?;
            Ok(bytes
                .chunks_exact(4)
                .map(|t| u32::from_le_bytes([t[0], t[1], t[2], t[3]]))
                .collect())
        }
        format => Err(MprError::UnsupportedFormat {
            what: "read_u32",
            format,
        }),
    }
}

/// Reads the depth aspect of a `Depth32Float` texture.
pub fn read_depth(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<f32>> {
    match texture.format() {
        wgpu::TextureFormat::Depth32Float | wgpu::TextureFormat::Depth32FloatStencil8 => {
            let bytes = read_texture_bytes(ctx, texture, wgpu::TextureAspect::DepthOnly)?;
            Ok(bytes
                .chunks_exact(4)
                .map(|t| f32::from_le_bytes([t[0], t[1], t[2], t[3]]))
                .collect())
        }
        format => Err(MprError::UnsupportedFormat {
            what: "read_depth",
            format,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_padded_to_256_bytes() {
        assert_eq!(padded_bytes_per_row(64, 16), 1024);
        assert_eq!(padded_bytes_per_row(1, 4), 256);
        assert_eq!(padded_bytes_per_row(65, 4), 512);
        assert_eq!(padded_bytes_per_row(3, 16), 256);
    }

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert!(f16_to_f32(0x7e00).is_nan());
    }
}
