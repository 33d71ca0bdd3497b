//! "How it is reflected": the mirror image M convolved with the kernel texture K and modulated by the reflectance R, the view-dependent term `(M * K) R` of equation 2 (Bastos et al. 1999, sections 8.2.1 and 8.2.2).
//!
//! **Solid-angle integration, `M * K`.** K ([`KernelTexture`], lustre-brdf)
//! samples `D G` over the angular offset φ from the mirror direction,
//! normalised to unit sum, out to `φmax`. A reflected ray leaving the
//! reflector at an angle φ from the mirror direction reaches geometry at
//! reflected distance `d` displaced by `d tan φ`, seen from the eye at
//! distance `e + d` (`e` from the eye to the reflector), so `φmax` spans
//! `r = fy d tan φmax / (e + d)` pixels for a view of focal length `fy`
//! pixels (lustre-brdf's `KernelTexture::image_size` is the same for a
//! camera's field of view: `2 fy = H / tan(fov/2)`). The paper's kernel is
//! space-invariant, which "assumes that reflected points are at a constant
//! distance from the reflector" (section 9): [`kernel_radius`] takes the
//! mean of `d/(e + d)` over the pixels M covers. The kernel is resampled
//! at the pixel offsets within `r` (bilinearly from K's texels at
//! `φ = offset/r · φmax`) and each output pixel is the weighted mean of the
//! covered pixels under it: the convolution is confined to the stencilled
//! region, so its edge is not darkened by what lies outside it. A radius
//! below half a pixel leaves M as it is (a mirror).
//!
//! **Reflectance modulation, `R`.** In the mirror configuration of a pixel
//! `N·L = N·V = cos θ`, the cosine between the reflector's normal and the
//! pixel's ray, and R is `F(cos θ)/(π cos² θ)` (equation 4's second
//! factor), looked up in the flipped 1D table of section 9
//! ([`FlippedRadialReflectance`]) as the GPU will, or evaluated exactly.
//!
//! **Magnitude.** With K normalised to unit sum, `(M * K) R` of a uniform
//! M = L0 is `L0 F/(π cos² θ)`, which grows without bound towards grazing
//! angles while a microfacet lobe's reflected radiance stays below `L0`:
//! the paper's equation 4 keeps Cook and Torrance's 1981 denominator and
//! leaves the magnitude to `ks`. How `ks` and the kernel's normalisation
//! combine is for the composed frame to settle against the path-traced
//! reference; this module computes the paper's terms as they stand.

use glam::Vec2;
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::reflectance_modulation::FlippedRadialReflectance;
use lustre_geometry::{Plane, Rgb};

use crate::reprojection::ReflectedImage;
use crate::view::PinholeView;

/// The kernel radius `r = fy tan φmax · mean(d/(e + d))` in pixels for M of `image` seen by `view` from a reflector in `plane` (module documentation); zero when M covers nothing.
pub fn kernel_radius(
    image: &ReflectedImage,
    view: &PinholeView,
    plane: &Plane,
    half_angle: f32,
) -> f32 {
    view.focal.y * half_angle.tan() * mean_depth_ratio(image, view, plane)
}

/// The mean of [`depth_ratio`] `d/(e + d)` over the pixels M covers; zero when it covers none.
pub fn mean_depth_ratio(image: &ReflectedImage, view: &PinholeView, plane: &Plane) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for y in 0..image.height {
        for x in 0..image.width {
            if let Some(ratio) = depth_ratio(image, view, plane, x, y) {
                sum += f64::from(ratio);
                n += 1;
            }
        }
    }
    if n == 0 {
        return 0.0;
    }
    (sum / n as f64) as f32
}

