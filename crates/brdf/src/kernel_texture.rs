//! The kernel texture K of Bastos et al.'s BRDF decomposition: `D G` sampled over the angular offset from the mirror direction (R. Bastos, K. Hoff, W. Wynn and A. Lastra, "Increased photorealism for interactive architectural walkthroughs", I3D 1999, section 8.2.1, equation 4).
//!
//! Equation 4 splits Cook-Torrance's specular term into `{D G}` and
//! `{F / (π (N·L)(N·V))}`. K is the first factor, sampled as a function of
//! the reflected direction's angular offset `φ = (φx, φy)` from the mirror
//! direction at normal viewing (`wo = +Z`, the space-invariant kernel the
//! paper convolves with): texel centre → `φ` → `wi` at polar angle `|φ|` →
//! `h = normalize(wi + wo)` (so θh = |φ|/2) → weight `D(h) G(wi, wo, h)`,
//! then normalised to unit sum so the convolution preserves energy.
//!
//! **Support.** Beckmann slopes have per-axis variance α²/2; a reflected
//! direction moves by twice the facet tilt, so the reflected angle has
//! per-axis variance `σφ² = 4 · α²/2 = 2α²` (small α; the same factor two as
//! in [`crate::scatter_distribution`]). The kernel spans `±4 σφ = ±4√2 α` by
//! default, which loses 0.1 % of its second moment.
//!
//! **Image-space size.** The convolution runs on the reflected image.
//! A reflected ray leaving the reflector at angle φ from the mirror
//! direction reaches geometry at the reflected distance `d` displaced by
//! `d tan φ`; the virtual camera sees that geometry at distance `e + d`
//! (`e` the eye-to-reflector distance), where one pixel of an image `H`
//! pixels high with vertical field of view `fov` spans
//! `2 (e + d) tan(fov/2) / H`. An angular offset φ therefore spans
//! `p(φ) = H d tan φ / (2 (e + d) tan(fov/2))` pixels, and the kernel's
//! full width is `2 p(φmax)` pixels ([`KernelTexture::image_size`]). For
//! distant reflections (`d ≫ e`) this tends to `H tan φmax / tan(fov/2)`;
//! for geometry on the reflector (`d → 0`) to zero (no blur), the paper's
//! remark that nearer points should be blurred less (section 9).

use glam::Vec3;

use crate::error::{BrdfError, Result};
use crate::microfacet::{Distribution, Shadowing};
use crate::texture::TextureRgba32F;

/// The kernel texture K: `size × size` weights of `D G` over the angular offset from the mirror direction, summing to one (Bastos et al. 1999, section 8.2.1).
#[derive(Debug, Clone, PartialEq)]
pub struct KernelTexture {
    /// Texels per side N.
    pub size: usize,
    /// Angular half-width φmax of the kernel, radians: texel centres span (-φmax, φmax).
    pub half_angle: f32,
    /// `size × size` weights, row-major (row = φy), summing to one.
    pub weights: Vec<f32>,
}

/// Default kernel half-width in reflected-angle standard deviations (4σ: 0.1 % of the second moment lost).
pub const KERNEL_SUPPORT_SIGMAS: f32 = 4.0;

/// Per-axis standard deviation `√2 α` of the reflected direction's angle for Beckmann roughness α at normal incidence (small α; derived in the module documentation).
pub fn reflected_angle_sigma(alpha: f32) -> f32 {
    std::f32::consts::SQRT_2 * alpha
}

impl KernelTexture {
    /// K for a microfacet distribution and shadowing term, `size` texels per side, spanning ±4√2 α (Bastos et al. 1999, section 8.2.1: "a Gaussian or a Beckman distribution is sampled in order to create the kernel").
    pub fn new(distribution: &Distribution, shadowing: Shadowing, size: usize) -> Result<Self> {
        let half = (KERNEL_SUPPORT_SIGMAS * reflected_angle_sigma(distribution.alpha()))
            .min(std::f32::consts::FRAC_PI_2);
        Self::with_half_angle(distribution, shadowing, size, half)
    }

