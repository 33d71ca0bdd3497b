//! Bastos et al. 1999, section 8.2: `M * K` and R on the reflected image, against constant images, a single bright pixel, lustre-brdf's kernel size and the exact reflectance.

use glam::{Vec2, Vec3};
use lustre_brdf::Fresnel;
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::microfacet::{Distribution, Shadowing};
use lustre_brdf::reflectance_modulation::{FlippedRadialReflectance, reflectance_modulation};
use lustre_geometry::material::MicrofacetDistribution;
use lustre_geometry::{Camera, Plane, Rgb};
use lustre_ibr::PinholeView;
use lustre_ibr::ReflectedImage;
use lustre_ibr::glossy::{
    convolve, convolve_by_depth, convolve_in, depth_ratio, is_void, kernel_radius, modulate,
    modulate_in, pixel_cos_theta, pixel_kernel,
};

fn kernel(alpha: f32) -> KernelTexture {
    let d = Distribution::new(MicrofacetDistribution::Beckmann, alpha, "test").unwrap();
    KernelTexture::new(&d, Shadowing::Smith, 33).unwrap()
}

fn filled(w: u32, h: u32, c: Rgb) -> ReflectedImage {
    let mut im = ReflectedImage::new(w, h);
    im.radiance.fill(c);
    im.depth.fill(5.0);
    im
}

#[test]
fn convolution_keeps_a_constant_image_and_spreads_a_bright_pixel_as_k() {
    let taps = pixel_kernel(&kernel(0.1), 6.3);
    let total: f32 = taps.iter().map(|t| t.2).sum();
    assert!((total - 1.0).abs() < 1e-5);
    assert!(taps.len() > 50);
    // Symmetric: D G depends on |φ| only.
    for &(dx, dy, w) in &taps {
        let m = taps.iter().find(|t| t.0 == -dx && t.1 == -dy).unwrap();
        assert!((m.2 - w).abs() < 1e-6);
    }
    let c = Rgb::new(0.3, 1.5, 7.0);
    let out = convolve(&filled(40, 30, c), &taps);
    for r in &out.radiance {
        assert!((*r - c).abs().max_element() < 1e-5 * 7.0);
    }
    // A single bright pixel away from the edges: the output around it is K, its sum the pixel's.
    let mut im = filled(40, 30, Rgb::ZERO);
    let (x0, y0) = (20i32, 15i32);
    im.radiance[(y0 * 40 + x0) as usize] = Rgb::ONE;
    let out = convolve(&im, &taps);
    let sum: f32 = out.radiance.iter().map(|r| r.x).sum();
    assert!((sum - 1.0).abs() < 1e-4, "energy {sum}");
    for &(dx, dy, w) in &taps {
        let v = out.radiance[((y0 + dy) * 40 + x0 + dx) as usize].x;
        assert!((v - w).abs() < 1e-6, "({dx}, {dy}): {v} vs {w}");
    }
    // Below half a pixel: a mirror, M unchanged.
    assert_eq!(pixel_kernel(&kernel(0.1), 0.3), vec![(0, 0, 1.0)]);
}

#[test]
fn convolution_stays_inside_the_stencilled_region() {
    // Half the image covered with one colour: the uncovered half neither darkens the edge nor receives light.
    let mut im = filled(30, 20, Rgb::splat(2.0));
    for y in 0..20 {
        for x in 15..30 {
            im.depth[y * 30 + x] = f32::INFINITY;
            im.radiance[y * 30 + x] = Rgb::ZERO;
        }
    }
    let out = convolve(&im, &pixel_kernel(&kernel(0.2), 4.0));
    for y in 0..20 {
        for x in 0..30 {
            let r = out.radiance[y * 30 + x];
            if x < 15 {
                assert!((r - Rgb::splat(2.0)).abs().max_element() < 1e-5);
            } else {
                assert_eq!(r, Rgb::ZERO);
            }
        }
    }
}