/// `d/(e + d)` at pixel `(x, y)`: M's depth `z = e + d` along the view axis over the reflector's depth `e` there; `None` where M is uncovered or the ray misses the reflector's plane.
pub fn depth_ratio(
    image: &ReflectedImage,
    view: &PinholeView,
    plane: &Plane,
    x: u32,
    y: u32,
) -> Option<f32> {
    let z = image.depth[(y * image.width + x) as usize];
    if !z.is_finite() {
        return None;
    }
    // Depth of the reflector along the view axis at this pixel.
    let d = view.direction(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
    let denom = d.dot(plane.normal);
    if denom.abs() < 1e-6 {
        return None;
    }
    let t = -plane.signed_distance(view.eye) / denom;
    let e = t * d.dot(view.forward);
    if !(e > 0.0) || z < e {
        return None;
    }
    Some((z - e) / z)
}

/// K's bilinear weight at `(u, v)` in units of its half-width (centres span (-1, 1)); zero beyond.
fn kernel_lookup(kernel: &KernelTexture, u: f32, v: f32) -> f32 {
    let n = kernel.size as f32;
    let (x, y) = ((u + 1.0) * 0.5 * n - 0.5, (v + 1.0) * 0.5 * n - 0.5);
    if x < -0.5 || y < -0.5 || x > n - 0.5 || y > n - 0.5 {
        return 0.0;
    }
    let (x, y) = (x.clamp(0.0, n - 1.0), y.clamp(0.0, n - 1.0));
    let (i, j) = (x.floor() as usize, y.floor() as usize);
    let (i1, j1) = ((i + 1).min(kernel.size - 1), (j + 1).min(kernel.size - 1));
    let (fx, fy) = (x - i as f32, y - j as f32);
    kernel.weight(i, j) * (1.0 - fx) * (1.0 - fy)
        + kernel.weight(i1, j) * fx * (1.0 - fy)
        + kernel.weight(i, j1) * (1.0 - fx) * fy
        + kernel.weight(i1, j1) * fx * fy
}

/// The most pixels a depth-varying kernel reaches from its centre (a cap on the gather's cost).
pub const MAX_KERNEL_REACH: i32 = 48;

/// `M * K` with the kernel sized per pixel by its own depth, section 9's
/// "more accurate method" in the limit of one depth layer per pixel: pixel
/// `p` gathers with radius `r(p) = fy tan φmax d/(e + d)` at its own
/// reflected point ([`depth_ratio`]), so geometry that touches the
/// reflector stays sharp and distant geometry blurs, as a glossy lobe
/// does; uncovered pixels of the domain use `mean_ratio` (the
/// space-invariant kernel's). The domain and weights are
/// [`convolve_in`]'s; the reach is capped at [`MAX_KERNEL_REACH`] pixels.
pub fn convolve_by_depth(
    image: &ReflectedImage,
    mask: Option<&[bool]>,
    kernel: &KernelTexture,
    view: &PinholeView,
    plane: &Plane,
    mean_ratio: f32,
) -> ReflectedImage {
    let (w, h) = (image.width as i32, image.height as i32);
    let scale = view.focal.y * kernel.half_angle.tan();
    let mut out = image.clone();
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            if !in_domain(image, mask, k) {
                continue;
            }
            let ratio = depth_ratio(image, view, plane, x as u32, y as u32).unwrap_or(mean_ratio);
            let radius = scale * ratio;
            if !(radius >= 0.5) {
                if !image.depth[k].is_finite() {
                    out.radiance[k] = Rgb::ZERO;
                }
                continue;
            }
            let reach = (radius.ceil() as i32).min(MAX_KERNEL_REACH);
            let taps = (-reach..=reach).flat_map(|dy| {
                (-reach..=reach).map(move |dx| {
                    (
                        dx,
                        dy,
                        kernel_lookup(kernel, dx as f32 / radius, dy as f32 / radius),
                    )
                })
            });
            out.radiance[k] = weighted_mean(image, mask, x, y, taps);
        }
    }
    out
}

/// K resampled at the integer pixel offsets within `radius` pixels: `(dx, dy, weight)` with weights summing to one; the single offset (0, 0) for a radius under half a pixel.
pub fn pixel_kernel(kernel: &KernelTexture, radius: f32) -> Vec<(i32, i32, f32)> {
    if !(radius >= 0.5) {
        return vec![(0, 0, 1.0)];
    }
    let reach = radius.ceil() as i32;
    // Offset o pixels is o/r in K's half-widths.
    let mut taps = Vec::new();
    for dy in -reach..=reach {
        for dx in -reach..=reach {
            let w = kernel_lookup(kernel, dx as f32 / radius, dy as f32 / radius);
            if w > 0.0 {
                taps.push((dx, dy, w));
            }
        }
    }
    let total: f32 = taps.iter().map(|t| t.2).sum();
    if !(total > 0.0) {
        return vec![(0, 0, 1.0)];
    }
    for t in &mut taps {
        t.2 /= total;
    }
    taps
}

/// `M * K`: each covered pixel the weighted mean of the covered pixels under the resampled kernel (module documentation); uncovered pixels stay empty.
pub fn convolve(image: &ReflectedImage, taps: &[(i32, i32, f32)]) -> ReflectedImage {
    convolve_in(image, None, taps)
}

