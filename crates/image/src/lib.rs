//! # lustre-image
//!
//! Linear HDR images for Lustre (DESIGN.md, "Data flow", 4 and "Testing"):
//! the [`Image`] type, EXR and PNG files written atomically (temporary
//! file + rename, DESIGN.md "Conventions"), JSON sidecars, and the metrics
//! the golden and reference comparisons use.
//!
//! | item | what |
//! |---|---|
//! | [`Image`] | row-major linear Rec.709 RGB, W/(m² sr) |
//! | [`read_exr`], [`write_exr`], [`Precision`] | OpenEXR in (f16/f32) and out |
//! | [`write_png`], [`to_srgb8`], [`srgb_oetf`], [`write_png_srgb8`] | exposure, clamp, sRGB, 8-bit PNG |
//! | [`write_json_atomic`], [`write_bytes_atomic`] | sidecars and other files |
//! | [`metrics::relative_mse`], [`metrics::mse`], [`metrics::mean`] | Rousselle et al. 2011 relMSE and friends |
//! | [`metrics::flip`], [`metrics::difference_image`] | NVIDIA's LDR-FLIP and its magma error image |
//!
//! ```
//! use lustre_image::{metrics, Image};
//!
//! let reference = Image::filled(16, 16, [0.5, 0.25, 0.125]).unwrap();
//! let test = Image::filled(16, 16, [0.5, 0.25, 0.25]).unwrap();
//! let rel = metrics::relative_mse(&test, &reference, metrics::RELATIVE_MSE_EPSILON).unwrap();
//! assert!(rel > 0.0);
//! let flip = metrics::flip(&test, &reference, 0.0).unwrap();
//! assert!(flip.mean > 0.0 && flip.mean < 1.0);
//! ```

mod atomic;
mod error;
mod exr_file;
mod image;
pub mod metrics;
mod png_file;

pub use atomic::{write_bytes_atomic, write_json_atomic};
pub use error::ImageError;
pub use exr_file::{Precision, read_exr, write_exr};
pub use image::Image;
pub use png_file::{srgb_oetf, to_srgb8, write_png, write_png_srgb8};

#[cfg(test)]
mod test_support {
    //! Scratch directories and test images shared by the unit tests.

    use std::path::{Path, PathBuf};

    use crate::Image;

    /// A fresh, empty directory under the system temporary directory,
    /// removed on drop.
    pub struct Scratch(PathBuf);

    impl Scratch {
        /// Creates `<tmp>/lustre-image-<name>-<pid>`, emptied first.
        pub fn new(name: &str) -> Self {
            let dir =
                std::env::temp_dir().join(format!("lustre-image-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Self(dir)
        }

        /// The directory.
        pub fn path(&self) -> &Path {
            &self.0
        }

        /// The names of the directory's entries, sorted (hidden temporaries included).
        pub fn entries(&self) -> Vec<String> {
            let mut names: Vec<String> = std::fs::read_dir(&self.0)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            names
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// A smooth HDR test image: values from 0 to about 3, different per channel.
    pub fn ramp(width: u32, height: u32) -> Image {
        let pixels = (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| {
                    let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
                    [u * 3.0, v, 0.1 + 0.5 * u * v]
                })
            })
            .collect();
        Image::new(width, height, pixels).unwrap()
    }
}
