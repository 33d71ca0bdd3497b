//! The reflected image's resolution chosen from the glossiness (Bastos et
//! al. 1999, section 2: "mirror-like surfaces require high-resolution
//! images and narrow convolution kernels, while nearly diffuse surfaces
//! require low-resolution images and wide convolution kernels. This is a
//! material property"; section 5 names it among the contributions).
//!
//! A kernel whose support `φmax` spans `r = fy tan φmax · d/(e + d)`
//! pixels of the frame ([`crate::glossy::kernel_radius`]) needs no finer M
//! than one whose pixels are `scale = ⌊r / REFLECTED_KERNEL_RADIUS⌋` frame
//! pixels wide: there the kernel still spans [`REFLECTED_KERNEL_RADIUS`]
//! pixels or more, and M, the convolution and the modulation cost `scale²`
//! times less. The paper derives the resolution from the material alone,
//! the bound `d/(e + d) → 1` (reflected geometry far beyond the reflector);
//! with the scene near the reflector (glosbox at 128²: a mean `d/(e + d)`
//! of 0.14 on the floor, 0.1 to 0.35 on the gold box's faces) that bound
//! makes M three to ten times coarser than its blur and the reflection
//! blocky, so the caller passes the kernel's radius with the depth ratio
//! of the reflector's last M (mpr's `ibr`). With a target of 4 pixels
//! glosbox's relMSE rose from 0.00311 to 0.00491 (the gold box's void
//! filled in by points a coarse pixel wide); with 8 it is 0.00261.
//!
//! The reflector's pixels of the coarse grid are the fine mask sampled at
//! each coarse pixel's centre pixel ([`coarse_mask`]), and the blend reads
//! the coarse term at each fine pixel bilinearly over the coarse pixels
//! that hold a value ([`upsample`]), so the reflector's silhouette stays
//! the frame's own.

use lustre_geometry::Rgb;

/// The kernel's largest radius, in M's pixels, that the coarsened M keeps: `φmax` spans at least this many.
pub const REFLECTED_KERNEL_RADIUS: f32 = 8.0;

/// The coarsest M: at most this many frame pixels per M pixel along each axis.
pub const MAX_REFLECTED_SCALE: u32 = 16;

/// How many frame pixels wide a pixel of M is for a kernel whose support spans `radius` frame pixels (module documentation): `⌊radius / REFLECTED_KERNEL_RADIUS⌋` within `1..=MAX_REFLECTED_SCALE`; 1 for a mirror.
pub fn reflected_scale(radius: f32) -> u32 {
    if !(radius.is_finite() && radius > 0.0) {
        return 1;
    }
    ((radius / REFLECTED_KERNEL_RADIUS).floor() as u32).clamp(1, MAX_REFLECTED_SCALE)
}

/// The fine pixel a coarse pixel `(x, y)` of a grid `scale` times coarser samples: its centre pixel, clamped to the fine `width × height` image.
pub fn centre_pixel(x: u32, y: u32, scale: u32, width: u32, height: u32) -> (u32, u32) {
    (
        (x * scale + scale / 2).min(width - 1),
        (y * scale + scale / 2).min(height - 1),
    )
}

/// The reflector's mask (row-major, true where the reflector is seen) on the grid `scale` times coarser than its `width × height`: each coarse pixel takes its [`centre_pixel`]'s value.
pub fn coarse_mask(mask: &[bool], width: u32, height: u32, scale: u32) -> Vec<bool> {
    let s = scale.max(1);
    let (cw, ch) = (width.div_ceil(s), height.div_ceil(s));
    let mut out = Vec::with_capacity((cw * ch) as usize);
    for y in 0..ch {
        for x in 0..cw {
            let (fx, fy) = centre_pixel(x, y, s, width, height);
            out.push(mask[(fy * width + fx) as usize]);
        }
    }
    out
}