    /// K over an explicit angular half-width φmax in (0, π/2].
    pub fn with_half_angle(
        distribution: &Distribution,
        shadowing: Shadowing,
        size: usize,
        half_angle: f32,
    ) -> Result<Self> {
        if !(1..=4096).contains(&size) {
            return Err(BrdfError::OutOfRange {
                model: "kernel-texture".into(),
                param: "size".into(),
                value: size as f32,
                expected: "1 to 4096".into(),
            });
        }
        if !(half_angle > 0.0 && half_angle <= std::f32::consts::FRAC_PI_2) {
            return Err(BrdfError::OutOfRange {
                model: "kernel-texture".into(),
                param: "half_angle".into(),
                value: half_angle,
                expected: "0 to π/2 radians".into(),
            });
        }
        let mut weights = Vec::with_capacity(size * size);
        let wo = Vec3::Z;
        for j in 0..size {
            for i in 0..size {
                let (px, py) = (
                    texel_offset(i, size) * half_angle,
                    texel_offset(j, size) * half_angle,
                );
                let phi = (px * px + py * py).sqrt();
                let w = if phi >= std::f32::consts::FRAC_PI_2 {
                    0.0
                } else {
                    let (s, c) = phi.sin_cos();
                    let wi = if phi > 0.0 {
                        Vec3::new(s * px / phi, s * py / phi, c)
                    } else {
                        Vec3::Z
                    };
                    let h = (wi + wo).normalize();
                    distribution.d(h) * shadowing.g(distribution, wi, wo, h)
                };
                weights.push(if w.is_finite() { w.max(0.0) } else { 0.0 });
            }
        }
        let sum: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        if !(sum > 0.0) {
            return Err(BrdfError::OutOfRange {
                model: "kernel-texture".into(),
                param: "half_angle".into(),
                value: half_angle,
                expected: "a support where D G is not zero everywhere".into(),
            });
        }
        for w in &mut weights {
            *w = (f64::from(*w) / sum) as f32;
        }
        Ok(Self {
            size,
            half_angle,
            weights,
        })
    }

    /// The angular offset (φx or φy, radians) of texel index `i`'s centre.
    pub fn texel_angle(&self, i: usize) -> f32 {
        texel_offset(i, self.size) * self.half_angle
    }

    /// The weight at column `i`, row `j`.
    pub fn weight(&self, i: usize, j: usize) -> f32 {
        self.weights[j * self.size + i]
    }

    /// Full width in pixels of the kernel in the reflected image: `2 H d tan φmax / (2 (e + d) tan(fov/2))` for eye-to-reflector distance `e`, reflected distance `d`, vertical field of view `fov_y` (radians) and image height `H` (derived in the module documentation).
    pub fn image_size(
        &self,
        eye_distance: f32,
        reflected_distance: f32,
        fov_y: f32,
        image_height: u32,
    ) -> Result<f32> {
        let bad = |param: &str, value: f32, expected: &str| BrdfError::OutOfRange {
            model: "kernel-texture".into(),
            param: param.into(),
            value,
            expected: expected.into(),
        };
        if !(eye_distance.is_finite() && eye_distance >= 0.0) {
            return Err(bad("eye_distance", eye_distance, "finite, at least 0"));
        }
        if !(reflected_distance.is_finite() && reflected_distance >= 0.0) {
            return Err(bad(
                "reflected_distance",
                reflected_distance,
                "finite, at least 0",
            ));
        }
        if eye_distance + reflected_distance <= 0.0 {
            return Err(bad("eye_distance", eye_distance, "e + d positive"));
        }
        if !(fov_y > 0.0 && fov_y < std::f32::consts::PI) {
            return Err(bad("fov_y", fov_y, "0 to π radians"));
        }
        let h = image_height as f32;
        Ok(h * reflected_distance * self.half_angle.tan()
            / ((eye_distance + reflected_distance) * (0.5 * fov_y).tan()))
    }

    /// K as an RGBA texture: RGB = the weight, A = 1.
    pub fn to_texture(&self) -> TextureRgba32F {
        let n = self.size as u32;
        let mut t = TextureRgba32F::zeros(n, n);
        for j in 0..self.size {
            for i in 0..self.size {
                let w = self.weight(i, j);
                t.set_texel(i as u32, j as u32, [w, w, w, 1.0]);
            }
        }
        t
    }
}

/// Centre of texel `i` of `n` in (-1, 1): `(2i + 1 - n) / n`, exact under `i → n - 1 - i` (negation).
fn texel_offset(i: usize, n: usize) -> f32 {
    (2.0 * i as f32 + 1.0 - n as f32) / n as f32
}
