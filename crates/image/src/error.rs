//! The error type of every fallible function of this crate.

use std::path::PathBuf;

/// What went wrong, naming the file or the sizes at fault.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// A width or height of zero, or a pixel buffer whose length is not `width × height`.
    #[error("an image of {width}x{height} needs {expected} pixels, got {actual}")]
    InvalidSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// `width × height` (0 when it overflows or a side is zero).
        expected: usize,
        /// Length of the pixel buffer given.
        actual: usize,
    },
    /// Two images compared with each other differ in size.
    #[error(
        "the test image is {test_width}x{test_height} but the reference is {reference_width}x{reference_height}"
    )]
    SizeMismatch {
        /// Width of the test image.
        test_width: u32,
        /// Height of the test image.
        test_height: u32,
        /// Width of the reference image.
        reference_width: u32,
        /// Height of the reference image.
        reference_height: u32,
    },
    /// A metric is undefined for these images (e.g. a relative error against a black reference).
    #[error("{0}")]
    Undefined(String),
    /// An EXR file could not be read or decoded.
    #[error("cannot read {}: {source}", path.display())]
    ReadExr {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        source: exr::error::Error,
    },
    /// An EXR file has no layer with the channels `R`, `G` and `B`.
    #[error("{} has no layer with R, G and B channels (channels found: {})", path.display(), found.join(", "))]
    MissingChannels {
        /// The file.
        path: PathBuf,
        /// The channel names of every layer of the file.
        found: Vec<String>,
    },
    /// An EXR file holds a NaN or an infinity.
    #[error("{} holds a non-finite value {value} at pixel ({x}, {y})", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Column of the first non-finite pixel.
        x: usize,
        /// Row of the first non-finite pixel (0 = top).
        y: usize,
        /// The value found.
        value: f32,
    },
    /// Encoding an EXR image failed.
    #[error("cannot encode {} as EXR: {source}", path.display())]
    EncodeExr {
        /// The file being written.
        path: PathBuf,
        /// The encoder's error.
        source: exr::error::Error,
    },
    /// Encoding a PNG image failed.
    #[error("cannot encode {} as PNG: {source}", path.display())]
    EncodePng {
        /// The file being written.
        path: PathBuf,
        /// The encoder's error.
        source: ::image::ImageError,
    },
    /// Serialising JSON failed.
    #[error("cannot encode {} as JSON: {source}", path.display())]
    EncodeJson {
        /// The file being written.
        path: PathBuf,
        /// The serialiser's error.
        source: serde_json::Error,
    },
    /// Creating, writing or renaming a file failed.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file being written (its final name, not the temporary one).
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
}
