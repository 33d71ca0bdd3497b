//! Colour texture maps: the decoded `map_Kd` of an MTL material or the
//! `baseColorTexture` of a glTF one, which scales the diffuse reflectance of
//! the material's Lambertian part point by point.
//!
//! Texels are linear Rec.709 RGB in `f32` (8- and 16-bit files are sRGB
//! encoded and decoded with the exact sRGB transfer function; alpha is not
//! read). Row 0 is the top of the image. Texture coordinates follow OBJ's
//! convention, which the scene model keeps everywhere: `(0, 0)` is the
//! image's bottom-left corner and `v` grows upwards (the glTF loader flips
//! glTF's `v`). [`Texture::sample`] filters bilinearly between texel centres
//! and repeats the image outside `[0, 1]²` (OpenGL's `GL_REPEAT`, glTF's
//! default wrap), so a GPU sampler with `Repeat` and linear filtering at the
//! coordinates `(u, 1 − v)` reads the same value from level 0.
//!
//! Files are decoded with the `image` crate (PNG and JPEG).

use std::fmt;
use std::path::Path;

use glam::Vec2;

use crate::{GeometryError, Location, Result, Rgb};

/// Largest width or height of a texture file that is decoded (16,384 texels, 3 GiB of `f32` RGB at most).
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

/// A decoded colour texture: linear RGB texels, row 0 at the top (`v = 1`).
#[derive(Clone, PartialEq)]
pub struct Texture {
    name: String,
    width: u32,
    height: u32,
    texels: Vec<Rgb>,
}