#[test]
fn kernel_radius_is_lustre_brdf_kernel_size() {
    // The eye 1.5 m above a floor mirror looking straight down; the mirror image is of a ceiling 2.5 m above the floor: e = 1.5, d = 2.5 at every pixel.
    let (e, d) = (1.5f32, 2.5f32);
    let camera = Camera::look_at(Vec3::new(0.0, e, 0.0), Vec3::ZERO, Vec3::Z, 50.0);
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let view = PinholeView::mirrored(&camera, &plane, 64, 48);
    let mut im = filled(64, 48, Rgb::ONE);
    im.depth.fill(e + d);
    let k = kernel(0.08);
    let r = kernel_radius(&im, &view, &plane, k.half_angle);
    let full = k.image_size(e, d, 50f32.to_radians(), 48).unwrap();
    assert!(
        (2.0 * r - full).abs() < 1e-3 * full,
        "radius {r}, lustre-brdf's width {full}"
    );
}

#[test]
fn modulation_is_equation_4s_reflectance_at_each_pixel() {
    let fresnel = Fresnel::Dielectric { eta: 1.5 };
    let table = FlippedRadialReflectance::new(&fresnel, 256).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.0, 2.5),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        45.0,
    )
    .with_aspect(4.0 / 3.0);
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let (w, h) = (64u32, 48u32);
    let view = PinholeView::mirrored(&camera, &plane, w, h);
    let l0 = Rgb::new(1.0, 2.0, 3.0);
    let out = modulate(&filled(w, h, l0), &view, &plane, &table);
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            // The eye's own primary ray through the pixel: its angle with the floor's normal.
            let ray = camera.primary_ray(Camera::pixel_ndc(x, y, w, h, Vec2::splat(0.5)));
            let cos = -ray.direction.dot(plane.normal);
            if !(cos > 0.0) {
                continue; // the ray misses the floor
            }
            assert!((pixel_cos_theta(&view, &plane, x, y) - cos).abs() < 1e-5);
            if !(cos > 0.17) {
                continue; // above 80° the table's linear filter errs more
            }
            let exact = l0 * reflectance_modulation(&fresnel, cos);
            let got = out[(y * w + x) as usize];
            assert!(
                ((got - exact).abs() / exact).max_element() < 0.01,
                "({x}, {y}): {got} vs {exact}"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000);
}

