//! 8-bit sRGB PNG output: exposure, clamp, the sRGB transfer function.

use std::path::Path;

use ::image::ImageEncoder as _;
use ::image::codecs::png::PngEncoder;

use crate::atomic::write_atomic;
use crate::{Image, ImageError};

/// The sRGB opto-electronic transfer function (IEC 61966-2-1): linear `c`
/// in [0, 1] to the encoded value, `12.92 c` for `c ≤ 0.0031308`, else
/// `1.055 c^(1/2.4) − 0.055`.
pub fn srgb_oetf(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear channel to 8 bits: `round(255 · oetf(clamp(scale · c, 0, 1)))`,
/// NaN to 0.
fn encode_channel(c: f32, scale: f32) -> u8 {
    let v = c * scale;
    if !(v > 0.0) {
        return 0;
    }
    (srgb_oetf(v.min(1.0)) * 255.0).round() as u8
}

/// Tone maps `image` for display: each channel multiplied by `2^exposure`,
/// clamped to [0, 1], encoded with [`srgb_oetf`] and quantised to 8 bits
/// (row-major, top row first).
pub fn to_srgb8(image: &Image, exposure: f32) -> Vec<[u8; 3]> {
    let scale = exposure.exp2();
    image
        .pixels()
        .iter()
        .map(|p| p.map(|c| encode_channel(c, scale)))
        .collect()
}

/// Writes `image` tone mapped by [`to_srgb8`] at `exposure` as an 8-bit
/// RGB PNG, atomically.
pub fn write_png(path: impl AsRef<Path>, image: &Image, exposure: f32) -> Result<(), ImageError> {
    write_png_srgb8(
        path,
        image.width(),
        image.height(),
        &to_srgb8(image, exposure),
    )
}

/// Writes already encoded 8-bit RGB pixels (row-major, top row first), e.g.
/// a FLIP difference image, as a PNG, atomically.
pub fn write_png_srgb8(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    pixels: &[[u8; 3]],
) -> Result<(), ImageError> {
    let path = path.as_ref();
    let expected = (width as usize).checked_mul(height as usize).unwrap_or(0);
    if expected == 0 || expected != pixels.len() {
        return Err(ImageError::InvalidSize {
            width,
            height,
            expected,
            actual: pixels.len(),
        });
    }
    let bytes = pixels.as_flattened();
    write_atomic(path, |writer| {
        PngEncoder::new(writer)
            .write_image(bytes, width, height, ::image::ExtendedColorType::Rgb8)
            .map_err(|source| ImageError::EncodePng {
                path: path.to_path_buf(),
                source,
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::Scratch;

    #[test]
    fn oetf_matches_the_standard() {
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
        // Linear segment.
        assert!((srgb_oetf(0.002) - 0.02584).abs() < 1e-6);
        // Power segment: 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357.
        assert!((srgb_oetf(0.5) - 0.735_357).abs() < 1e-5);
        // The two pieces meet at the break point.
        let b = 0.003_130_8f32;
        assert!((12.92 * b - (1.055 * b.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
    }

    #[test]
    fn exposure_clamp_and_nan() {
        let image = Image::new(
            4,
            1,
            vec![
                [0.25, 0.5, 2.0],
                [-1.0, f32::NAN, f32::INFINITY],
                [0.0, 1.0, 0.2],
                [0.001, 0.0, 0.0],
            ],
        )
        .unwrap();
        let at_0 = to_srgb8(&image, 0.0);
        // 0.25 -> 0.537099 -> 137; 0.5 -> 0.735357 -> 188; 2.0 clamps to 255.
        assert_eq!(at_0[0], [137, 188, 255]);
        assert_eq!(at_0[1], [0, 0, 255]);
        // 0.2 -> 1.055 * 0.2^(1/2.4) - 0.055 = 0.484529 -> 123.55 -> 124.
        assert_eq!(at_0[2], [0, 255, 124]);
        // 0.001 * 12.92 * 255 = 3.29 -> 3.
        assert_eq!(at_0[3], [3, 0, 0]);
        // Exposure +1 doubles: 0.25 -> 0.5 -> 188.
        assert_eq!(to_srgb8(&image, 1.0)[0], [188, 255, 255]);
    }

    #[test]
    fn png_round_trip() {
        let dir = Scratch::new("png");
        let path = dir.path().join("a.png");
        let image = Image::new(2, 1, vec![[0.5, 0.0, 1.0], [0.25, 0.25, 0.25]]).unwrap();
        write_png(&path, &image, 0.0).unwrap();
        let back = ::image::open(&path).unwrap().into_rgb8();
        assert_eq!(back.dimensions(), (2, 1));
        assert_eq!(back.get_pixel(0, 0).0, [188, 0, 255]);
        assert_eq!(back.get_pixel(1, 0).0, [137, 137, 137]);
        assert_eq!(dir.entries(), vec!["a.png".to_owned()]);
    }

    #[test]
    fn wrong_pixel_count_and_missing_directory() {
        let dir = Scratch::new("png-errors");
        let path = dir.path().join("b.png");
        assert!(write_png_srgb8(&path, 2, 2, &[[0; 3]; 3]).is_err());
        let nested = dir.path().join("missing").join("c.png");
        let image = Image::filled(1, 1, [0.5; 3]).unwrap();
        assert!(write_png(&nested, &image, 0.0).is_err());
        assert!(dir.entries().is_empty());
    }
}