impl fmt::Debug for Texture {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Texture")
            .field("name", &self.name)
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1): an encoded value in `[0, 1]` to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The inverse of [`srgb_to_linear`]: a linear value in `[0, 1]` to its sRGB encoding.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl Texture {
    /// A texture of `width × height` linear texels, row by row from the top; fails on a zero side, a wrong texel count or texels that are not finite and non-negative.
    pub fn new(name: impl Into<String>, width: u32, height: u32, texels: Vec<Rgb>) -> Result<Self> {
        let name = name.into();
        let bad = |message: String| GeometryError::Parse {
            location: Location {
                file: name.clone().into(),
                line: None,
            },
            message,
        };
        if width == 0 || height == 0 {
            return Err(bad(format!("texture of {width} × {height} texels")));
        }
        if texels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(bad(format!(
                "{} texels for a {width} × {height} texture",
                texels.len()
            )));
        }
        if let Some(t) = texels
            .iter()
            .find(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(bad(format!(
                "texel {t} is not a finite non-negative colour"
            )));
        }
        Ok(Self {
            name,
            width,
            height,
            texels,
        })
    }

    /// Decodes a PNG or JPEG file (sRGB encoded); the error names the file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::decode(&bytes, &path.display().to_string())
    }

    /// Decodes PNG or JPEG bytes (sRGB encoded) named `name` in errors (a file path, or `file.glb: image 3`).
    pub fn decode(bytes: &[u8], name: &str) -> Result<Self> {
        let bad = |message: String| GeometryError::Parse {
            location: Location {
                file: name.into(),
                line: None,
            },
            message,
        };
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| bad(format!("cannot read the image: {e}")))?;
        if reader.format().is_none() {
            return Err(bad("not a PNG or JPEG image".into()));
        }
        let (width, height) = reader
            .into_dimensions()
            .map_err(|e| bad(format!("cannot decode the image: {e}")))?;
        if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(bad(format!(
                "a {width} × {height} image is larger than the {MAX_TEXTURE_SIDE} texels a side Lustre decodes"
            )));
        }
        let image = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| bad(format!("cannot read the image: {e}")))?
            .decode()
            .map_err(|e| bad(format!("cannot decode the image: {e}")))?;
        let rgb = image.to_rgb32f();
        let texels = rgb
            .pixels()
            .map(|p| Rgb::from(p.0.map(|c| srgb_to_linear(c.clamp(0.0, 1.0)))))
            .collect();
        Self::new(name, width, height, texels)
    }

    /// The texture as a 16-bit sRGB PNG (texels clamped to `[0, 1]`), which [`Texture::decode`] reads back within 10⁻⁴.
    pub fn encode_png16(&self) -> Result<Vec<u8>> {
        let samples: Vec<u16> = self
            .texels
            .iter()
            .flat_map(|t| t.to_array())
            .map(|c| (linear_to_srgb(c.clamp(0.0, 1.0)) * 65535.0).round() as u16)
            .collect();
        let image =
            image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(self.width, self.height, samples)
                .ok_or_else(|| GeometryError::Unsupported {
                    what: format!("texture `{}`", self.name),
                    why: "its texels do not fill its size".into(),
                })?;
        let mut png = Vec::new();
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| GeometryError::Unsupported {
                what: format!("texture `{}`", self.name),
                why: format!("cannot encode it as PNG: {e}"),
            })?;
        Ok(png)
    }

    /// The file (or embedded image) it was decoded from, or the name it was made with.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, row by row from the top.
    pub fn texels(&self) -> &[Rgb] {
        &self.texels
    }

    /// Texel `(x, y)`, `y = 0` the top row, both wrapped into the image (repeat).
    pub fn texel(&self, x: i64, y: i64) -> Rgb {
        let x = x.rem_euclid(i64::from(self.width)) as usize;
        let y = y.rem_euclid(i64::from(self.height)) as usize;
        self.texels[y * self.width as usize + x]
    }

    /// The bilinearly filtered colour at texture coordinates `uv` (OBJ's convention, `v` up), repeated outside `[0, 1]²` (OpenGL's bilinear `GL_LINEAR` with `GL_REPEAT`).
    pub fn sample(&self, uv: Vec2) -> Rgb {
        if !uv.is_finite() {
            return self.mean();
        }
        let u = uv.x.rem_euclid(1.0);
        let v = uv.y.rem_euclid(1.0);
        let s = f64::from(u) * f64::from(self.width) - 0.5;
        let t = (1.0 - f64::from(v)) * f64::from(self.height) - 0.5;
        let (x0, y0) = (s.floor(), t.floor());
        let (fx, fy) = ((s - x0) as f32, (t - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// The mean of all texels: the factor by which the texture scales a surface's reflected power on average over uniformly covered texture space.
    pub fn mean(&self) -> Rgb {
        let sum = self
            .texels
            .iter()
            .fold(glam::DVec3::ZERO, |s, t| s + t.as_dvec3());
        (sum / self.texels.len() as f64).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2 × 2: top row red, green; bottom row blue, white.
        Texture::new("checker", 2, 2, vec![Rgb::X, Rgb::Y, Rgb::Z, Rgb::ONE]).unwrap()
    }

    #[test]
    fn texel_centres_read_their_texel() {
        let t = checker();
        // Texel (0, 0) is the top-left one: u = 0.25, v = 0.75.
        assert_eq!(t.sample(Vec2::new(0.25, 0.75)), Rgb::X);
        assert_eq!(t.sample(Vec2::new(0.75, 0.75)), Rgb::Y);
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Rgb::Z);
        assert_eq!(t.sample(Vec2::new(0.75, 0.25)), Rgb::ONE);
    }

    #[test]
    fn bilinear_between_centres_and_repeat_across_edges() {
        let t = checker();
        // Half-way between the two top texels.
        assert!(
            (t.sample(Vec2::new(0.5, 0.75)) - Rgb::new(0.5, 0.5, 0.0))
                .abs()
                .max_element()
                < 1e-6
        );
        // At u = 0 the left and right columns wrap onto each other.
        assert!(
            (t.sample(Vec2::new(0.0, 0.75)) - Rgb::new(0.5, 0.5, 0.0))
                .abs()
                .max_element()
                < 1e-6
        );
        // Repeat: one period away reads the same.
        for uv in [Vec2::new(0.3, 0.6), Vec2::new(0.9, 0.1)] {
            let d = t.sample(uv) - t.sample(uv + Vec2::new(3.0, -2.0));
            assert!(d.abs().max_element() < 1e-5, "{uv}");
        }
        // The centre is the mean of the four.
        assert!((t.sample(Vec2::splat(0.5)) - t.mean()).abs().max_element() < 1e-6);
    }

    #[test]
    fn srgb_decode_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // 50 % sRGB grey is about 21.4 % linear.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        // Continuous at the linear segment's end.
        assert!((srgb_to_linear(0.04045) - 0.04045 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn png16_round_trip() {
        let texels = (0..12)
            .map(|i| Rgb::new(i as f32 / 11.0, 0.5, (i as f32 / 11.0).powi(3)))
            .collect();
        let t = Texture::new("ramp", 4, 3, texels).unwrap();
        let back = Texture::decode(&t.encode_png16().unwrap(), "ramp.png").unwrap();
        assert_eq!((back.width(), back.height()), (4, 3));
        for (a, b) in t.texels().iter().zip(back.texels()) {
            assert!((*a - *b).abs().max_element() < 1e-4, "{a} {b}");
        }
        for c in [0.0, 0.001, 0.2, 0.9, 1.0] {
            assert!((srgb_to_linear(linear_to_srgb(c)) - c).abs() < 1e-6);
        }
    }

    #[test]
    fn png_round_trip_and_bad_files() {
        let mut png = Vec::new();
        let img =
            image::RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8 * 100, y as u8 * 255, 128]));
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = Texture::decode(&png, "mem.png").unwrap();
        assert_eq!((t.width(), t.height()), (3, 2));
        let want = Rgb::new(
            srgb_to_linear(200.0 / 255.0),
            1.0,
            srgb_to_linear(128.0 / 255.0),
        );
        assert!((t.texel(2, 1) - want).abs().max_element() < 1e-6);
        let err = Texture::decode(b"not an image", "junk.png")
            .unwrap_err()
            .to_string();
        assert!(err.contains("junk.png"), "{err}");
        assert!(Texture::new("empty", 0, 4, vec![]).is_err());
        assert!(Texture::new("short", 2, 2, vec![Rgb::ONE; 3]).is_err());
        assert!(Texture::new("nan", 1, 1, vec![Rgb::NAN]).is_err());
    }
}
