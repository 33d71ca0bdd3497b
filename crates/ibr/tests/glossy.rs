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
use lustre_ibr::glossy::{convolve, kernel_radius, modulate, pixel_cos_theta, pixel_kernel};

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
