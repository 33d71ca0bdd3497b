//! Unit-volume reconstruction kernels and the kernel support (section 2.2, equations 2 and 3).
//!
//! Both kernels are radial, supported on the unit disc and integrate to one
//! over the plane, so `K((x - x_p)/h) / h²` integrates to one over the
//! disc of radius `h` around the photon: `h` in equation 3 is the support
//! radius.

use std::f32::consts::PI;

/// Standard deviation of the Gaussian kernel before truncation, `1/(2√2)`: the per-axis variance 1/8 of Silverman's kernel, so both blur alike.
pub const GAUSSIAN_SIGMA: f32 = 0.353_553_4;

/// A unit-volume 2D kernel on the unit disc (section 2.2, `k` of equation 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kernel {
    /// Silverman's (1986, equation 4.5) second-order kernel `K₂(x) = 3/π (1 - |x|²)²` for `|x| < 1`, the paper's example.
    #[default]
    Silverman,
    /// A Gaussian of standard deviation [`GAUSSIAN_SIGMA`] truncated at `|x| = 1` (2.83 σ, 1.8 % of its mass) and renormalised: `exp(-|x|²/2σ²) / (2πσ² (1 - exp(-1/2σ²)))`.
    Gaussian,
}

impl Kernel {
    /// `K(x)` for `|x|² = r2`; zero outside the unit disc.
    pub fn eval_r2(&self, r2: f32) -> f32 {
        if !(r2 < 1.0) {
            return 0.0;
        }
        match self {
            Self::Silverman => {
                let t = 1.0 - r2;
                3.0 / PI * t * t
            }
            Self::Gaussian => {
                let s2 = GAUSSIAN_SIGMA * GAUSSIAN_SIGMA;
                let norm = 2.0 * PI * s2 * (1.0 - (-0.5 / s2).exp());
                (-0.5 * r2 / s2).exp() / norm
            }
        }
    }

    /// The radius `r ≤ 1` of the disc that holds the kernel mass `m ∈ [0, 1]`: the inverse of `1 − (1 − r²)³` (Silverman's `K₂`) or of `(1 − e^(−r²/2σ²)) / (1 − e^(−1/2σ²))` (the truncated Gaussian).
    pub fn radius_enclosing(&self, m: f32) -> f32 {
        let m = m.clamp(0.0, 1.0);
        let r2 = match self {
            Self::Silverman => 1.0 - (1.0 - m).cbrt(),
            Self::Gaussian => {
                let s2 = GAUSSIAN_SIGMA * GAUSSIAN_SIGMA;
                -2.0 * s2 * (1.0 - m * (1.0 - (-0.5 / s2).exp())).ln()
            }
        };
        r2.clamp(0.0, 1.0).sqrt()
    }

    /// `K(x)` at a 2D offset already divided by the support `h`.
    pub fn eval(&self, x: glam::Vec2) -> f32 {
        self.eval_r2(x.length_squared())
    }

    /// The kernel scaled to support radius `h`: `K(d/h) / h²` for a squared distance `d2` (the 2D normalisation of equation 2; module documentation).
    pub fn scaled(&self, d2: f32, h: f32) -> f32 {
        if !(h > 0.0) {
            return 0.0;
        }
        self.eval_r2(d2 / (h * h)) / (h * h)
    }

    /// A `size × size` regular sampling of the kernel over `[-1, 1]²` at texel centres, row-major: the kernel texture of section 3.2 (64 × 64 in the paper).
    pub fn texture(&self, size: usize) -> Vec<f32> {
        let mut out = Vec::with_capacity(size * size);
        for j in 0..size {
            for i in 0..size {
                let x = (i as f32 + 0.5) / size as f32 * 2.0 - 1.0;
                let y = (j as f32 + 0.5) / size as f32 * 2.0 - 1.0;
                out.push(self.eval_r2(x * x + y * y));
            }
        }
        out
    }
}

/// The kernel support `h = C √(A / n)` of a surface of area `A` with `n` hit points (equation 3); zero when `n = 0` or the inputs are not positive and finite.
pub fn kernel_support(c: f32, area: f32, n: usize) -> f32 {
    if n == 0 || !(c > 0.0) || !(area > 0.0) || !c.is_finite() || !area.is_finite() {
        return 0.0;
    }
    c * (area / n as f32).sqrt()
}

/// The kernel support `h = c √A n^(-1/6)` of a surface of area `A` with `n` hit points: the rate `h ∝ n^(-1/(d+4))`, `d = 2`, of the bandwidth that minimises the mean integrated squared error (Silverman 1986, the paper's reference 13, section 4.3.1 and equation 4.14); zero when `n = 0` or the inputs are not positive and finite.
///
/// Equation 3 keeps the expected number of photons under a kernel fixed
/// (`π C²` on a uniformly lit surface), so the estimate's variance does not
/// fall as photons are added; at this rate the count grows as `n^(2/3)` and
/// both the variance (`∝ 1/(n h²)`) and the squared bias (`∝ h⁴`) fall as
/// `n^(-2/3)`. `c = C n₀^(-1/3)` gives equation 3's support at `n₀` hits.
pub fn kernel_support_silverman(c: f32, area: f32, n: usize) -> f32 {
    if n == 0 || !(c > 0.0) || !(area > 0.0) || !c.is_finite() || !area.is_finite() {
        return 0.0;
    }
    c * area.sqrt() * (n as f32).powf(-1.0 / 6.0)
}

