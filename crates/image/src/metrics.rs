//! Image error metrics: relative MSE, MSE, channel means and FLIP.
//!
//! `t` is the test image and `r` the reference; sums run over the `N`
//! pixels and the three channels `c`.

use crate::{Image, ImageError, to_srgb8};

/// The `ε` of [`relative_mse`] used by Rousselle, Knaus & Zwicker (2011).
pub const RELATIVE_MSE_EPSILON: f64 = 0.01;

/// FLIP's default observer: pixels per degree of visual angle (a 0.7 m wide
/// 4K monitor seen from 0.7 m).
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Relative mean squared error (Rousselle, Knaus & Zwicker, "Adaptive
/// Sampling and Reconstruction using Greedy Error Minimization", 2011):
/// `relMSE = 1/(3N) Σ_pixels Σ_c (t_c − r_c)² / (r_c² + ε)`, with `ε`
/// (usually [`RELATIVE_MSE_EPSILON`]) keeping dark pixels from dominating.
pub fn relative_mse(test: &Image, reference: &Image, epsilon: f64) -> Result<f64, ImageError> {
    test.check_same_size(reference)?;
    let sum: f64 = pixel_pairs(test, reference)
        .map(|(t, r)| (t - r).powi(2) / (r * r + epsilon))
        .sum();
    Ok(sum / (3 * test.pixels().len()) as f64)
}

/// Rec. 709 luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of a linear pixel.
pub fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Mean luminance difference relative to the reference's mean luminance, the error of García Hernández et al.'s tables 2.1 and 2.6–2.8 (section 2.5.3): `Σ |Y(t) − Y(r)| / Σ Y(r)`; fails on different sizes or a black reference.
pub fn mean_luminance_difference(test: &Image, reference: &Image) -> Result<f64, ImageError> {
    test.check_same_size(reference)?;
    let (mut diff, mut total) = (0.0f64, 0.0f64);
    for (t, r) in test.pixels().iter().zip(reference.pixels()) {
        let yr = luminance(*r);
        diff += (luminance(*t) - yr).abs();
        total += yr;
    }
    if !(total > 0.0) {
        return Err(ImageError::Undefined(
            "the reference of a mean luminance difference is black".into(),
        ));
    }
    Ok(diff / total)
}

/// Mean squared error per channel: `MSE_c = 1/N Σ_pixels (t_c − r_c)²`.
pub fn mse(test: &Image, reference: &Image) -> Result<[f64; 3], ImageError> {
    test.check_same_size(reference)?;
    let mut sum = [0.0f64; 3];
    for (t, r) in test.pixels().iter().zip(reference.pixels()) {
        for c in 0..3 {
            sum[c] += (f64::from(t[c]) - f64::from(r[c])).powi(2);
        }
    }
    Ok(sum.map(|s| s / test.pixels().len() as f64))
}

/// Mean per channel: `mean_c = 1/N Σ_pixels p_c`.
pub fn mean(image: &Image) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for p in image.pixels() {
        for c in 0..3 {
            sum[c] += f64::from(p[c]);
        }
    }
    sum.map(|s| s / image.pixels().len() as f64)
}

/// Every channel of every pixel of two same-size images, as `(t, r)` in f64.
fn pixel_pairs<'a>(test: &'a Image, reference: &'a Image) -> impl Iterator<Item = (f64, f64)> + 'a {
    test.pixels()
        .iter()
        .zip(reference.pixels())
        .flat_map(|(t, r)| (0..3).map(move |c| (f64::from(t[c]), f64::from(r[c]))))
}

/// The outcome of a FLIP comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct FlipResult {
    /// Columns of `error_map`.
    pub width: u32,
    /// Rows of `error_map`.
    pub height: u32,
    /// Mean FLIP error `1/N Σ_pixels e` (the single number FLIP's authors recommend).
    pub mean: f32,
    /// 95th percentile of the per-pixel error (nearest rank: the `⌈0.95 N⌉`-th smallest).
    pub p95: f32,
    /// 99th percentile of the per-pixel error (nearest rank: the `⌈0.99 N⌉`-th smallest): a local error on an object covering more than 1 % of the image shows here when the mean hides it.
    pub p99: f32,
    /// Largest per-pixel error.
    pub max: f32,
    /// Per-pixel FLIP error `e` in [0, 1], row-major, top row first.
    pub error_map: Vec<f32>,
}