/// The coarse term (`coarse_width` wide, row-major; `valid` where it holds
/// a value) at fine pixel `(x, y)` of a grid `scale` times finer: bilinear
/// between the four coarse pixels around the fine pixel's centre, each
/// weight kept only where the coarse pixel is valid and the sum
/// renormalised; zero where none of the four is valid.
pub fn upsample(
    term: &[Rgb],
    valid: &[bool],
    coarse_width: u32,
    scale: u32,
    x: u32,
    y: u32,
) -> Rgb {
    let s = scale.max(1);
    if s == 1 {
        let k = (y * coarse_width + x) as usize;
        return if valid[k] { term[k] } else { Rgb::ZERO };
    }
    let coarse_height = (term.len() as u32) / coarse_width;
    // The fine pixel's centre in coarse pixel coordinates, less the half pixel to coarse centres.
    let cx = (x as f32 + 0.5) / s as f32 - 0.5;
    let cy = (y as f32 + 0.5) / s as f32 - 0.5;
    let (x0, y0) = (cx.floor(), cy.floor());
    let (fx, fy) = (cx - x0, cy - y0);
    let (mut sum, mut weight) = (Rgb::ZERO, 0.0f32);
    for (dx, dy, w) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let (sx, sy) = (x0 as i64 + dx, y0 as i64 + dy);
        if sx < 0 || sy < 0 || sx >= coarse_width as i64 || sy >= coarse_height as i64 {
            continue;
        }
        let k = (sy * coarse_width as i64 + sx) as usize;
        if valid[k] && w > 0.0 {
            sum += term[k] * w;
            weight += w;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        Rgb::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_keeps_the_kernel_at_least_the_target_radius_wide() {
        // A mirror-like lobe needs the frame's resolution.
        assert_eq!(reflected_scale(0.5), 1);
        assert_eq!(reflected_scale(0.0), 1);
        assert_eq!(reflected_scale(f32::NAN), 1);
        for radius in [8.0f32, 15.9, 16.0, 63.0, 101.0] {
            let s = reflected_scale(radius);
            let coarse = radius / s as f32;
            assert!(coarse >= REFLECTED_KERNEL_RADIUS, "{radius}: {s} {coarse}");
            assert!(
                coarse < 2.0 * REFLECTED_KERNEL_RADIUS,
                "{radius}: {s} {coarse}"
            );
        }
        assert_eq!(reflected_scale(1e5), MAX_REFLECTED_SCALE);
    }

    #[test]
    fn a_valid_constant_term_upsamples_to_itself_and_invalid_pixels_stay_out() {
        let (cw, ch, s) = (5u32, 4u32, 3u32);
        let c = Rgb::new(0.2, 0.4, 0.8);
        let term = vec![c; (cw * ch) as usize];
        let valid = vec![true; term.len()];
        for y in 0..ch * s {
            for x in 0..cw * s {
                let v = upsample(&term, &valid, cw, s, x, y);
                assert!((v - c).abs().max_element() < 1e-6, "{x},{y}: {v:?}");
            }
        }
        // Invalid coarse pixels hold garbage that must not leak in.
        let mut term = term;
        let mut valid = valid;
        for k in 0..cw as usize {
            term[k] = Rgb::new(100.0, 100.0, 100.0);
            valid[k] = false;
        }
        for x in 0..cw * s {
            let v = upsample(&term, &valid, cw, s, x, s + 1);
            assert!((v - c).abs().max_element() < 1e-6, "{x}: {v:?}");
        }
        // Fine pixels around only invalid coarse ones get nothing.
        assert_eq!(upsample(&term, &valid, cw, s, 4, 0), Rgb::ZERO);
        // Between two valid coarse centres the value is the linear blend.
        let mut ramp = vec![Rgb::ZERO; (cw * ch) as usize];
        for (k, r) in ramp.iter_mut().enumerate() {
            *r = Rgb::splat((k as u32 % cw) as f32);
        }
        let all = vec![true; ramp.len()];
        // Fine pixel 4's centre (4.5) is coarse coordinate 1.75: three quarters from coarse 1 to 2.
        let v = upsample(&ramp, &all, cw, 2, 4, 2);
        assert!((v.x - 1.75).abs() < 1e-6, "{v:?}");
    }

    #[test]
    fn the_coarse_mask_samples_each_coarse_pixels_centre() {
        let (w, h) = (7u32, 5u32);
        let mask: Vec<bool> = (0..w * h).map(|k| k % w >= 3).collect();
        let coarse = coarse_mask(&mask, w, h, 2);
        assert_eq!(coarse.len(), 4 * 3);
        // Coarse column x samples fine column min(2x + 1, 6): 1, 3, 5, 6.
        for y in 0..3 {
            assert_eq!(
                &coarse[y * 4..y * 4 + 4],
                &[false, true, true, true],
                "row {y}"
            );
        }
        assert_eq!(centre_pixel(3, 2, 2, w, h), (6, 4));
        assert_eq!(coarse_mask(&mask, w, h, 1), mask);
    }
}
