//! [`Image`]: a linear HDR RGB image.

use crate::ImageError;

/// A linear HDR image: `width × height` pixels, row-major with the top row
/// first, each pixel linear Rec.709 RGB radiance in W/(m² sr) (DESIGN.md,
/// "Conventions"). The pixel count always equals `width × height` and both
/// sides are at least 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Columns.
    width: u32,
    /// Rows.
    height: u32,
    /// `pixels[y * width + x]`, `y = 0` at the top.
    pixels: Vec<[f32; 3]>,
}

/// `width × height` as a pixel count, or the size error for `actual` pixels.
fn pixel_count(width: u32, height: u32, actual: usize) -> Result<usize, ImageError> {
    let expected = (width as usize).checked_mul(height as usize).unwrap_or(0);
    if expected == 0 || expected != actual {
        return Err(ImageError::InvalidSize {
            width,
            height,
            expected,
            actual,
        });
    }
    Ok(expected)
}

impl Image {
    /// An image from row-major RGB pixels (top row first); fails unless
    /// `pixels.len() == width × height > 0`.
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 3]>) -> Result<Self, ImageError> {
        pixel_count(width, height, pixels.len())?;
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// An image with every pixel `value`; fails when a side is zero.
    pub fn filled(width: u32, height: u32, value: [f32; 3]) -> Result<Self, ImageError> {
        let count = (width as usize).checked_mul(height as usize).unwrap_or(0);
        pixel_count(width, height, count)?;
        Ok(Self {
            width,
            height,
            pixels: vec![value; count],
        })
    }

    /// An image from row-major RGBA pixels (e.g. a GPU readback), dropping alpha.
    pub fn from_rgba(width: u32, height: u32, rgba: &[[f32; 4]]) -> Result<Self, ImageError> {
        pixel_count(width, height, rgba.len())?;
        Ok(Self {
            width,
            height,
            pixels: rgba.iter().map(|&[r, g, b, _]| [r, g, b]).collect(),
        })
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, row-major, top row first.
    pub fn pixels(&self) -> &[[f32; 3]] {
        &self.pixels
    }

    /// The pixels, mutable (the size cannot change).
    pub fn pixels_mut(&mut self) -> &mut [[f32; 3]] {
        &mut self.pixels
    }

    /// The pixel in column `x` and row `y` (0 = top); panics outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Gives the pixel buffer back.
    pub fn into_pixels(self) -> Vec<[f32; 3]> {
        self.pixels
    }

    /// Fails with [`ImageError::SizeMismatch`] unless `self` (the test image)
    /// and `reference` have the same width and height.
    pub fn check_same_size(&self, reference: &Image) -> Result<(), ImageError> {
        if (self.width, self.height) != (reference.width, reference.height) {
            return Err(ImageError::SizeMismatch {
                test_width: self.width,
                test_height: self.height,
                reference_width: reference.width,
                reference_height: reference.height,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_validated() {
        assert!(Image::new(2, 3, vec![[0.0; 3]; 6]).is_ok());
        for (w, h, n) in [(2, 3, 5), (0, 3, 0), (2, 0, 0), (0, 0, 0)] {
            let error = Image::new(w, h, vec![[0.0; 3]; n]).unwrap_err();
            assert!(matches!(error, ImageError::InvalidSize { .. }), "{error}");
        }
        assert!(Image::filled(0, 4, [1.0; 3]).is_err());
        assert!(Image::from_rgba(1, 2, &[[0.0; 4]]).is_err());
    }

    #[test]
    fn from_rgba_drops_alpha_and_keeps_order() {
        let image = Image::from_rgba(2, 1, &[[1.0, 2.0, 3.0, 9.0], [4.0, 5.0, 6.0, 9.0]]).unwrap();
        assert_eq!(image.pixels(), &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert_eq!(image.pixel(1, 0), [4.0, 5.0, 6.0]);
    }

    #[test]
    fn size_mismatch_names_both_sizes() {
        let a = Image::filled(2, 2, [0.0; 3]).unwrap();
        let b = Image::filled(3, 2, [0.0; 3]).unwrap();
        let error = a.check_same_size(&b).unwrap_err().to_string();
        assert!(error.contains("2x2") && error.contains("3x2"), "{error}");
        assert!(a.check_same_size(&a.clone()).is_ok());
    }
}