/// The `q`-quantile of ascending, non-empty `sorted` by nearest rank: the
/// `⌈q n⌉`-th smallest value (the smallest for `q n ≤ 1`).
fn nearest_rank(sorted: &[f32], q: f64) -> f32 {
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// LDR-FLIP (Andersson et al., "FLIP: A Difference Evaluator for
/// Alternating Images", 2020) of `test` against `reference`, both tone mapped
/// by [`to_srgb8`] at the same `exposure`, at [`PIXELS_PER_DEGREE`], with
/// NVIDIA's implementation (the `nv-flip` crate).
pub fn flip(test: &Image, reference: &Image, exposure: f32) -> Result<FlipResult, ImageError> {
    test.check_same_size(reference)?;
    let (width, height) = (test.width(), test.height());
    let flip_image = |image: &Image| {
        nv_flip::FlipImageRgb8::with_data(width, height, to_srgb8(image, exposure).as_flattened())
    };
    let error_map =
        nv_flip::flip(flip_image(reference), flip_image(test), PIXELS_PER_DEGREE).to_vec();
    let n = error_map.len();
    let mean = (error_map.iter().map(|&e| f64::from(e)).sum::<f64>() / n as f64) as f32;
    let mut sorted = error_map.clone();
    sorted.sort_by(f32::total_cmp);
    Ok(FlipResult {
        width,
        height,
        mean,
        p95: nearest_rank(&sorted, 0.95),
        p99: nearest_rank(&sorted, 0.99),
        max: sorted[n - 1],
        error_map,
    })
}

/// A FLIP error map (values in [0, 1], `width × height`, row-major) shown
/// with FLIP's magma colour map, for `-difference` images: error `e` maps
/// to entry `round(255 e)` of the 256-entry map.
pub fn difference_image(
    error_map: &[f32],
    width: u32,
    height: u32,
) -> Result<Vec<[u8; 3]>, ImageError> {
    let expected = (width as usize).checked_mul(height as usize).unwrap_or(0);
    if expected == 0 || expected != error_map.len() {
        return Err(ImageError::InvalidSize {
            width,
            height,
            expected,
            actual: error_map.len(),
        });
    }
    let colours = nv_flip::FlipImageFloat::with_data(width, height, error_map)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec();
    Ok(colours
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::ramp;

    fn two_by_one(a: [f32; 3], b: [f32; 3]) -> Image {
        Image::new(2, 1, vec![a, b]).unwrap()
    }

    #[test]
    fn mean_luminance_difference_by_hand() {
        let reference = two_by_one([1.0, 1.0, 1.0], [0.0, 1.0, 0.0]);
        let test = two_by_one([2.0, 1.0, 1.0], [0.0, 0.5, 0.0]);
        // |ΔY| = 0.2126 + 0.5 · 0.7152; ΣY(r) = 1 + 0.7152.
        let expected = (0.2126 + 0.5 * 0.7152) / (1.0 + 0.7152);
        let got = mean_luminance_difference(&test, &reference).unwrap();
        assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
        assert_eq!(
            mean_luminance_difference(&reference, &reference).unwrap(),
            0.0
        );
        let black = two_by_one([0.0; 3], [0.0; 3]);
        assert!(mean_luminance_difference(&test, &black).is_err());
        assert!(mean_luminance_difference(&test, &ramp(3, 1)).is_err());
    }

    #[test]
    fn relative_mse_by_hand() {
        let reference = two_by_one([1.0, 0.0, 2.0], [0.5, 0.5, 0.5]);
        let test = two_by_one([1.5, 0.1, 2.0], [0.5, 0.0, 1.0]);
        // Terms: 0.25/1.01, 0.01/0.01, 0, 0, 0.25/0.26, 0.25/0.26.
        let expected = (0.25 / 1.01 + 1.0 + 0.25 / 0.26 + 0.25 / 0.26) / 6.0;
        let got = relative_mse(&test, &reference, RELATIVE_MSE_EPSILON).unwrap();
        assert!((got - expected).abs() < 1e-7, "{got} vs {expected}");
        assert_eq!(relative_mse(&reference, &reference, 0.01).unwrap(), 0.0);
    }

    #[test]
    fn mse_and_mean_by_hand() {
        let reference = two_by_one([1.0, 0.0, 2.0], [0.5, 0.5, 0.5]);
        let test = two_by_one([1.5, 0.1, 2.0], [0.5, 0.0, 1.0]);
        let m = mse(&test, &reference).unwrap();
        let expected = [0.125, (0.01 + 0.25) / 2.0, 0.125];
        for c in 0..3 {
            assert!((m[c] - expected[c]).abs() < 1e-7, "{m:?}");
        }
        assert_eq!(mean(&reference), [0.75, 0.25, 1.25]);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = Image::filled(2, 2, [0.0; 3]).unwrap();
        let b = Image::filled(2, 3, [0.0; 3]).unwrap();
        for result in [
            relative_mse(&a, &b, 0.01).err(),
            mse(&a, &b).err(),
            flip(&a, &b, 0.0).err(),
        ] {
            assert!(matches!(result, Some(ImageError::SizeMismatch { .. })));
        }
    }

    #[test]
    fn flip_of_identical_images_is_zero() {
        let image = ramp(32, 24);
        let result = flip(&image, &image.clone(), 0.0).unwrap();
        assert_eq!((result.width, result.height), (32, 24));
        assert_eq!(result.error_map.len(), 32 * 24);
        assert!(result.mean.abs() < 1e-6, "{}", result.mean);
        assert!(result.max.abs() < 1e-6, "{}", result.max);
    }

    #[test]
    fn flip_of_very_different_images_is_large() {
        let black = Image::filled(32, 32, [0.0; 3]).unwrap();
        let white = Image::filled(32, 32, [1.0; 3]).unwrap();
        let result = flip(&white, &black, 0.0).unwrap();
        assert!(result.mean > 0.5, "{}", result.mean);
        assert!(result.p95 >= result.mean && result.p99 >= result.p95 && result.max >= result.p99);
        // A 5 % brighter image gives an error well between the two
        // (0.119 with nv-flip 0.1.2).
        let mut brighter = ramp(32, 32);
        for p in brighter.pixels_mut() {
            *p = p.map(|c| c * 1.05);
        }
        let small = flip(&brighter, &ramp(32, 32), 0.0).unwrap();
        assert!(small.mean > 0.01 && small.mean < 0.25, "{}", small.mean);
        // Both images are tone mapped at the given exposure: at -20 stops
        // white quantises to black too.
        assert!(flip(&white, &black, -20.0).unwrap().mean.abs() < 1e-6);
    }

    #[test]
    fn p95_is_the_nearest_rank() {
        let sorted: Vec<f32> = (1..=20).map(|i| i as f32).collect();
        // ⌈0.95 · 20⌉ = 19th smallest.
        assert_eq!(nearest_rank(&sorted, 0.95), 19.0);
        // ⌈0.95 · 21⌉ = 20th of 21.
        let sorted: Vec<f32> = (1..=21).map(|i| i as f32).collect();
        assert_eq!(nearest_rank(&sorted, 0.95), 20.0);
        assert_eq!(nearest_rank(&[3.0], 0.95), 3.0);
        assert_eq!(nearest_rank(&sorted, 0.0), 1.0);
        // ⌈0.99 · 200⌉ = 198th of 200.
        let sorted: Vec<f32> = (1..=200).map(|i| i as f32).collect();
        assert_eq!(nearest_rank(&sorted, 0.99), 198.0);
    }

    #[test]
    fn p99_sees_a_local_error_the_mean_hides() {
        // 1.5 % of the pixels (a 10 × 15 block of 100 × 100) 20 % brighter:
        // mean 0.0072, p95 0.015, p99 0.29 with nv-flip 0.1.2.
        let reference = ramp(100, 100);
        let mut test = reference.clone();
        for y in 40..55 {
            for x in 30..40 {
                let i = (y * 100 + x) as usize;
                test.pixels_mut()[i] = test.pixels()[i].map(|c| 1.2 * c);
            }
        }
        let result = flip(&test, &reference, 0.0).unwrap();
        assert!(result.mean < 0.01, "{}", result.mean);
        assert!(result.p95 < 0.05, "{}", result.p95);
        assert!(result.p99 > 0.1, "{}", result.p99);
    }

    #[test]
    fn difference_image_uses_magma() {
        let colours = difference_image(&[0.0, 1.0], 2, 1).unwrap();
        // Magma starts near black and ends near pale yellow.
        assert!(colours[0].iter().all(|&c| c < 20), "{colours:?}");
        assert!(colours[1][0] > 200 && colours[1][1] > 200, "{colours:?}");
        assert!(difference_image(&[0.0; 3], 2, 1).is_err());
    }
}