#[test]
fn a_crack_takes_its_neighbours_mean_and_the_void_is_black() {
    // A constant M over a reflector that covers the whole image, with a
    // one-pixel crack (a row of uncovered pixels amid covered ones) and a
    // void block (uncovered, 12 × 12, where the mirrored rays leave the scene).
    let (w, h) = (40u32, 40u32);
    let c = Rgb::new(1.0, 2.0, 3.0);
    let mut im = filled(w, h, c);
    let mask = vec![true; (w * h) as usize];
    for x in 0..w {
        im.depth[(20 * w + x) as usize] = f32::INFINITY;
        im.radiance[(20 * w + x) as usize] = Rgb::ZERO;
    }
    for y in 2..14 {
        for x in 2..14 {
            im.depth[(y * w + x) as usize] = f32::INFINITY;
            im.radiance[(y * w + x) as usize] = Rgb::ZERO;
        }
    }
    // The crack's pixels have covered neighbours; the void's inner 10 × 10 none.
    assert!(!is_void(&im, Some(&mask), (20 * w + 30) as usize));
    assert!(!is_void(&im, Some(&mask), (2 * w + 5) as usize));
    assert!(is_void(&im, Some(&mask), (3 * w + 5) as usize));
    assert!(!is_void(&im, None, (3 * w + 5) as usize));
    let taps = pixel_kernel(&kernel(0.1), 5.0);
    let out = convolve_in(&im, Some(&mask), &taps);
    // The crack, far from the void: exactly M (the weights skip it, no darkening).
    for x in 25..40 {
        let r = out.radiance[(20 * w + x) as usize];
        assert!((r - c).abs().max_element() < 1e-5, "crack pixel {x}: {r}");
    }
    // Inside the void, farther than the kernel's reach from M: black.
    assert_eq!(out.radiance[(8 * w + 8) as usize], Rgb::ZERO);
    // Beside the void, the lobe picks up black: M times the covered
    // weight over the covered and void weight (the void block's rim, beside
    // covered pixels, counts as cracks and stays out).
    let x = 14u32;
    let weight_in = |lo: i32, hi: i32| -> f32 {
        taps.iter()
            .filter(|&&(dx, dy, _)| {
                let (sx, sy) = (x as i32 + dx, 8 + dy);
                (lo..hi).contains(&sx) && (lo..hi).contains(&sy)
            })
            .map(|t| t.2)
            .sum()
    };
    let (void, block) = (weight_in(3, 13), weight_in(2, 14));
    let covered = 1.0 - block;
    let want = c * (covered / (covered + void));
    let got = out.radiance[(8 * w + x) as usize];
    assert!(void > 0.05, "the void is in reach: {void}");
    assert!(
        (got - want).abs().max_element() < 1e-4 * 3.0,
        "beside the void {got}, want {want}"
    );
    // Without the mask, the void takes no part and no value (the stencilled rule).
    let plain = convolve(&im, &taps);
    assert!(
        (plain.radiance[(8 * w + x) as usize] - c)
            .abs()
            .max_element()
            < 1e-5
    );
    assert_eq!(plain.radiance[(20 * w + 30) as usize], Rgb::ZERO);
    // The modulation lights every pixel of the mask, the crack included, and nothing else.
    let camera = Camera::look_at(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::Z, 50.0);
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let view = PinholeView::mirrored(&camera, &plane, w, h);
    let table = FlippedRadialReflectance::new(&Fresnel::One, 64).unwrap();
    let term = modulate_in(&out, Some(&mask), &view, &plane, &table);
    assert!(term[(20 * w + 30) as usize].max_element() > 0.0);
    let unmasked = modulate(&plain, &view, &plane, &table);
    assert_eq!(unmasked[(20 * w + 30) as usize], Rgb::ZERO);
}

#[test]
fn the_kernel_by_depth_is_the_space_invariant_one_at_equal_depth_and_sharp_at_contact() {
    // The eye 1.5 m above a floor mirror looking straight down.
    let e = 1.5f32;
    let camera = Camera::look_at(Vec3::new(0.0, e, 0.0), Vec3::ZERO, Vec3::Z, 50.0);
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let (w, h) = (48u32, 40u32);
    let view = PinholeView::mirrored(&camera, &plane, w, h);
    let k = kernel(0.08);
    // A random-looking M all at d = 2.5 m: d/(e + d) is the same at every pixel.
    let mut im = filled(w, h, Rgb::ONE);
    for (i, r) in im.radiance.iter_mut().enumerate() {
        let v = ((i as u32).wrapping_mul(2_654_435_761) >> 24) as f32 / 255.0;
        *r = Rgb::new(v, 1.0 - v, 0.5);
    }
    // Depth along the view axis: e + d (the axis is the floor's normal here).
    im.depth.fill(e + 2.5);
    let ratio = depth_ratio(&im, &view, &plane, 10, 10).unwrap();
    assert!((ratio - 2.5 / 4.0).abs() < 1e-5, "d/(e + d) = {ratio}");
    let radius = kernel_radius(&im, &view, &plane, k.half_angle);
    let invariant = convolve(&im, &pixel_kernel(&k, radius));
    let by_depth = convolve_by_depth(&im, None, &k, &view, &plane, ratio);
    for (a, b) in invariant.radiance.iter().zip(&by_depth.radiance) {
        assert!((*a - *b).abs().max_element() < 1e-4, "{a} vs {b}");
    }
    // Geometry touching the mirror (d → 0): the kernel shrinks below half a pixel, M unchanged.
    im.depth.fill(e * 1.0001);
    let sharp = convolve_by_depth(&im, None, &k, &view, &plane, ratio);
    assert_eq!(sharp.radiance, im.radiance);
}
