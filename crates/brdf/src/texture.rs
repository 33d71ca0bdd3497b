//! Plain RGBA float image data for textures that a GPU crate uploads (the K and R textures of Bastos et al. 1999, section 8.2).

/// A `width × height` image of RGBA `f32` texels, row-major from row 0 (texture coordinate t = 0) upwards, four floats per texel: the layout of wgpu's `Rgba32Float`.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureRgba32F {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width × height × 4` floats, RGBA per texel.
    pub texels: Vec<f32>,
}

impl TextureRgba32F {
    /// A texture of zeros.
    pub fn zeros(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            texels: vec![0.0; width as usize * height as usize * 4],
        }
    }

    /// The RGBA texel at column `x`, row `y`; `None` outside the image.
    pub fn texel(&self, x: u32, y: u32) -> Option<[f32; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y as usize * self.width as usize + x as usize) * 4;
        Some([
            self.texels[i],
            self.texels[i + 1],
            self.texels[i + 2],
            self.texels[i + 3],
        ])
    }

    /// Sets the texel at column `x`, row `y` (ignored outside the image).
    pub fn set_texel(&mut self, x: u32, y: u32, rgba: [f32; 4]) {
        if x < self.width && y < self.height {
            let i = (y as usize * self.width as usize + x as usize) * 4;
            self.texels[i..i + 4].copy_from_slice(&rgba);
        }
    }

    /// Bytes per row (`width × 16`), as a GPU upload needs.
    pub fn bytes_per_row(&self) -> u32 {
        self.width * 16
    }
}