/// The mean of M under `taps` `(dx, dy, weight)` about pixel `(x, y)`, weighted over the pixels M covers and the void ones (black; [`convolve_in`]); zero where none is under a positive weight.
fn weighted_mean(
    image: &ReflectedImage,
    mask: Option<&[bool]>,
    x: i32,
    y: i32,
    taps: impl Iterator<Item = (i32, i32, f32)>,
) -> Rgb {
    let (w, h) = (image.width as i32, image.height as i32);
    let (mut sum, mut weight) = (Rgb::ZERO, 0.0f32);
    for (dx, dy, t) in taps {
        let (sx, sy) = (x + dx, y + dy);
        if !(t > 0.0) || sx < 0 || sy < 0 || sx >= w || sy >= h {
            continue;
        }
        let s = (sy * w + sx) as usize;
        if image.depth[s].is_finite() {
            sum += image.radiance[s] * t;
            weight += t;
        } else if is_void(image, mask, s) {
            weight += t;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        Rgb::ZERO
    }
}

/// Whether pixel `k` gets a value: covered by M, or inside the reflector's `mask`.
fn in_domain(image: &ReflectedImage, mask: Option<&[bool]>, k: usize) -> bool {
    image.depth[k].is_finite() || mask.is_some_and(|m| m[k])
}

/// Whether pixel `k` is void: inside the reflector's `mask`, uncovered by M and by its eight neighbours. An uncovered pixel beside a covered one is a crack between reprojected points (a point drawn a pixel too small), left out of the weights; a pixel amid uncovered ones is where the mirrored ray left the scene, black.
pub fn is_void(image: &ReflectedImage, mask: Option<&[bool]>, k: usize) -> bool {
    let Some(mask) = mask else {
        return false;
    };
    if !mask[k] || image.depth[k].is_finite() {
        return false;
    }
    let (w, h) = (image.width as i64, image.height as i64);
    let (x, y) = (k as i64 % w, k as i64 / w);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (sx, sy) = (x + dx, y + dy);
            if sx >= 0
                && sy >= 0
                && sx < w
                && sy < h
                && image.depth[(sy * w + sx) as usize].is_finite()
            {
                return false;
            }
        }
    }
    true
}

/// `M * K` at the pixels M covers and those of the reflector's `mask` (row-major, true where the reflector is seen), each the weighted mean over the pixels M covers and the void pixels ([`is_void`]): where the mirrored ray leaves the scene M is black, and the glossy lobe blurs the scene's edge into the void as into any dark surface; other pixels, cracks and those outside the reflector, stay out of the weights, so neither the reflector's own silhouette nor a crack darkens it, and a crack takes the mean of its neighbours. Pixels outside both stay empty.
pub fn convolve_in(
    image: &ReflectedImage,
    mask: Option<&[bool]>,
    taps: &[(i32, i32, f32)],
) -> ReflectedImage {
    let (w, h) = (image.width as i32, image.height as i32);
    let mut out = image.clone();
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            if !in_domain(image, mask, k) {
                continue;
            }
            out.radiance[k] = weighted_mean(image, mask, x, y, taps.iter().copied());
        }
    }
    out
}

/// `cos θ` of pixel `(x, y)`: the cosine between the reflector's normal and the pixel's ray (`N·V` of the mirror configuration).
pub fn pixel_cos_theta(view: &PinholeView, plane: &Plane, x: u32, y: u32) -> f32 {
    view.direction(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
        .dot(plane.normal)
        .abs()
}

/// `(M * K) R`: `blurred` modulated per pixel by the flipped table at the pixel's `cos θ` (section 8.2.2); uncovered pixels are zero.
pub fn modulate(
    blurred: &ReflectedImage,
    view: &PinholeView,
    plane: &Plane,
    table: &FlippedRadialReflectance,
) -> Vec<Rgb> {
    modulate_in(blurred, None, view, plane, table)
}

/// [`modulate`] over the domain of [`convolve_in`]: the pixels M covers and those of `mask`.
pub fn modulate_in(
    blurred: &ReflectedImage,
    mask: Option<&[bool]>,
    view: &PinholeView,
    plane: &Plane,
    table: &FlippedRadialReflectance,
) -> Vec<Rgb> {
    let mut out = vec![Rgb::ZERO; blurred.radiance.len()];
    for y in 0..blurred.height {
        for x in 0..blurred.width {
            let k = (y * blurred.width + x) as usize;
            if in_domain(blurred, mask, k) {
                out[k] = blurred.radiance[k] * table.eval(pixel_cos_theta(view, plane, x, y));
            }
        }
    }
    out
}
