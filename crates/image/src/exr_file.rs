//! OpenEXR files: linear RGB in, linear RGB out (DESIGN.md, "Data flow", 4).

use std::path::Path;

use exr::prelude::{
    Encoding, Image as ExrImage, MetaData, ReadChannels, ReadLayers, SpecificChannels, Vec2,
    WritableImage, f16, read,
};

use crate::atomic::write_atomic;
use crate::{Image, ImageError};

/// The sample type of the RGB channels of a written EXR file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// 32-bit float: exact, for renders and references.
    F32,
    /// 16-bit half float (11 significant bits): half the size, for committed goldens.
    F16,
}

/// Reads the first layer with `R`, `G` and `B` channels (f16, f32 or u32
/// samples, any other channels ignored) of the EXR file at `path`,
/// rejecting NaN and infinite values.
pub fn read_exr(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let read_error = |source| ImageError::ReadExr {
        path: path.to_path_buf(),
        source,
    };
    let meta = MetaData::read_from_file(path, false).map_err(read_error)?;
    let names = |header: &exr::meta::header::Header| -> Vec<String> {
        header
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect()
    };
    let has_rgb = meta.headers.iter().any(|header| {
        let names = names(header);
        ["R", "G", "B"].iter().all(|c| names.iter().any(|n| n == c))
    });
    if !has_rgb {
        return Err(ImageError::MissingChannels {
            path: path.to_path_buf(),
            found: meta.headers.iter().flat_map(names).collect(),
        });
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |resolution: Vec2<usize>, _| {
                (
                    resolution.width(),
                    resolution.height(),
                    vec![[0.0f32; 3]; resolution.width() * resolution.height()],
                )
            },
            |(width, _, pixels): &mut (usize, usize, Vec<[f32; 3]>),
             position: Vec2<usize>,
             (r, g, b): (f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(read_error)?;
    let (width, height, pixels) = image.layer_data.channel_data.pixels;
    if let Some((i, value)) = pixels
        .iter()
        .enumerate()
        .find_map(|(i, p)| p.iter().find(|v| !v.is_finite()).map(|&v| (i, v)))
    {
        return Err(ImageError::NonFinite {
            path: path.to_path_buf(),
            x: i % width,
            y: i / width,
            value,
        });
    }
    let side = |n: usize| {
        u32::try_from(n).map_err(|_| ImageError::InvalidSize {
            width: u32::MAX,
            height: u32::MAX,
            expected: 0,
            actual: pixels.len(),
        })
    };
    Image::new(side(width)?, side(height)?, pixels)
}

/// Writes `image` to `path` as a single-layer EXR with `R`, `G`, `B`
/// channels of the given precision, ZIP-compressed (lossless), atomically.
pub fn write_exr(
    path: impl AsRef<Path>,
    image: &Image,
    precision: Precision,
) -> Result<(), ImageError> {
    let path = path.as_ref();
    let size = (image.width() as usize, image.height() as usize);
    let width = size.0;
    let at = move |p: Vec2<usize>| image.pixels()[p.y() * width + p.x()];
    let encode_error = |source| ImageError::EncodeExr {
        path: path.to_path_buf(),
        source,
    };
    write_atomic(path, |writer| {
        let result = match precision {
            Precision::F32 => ExrImage::from_encoded_channels(
                size,
                Encoding::SMALL_LOSSLESS,
                SpecificChannels::rgb(|p: Vec2<usize>| {
                    let [r, g, b] = at(p);
                    (r, g, b)
                }),
            )
            .write()
            .to_buffered(writer),
            Precision::F16 => ExrImage::from_encoded_channels(
                size,
                Encoding::SMALL_LOSSLESS,
                SpecificChannels::rgb(|p: Vec2<usize>| {
                    let [r, g, b] = at(p);
                    (f16::from_f32(r), f16::from_f32(g), f16::from_f32(b))
                }),
            )
            .write()
            .to_buffered(writer),
        };
        result.map_err(encode_error)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{Scratch, ramp};

    #[test]
    fn f32_round_trip_is_exact() {
        let dir = Scratch::new("exr-f32");
        let image = ramp(7, 5);
        let path = dir.path().join("ramp.exr");
        write_exr(&path, &image, Precision::F32).unwrap();
        assert_eq!(read_exr(&path).unwrap(), image);
        assert_eq!(dir.entries(), vec!["ramp.exr".to_owned()]);
    }

    #[test]
    fn f16_round_trip_is_within_half_precision() {
        let dir = Scratch::new("exr-f16");
        let image = ramp(9, 4);
        let path = dir.path().join("ramp.exr");
        write_exr(&path, &image, Precision::F16).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width(), back.height()), (9, 4));
        for (a, b) in image.pixels().iter().zip(back.pixels()) {
            for c in 0..3 {
                // f16 keeps 11 significant bits: relative error at most 2^-11.
                assert!(
                    (a[c] - b[c]).abs() <= a[c].abs() * 2f32.powi(-11) + 1e-7,
                    "{} vs {}",
                    a[c],
                    b[c]
                );
            }
        }
    }

    #[test]
    fn missing_directory_leaves_nothing() {
        let dir = Scratch::new("exr-missing-dir");
        let path = dir.path().join("nope").join("x.exr");
        let error = write_exr(&path, &ramp(2, 2), Precision::F32).unwrap_err();
        assert!(error.to_string().contains("x.exr"), "{error}");
        assert!(!path.exists());
        assert!(dir.entries().is_empty());
    }

    #[test]
    fn missing_file_names_the_path() {
        let error = read_exr("/nonexistent/lustre/missing.exr").unwrap_err();
        assert!(matches!(error, ImageError::ReadExr { .. }));
        assert!(error.to_string().contains("missing.exr"), "{error}");
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        let dir = Scratch::new("exr-garbage");
        let path = dir.path().join("garbage.exr");
        std::fs::write(&path, b"not an exr file at all").unwrap();
        assert!(matches!(
            read_exr(&path).unwrap_err(),
            ImageError::ReadExr { .. }
        ));
    }

    #[test]
    fn missing_channels_are_rejected() {
        let dir = Scratch::new("exr-luminance");
        let path = dir.path().join("y.exr");
        let image = ExrImage::from_channels(
            (2, 2),
            SpecificChannels::build()
                .with_channel("Y")
                .with_pixel_fn(|_| (0.5f32,)),
        );
        image.write().to_file(&path).unwrap();
        let error = read_exr(&path).unwrap_err();
        assert!(
            matches!(error, ImageError::MissingChannels { .. }),
            "{error}"
        );
        assert!(error.to_string().contains('Y'), "{error}");
    }

    #[test]
    fn nan_is_rejected_with_its_pixel() {
        let dir = Scratch::new("exr-nan");
        let path = dir.path().join("nan.exr");
        let mut image = ramp(3, 3);
        image.pixels_mut()[5][1] = f32::NAN;
        write_exr(&path, &image, Precision::F32).unwrap();
        let error = read_exr(&path).unwrap_err();
        assert!(
            matches!(error, ImageError::NonFinite { x: 2, y: 1, .. }),
            "{error}"
        );
    }
}