/// The splat triangle of section 3.2 (figure 1) in kernel units (multiply by
/// `h` along two orthonormal in-plane axes): right angle at `(-1, -1)`, legs
/// of `2 + √2` along the axes, hypotenuse `x + y = √2`. Its three sides touch
/// the unit support disc, so it encloses the kernel with the least area of
/// any right isosceles triangle aligned with the kernel texture
/// (`(2 + √2)²/2 ≈ 5.83 h²`).
///
/// The figure is missing from our copy of the paper; its text gives
/// `g = (1/2 + √2) h`, which cannot be the side of a triangle enclosing a
/// disc of radius `h` (any such side is at least `2√3 h`), so `g` must
/// measure something in the figure we cannot see. The GPU pass
/// (`lustre-mpr`'s `splat.wgsl`) uses these corners.
pub fn splat_triangle() -> [glam::Vec2; 3] {
    let far = 1.0 + std::f32::consts::SQRT_2;
    [
        glam::Vec2::new(-1.0, -1.0),
        glam::Vec2::new(far, -1.0),
        glam::Vec2::new(-1.0, far),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Silverman's rate meets equation 3 at `n₀` hits with `c = C n₀^(-1/3)`, and the photons expected under the kernel, `π h² n / A`, grow as `n^(2/3)` (64× the hits, 16× the photons under a kernel) where equation 3 keeps `π C²`.
    #[test]
    fn silverman_support_keeps_more_photons_under_the_kernel_as_n_grows() {
        let (c, area, n0) = (16.0f32, 4.0f32, 30_000usize);
        let s = c * (n0 as f32).powf(-1.0 / 3.0);
        let h0 = kernel_support_silverman(s, area, n0);
        assert!((h0 - kernel_support(c, area, n0)).abs() < 1e-5 * h0);
        let under = |h: f32, n: usize| PI * h * h * n as f32 / area;
        let n1 = 64 * n0;
        let ratio = under(kernel_support_silverman(s, area, n1), n1) / under(h0, n0);
        assert!((ratio - 16.0).abs() < 1e-3, "{ratio}");
        let fixed = under(kernel_support(c, area, n1), n1);
        assert!((fixed - PI * c * c).abs() < 1e-2 * fixed);
        assert_eq!(kernel_support_silverman(s, area, 0), 0.0);
        assert_eq!(kernel_support_silverman(f32::NAN, area, n0), 0.0);
    }

    /// The disc of radius `radius_enclosing(m)` holds mass `m`, by a midpoint sum of `K` over rings.
    #[test]
    fn radius_enclosing_inverts_the_radial_mass() {
        for kernel in [Kernel::Silverman, Kernel::Gaussian] {
            for m in [0.1f32, 0.5, 0.9, 1.0] {
                let r = kernel.radius_enclosing(m) as f64;
                let n = 10_000;
                let mass: f64 = (0..n)
                    .map(|i| {
                        let s = (i as f64 + 0.5) / n as f64 * r;
                        kernel.eval_r2((s * s) as f32) as f64 * 2.0 * std::f64::consts::PI * s * r
                            / n as f64
                    })
                    .sum();
                assert!((mass - m as f64).abs() < 1e-4, "{kernel:?} {m}: {mass}");
            }
        }
    }

    #[test]
    fn the_splat_triangle_touches_the_support_disc_on_all_three_sides() {
        let [a, b, c] = splat_triangle();
        // Distance from the origin to the line through p and q, and the side's orientation.
        let distance = |p: glam::Vec2, q: glam::Vec2| {
            let d = q - p;
            (d.x * p.y - d.y * p.x).abs() / d.length()
        };
        for (p, q) in [(a, b), (b, c), (c, a)] {
            assert!((distance(p, q) - 1.0).abs() < 1e-6, "{p} {q}");
        }
        // The origin is inside: the disc is enclosed, not just tangent from outside.
        let cross = |p: glam::Vec2, q: glam::Vec2, r: glam::Vec2| (q - p).perp_dot(r - p);
        let o = glam::Vec2::ZERO;
        assert!(cross(a, b, o) > 0.0 && cross(b, c, o) > 0.0 && cross(c, a, o) > 0.0);
        let area = 0.5 * (b - a).perp_dot(c - a);
        assert!((area - (2.0 + std::f32::consts::SQRT_2).powi(2) / 2.0).abs() < 1e-5);
    }
}
