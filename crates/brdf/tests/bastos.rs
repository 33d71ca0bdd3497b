//! Bastos et al. 1999, section 8.2: the kernel texture K and the reflectance modulation map R.

mod support;

use glam::Vec3;
use lustre_brdf::Fresnel;
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::microfacet::{Distribution, Shadowing};
use lustre_brdf::reflectance_modulation::{
    FlippedRadialReflectance, RadialReflectance, reflectance_modulation, reflectance_sphere_map,
};
use lustre_geometry::Rgb;
use lustre_geometry::material::MicrofacetDistribution;
use support::{AU_ETA, AU_K, complex_fresnel};

fn beckmann(alpha: f32) -> Distribution {
    Distribution::new(MicrofacetDistribution::Beckmann, alpha, "test").unwrap()
}

#[test]
fn kernel_sums_to_one_and_is_symmetric() {
    for (alpha, shadowing) in [(0.05, Shadowing::Smith), (0.3, Shadowing::VCavity)] {
        let k = KernelTexture::new(&beckmann(alpha), shadowing, 33).unwrap();
        let sum: f64 = k.weights.iter().map(|&w| f64::from(w)).sum();
        assert!((sum - 1.0).abs() < 1e-5, "sum {sum}");
        let n = k.size;
        for j in 0..n {
            for i in 0..n {
                let w = k.weight(i, j);
                assert!(w >= 0.0);
                // Mirror in x, in y, and transpose: D G depends on |φ| only.
                for v in [
                    k.weight(n - 1 - i, j),
                    k.weight(i, n - 1 - j),
                    k.weight(j, i),
                ] {
                    assert!(
                        (v - w).abs() <= 1e-7 * w.max(1e-30),
                        "({i}, {j}): {v} vs {w}"
                    );
                }
            }
        }
        // The peak is the mirror direction, the centre texel.
        let c = n / 2;
        assert!(k.weights.iter().all(|&w| w <= k.weight(c, c)));
    }
}

#[test]
fn kernel_second_moment_is_the_reflected_angle_variance() {
    // Beckmann slopes have per-axis variance α²/2 and the reflected
    // direction turns twice the facet tilt, so Σ K φx² = 2α². Corrections:
    // truncation at 4σ loses 0.1 %, the small-angle terms (tan θh, sin φ/φ,
    // G) are O(α²) relative (under 1 % here), the 64-texel midpoint rule on
    // a Gaussian is exact to far below that: a 2 % tolerance.
    for alpha in [0.02f32, 0.05] {
        let k = KernelTexture::new(&beckmann(alpha), Shadowing::Smith, 64).unwrap();
        let (mut mx, mut my, mut mxy) = (0.0f64, 0.0f64, 0.0f64);
        for j in 0..k.size {
            for i in 0..k.size {
                let (px, py) = (f64::from(k.texel_angle(i)), f64::from(k.texel_angle(j)));
                let w = f64::from(k.weight(i, j));
                mx += w * px * px;
                my += w * py * py;
                mxy += w * px * py;
            }
        }
        let expected = 2.0 * f64::from(alpha) * f64::from(alpha);
        for m in [mx, my] {
            assert!(
                (m / expected - 1.0).abs() < 0.02,
                "α = {alpha}: {m} vs 2α² = {expected}"
            );
        }
        assert!(mxy.abs() < 1e-6 * expected);
    }
}

#[test]
fn kernel_image_size_follows_the_derivation() {
    let k = KernelTexture::new(&beckmann(0.1), Shadowing::Smith, 32).unwrap();
    let fov = 40f32.to_radians();
    // e = 2, d = 3, H = 600: 600 · 3 tan φmax / (5 tan 20°).
    let got = k.image_size(2.0, 3.0, fov, 600).unwrap();
    let want = 600.0 * 3.0 * k.half_angle.tan() / (5.0 * (20f32.to_radians()).tan());
    assert!((got - want).abs() < 1e-3 * want);
    // No blur for geometry on the reflector; distant geometry tends to H tan φmax / tan(fov/2).
    assert_eq!(k.image_size(2.0, 0.0, fov, 600).unwrap(), 0.0);
    let far = k.image_size(2.0, 1e7, fov, 600).unwrap();
    assert!((far - 600.0 * k.half_angle.tan() / (20f32.to_radians()).tan()).abs() < 1e-2);
    assert!(k.image_size(-1.0, 3.0, fov, 600).is_err());
    assert!(k.image_size(2.0, 3.0, 0.0, 600).is_err());
    assert!(KernelTexture::new(&beckmann(0.1), Shadowing::Smith, 0).is_err());
}

#[test]
fn sphere_map_is_fresnel_over_the_denominator_at_sample_texels() {
    let fresnel = Fresnel::Conductor {
        eta: Rgb::from_array(AU_ETA),
        k: Rgb::from_array(AU_K),
    };
    let n = 64u32;
    let map = reflectance_sphere_map(&fresnel, n).unwrap();
    assert_eq!(
        (map.width, map.height, map.texels.len()),
        (n, n, 64 * 64 * 4)
    );
    for (i, j) in [
        (32, 32),
        (40, 10),
        (5, 30),
        (63, 31),
        (0, 0),
        (20, 50),
        (61, 40),
    ] {
        // The test's own geometry: texel centre → sphere normal → mirror of v = +Z.
        let x = (i as f64 + 0.5) / 64.0 * 2.0 - 1.0;
        let y = (j as f64 + 0.5) / 64.0 * 2.0 - 1.0;
        let texel = map.texel(i, j).unwrap();
        if x * x + y * y > 1.0 {
            assert_eq!(texel, [0.0; 4], "({i}, {j}) outside the disk");
            continue;
        }
        let nrm = [x, y, (1.0 - x * x - y * y).sqrt()];
        let v = [0.0, 0.0, 1.0];
        let n_dot_v = nrm[2];
        let r: Vec<f64> = (0..3).map(|c| 2.0 * n_dot_v * nrm[c] - v[c]).collect();
        let n_dot_l: f64 = (0..3).map(|c| nrm[c] * r[c]).sum();
        for ch in 0..3 {
            let f = complex_fresnel(n_dot_v, f64::from(AU_ETA[ch]), f64::from(AU_K[ch]));
            let want = f / (std::f64::consts::PI * n_dot_l * n_dot_v);
            let got = f64::from(texel[ch]);
            assert!(
                (got - want).abs() <= 1e-4 * want,
                "({i}, {j}) channel {ch}: {got} vs {want}"
            );
        }
        assert_eq!(texel[3], 1.0);
    }
}

#[test]
fn radial_table_equals_the_sphere_map_along_any_radius() {
    let fresnel = Fresnel::Dielectric { eta: 1.5 };
    let n = 256u32;
    let map = reflectance_sphere_map(&fresnel, n).unwrap();
    let radial = RadialReflectance::new(&fresnel, n / 2).unwrap();
    assert_eq!(radial.to_texture().width, n / 2);
    // Bilinear sample of the map (texel centres at (i + ½)/n).
    let bilinear = |s: f32, t: f32| -> Vec3 {
        let (x, y) = (s * n as f32 - 0.5, t * n as f32 - 0.5);
        let (i, j) = (x.floor() as u32, y.floor() as u32);
        let (fx, fy) = (x - i as f32, y - j as f32);
        let g = |a: u32, b: u32| Vec3::from_slice(&map.texel(a, b).unwrap()[..3]);
        g(i, j) * (1.0 - fx) * (1.0 - fy)
            + g(i + 1, j) * fx * (1.0 - fy)
            + g(i, j + 1) * (1.0 - fx) * fy
            + g(i + 1, j + 1) * fx * fy
    };
    // Up to ρ = 0.9 bilinear filtering of R ∝ 1/(1 - ρ²) errs by at most
    // (2/256)²/8 · max|R''/R| ≈ 0.15 %; hold it to 0.5 %.
    for psi_deg in [0.0f32, 17.0, 45.0, 90.0, 133.0, 200.0, 301.0] {
        let psi = psi_deg.to_radians();
        for (k, v) in radial.values.iter().enumerate() {
            let rho = (k as f32 + 0.5) / (n / 2) as f32;
            if rho > 0.9 {
                break;
            }
            let m = bilinear(0.5 + 0.5 * rho * psi.cos(), 0.5 + 0.5 * rho * psi.sin());
            assert!(
                (m - *v).abs().max_element() <= 5e-3 * v.max_element(),
                "ψ = {psi_deg}°, ρ = {rho}: map {m} vs table {v}"
            );
            assert!((radial.eval(rho) - *v).abs().max_element() <= 1e-6 * v.max_element());
        }
    }
    assert_eq!(radial.eval(1.5), Rgb::ZERO);
}

#[test]
fn flipped_table_holds_r_and_resolves_grazing_angles_better() {
    // Section 9: indexed by cos θ, the table resolves the grazing angles, where
    // R = F/(π cos² θ) grows fastest, finer than the sphere map's radius sin θ.
    let fresnel = Fresnel::Conductor {
        eta: Vec3::from_array(AU_ETA),
        k: Vec3::from_array(AU_K),
    };
    let m = 64u32;
    let flipped = FlippedRadialReflectance::new(&fresnel, m).unwrap();
    let radial = RadialReflectance::new(&fresnel, m).unwrap();
    assert_eq!(flipped.to_texture().width, m);
    // At its entry centres it is R itself (equation 4's second factor).
    for (k, v) in flipped.values.iter().enumerate() {
        let c = (k as f32 + 0.5) / m as f32;
        // Against the tests' own f64 Fresnel of gold.
        for ch in 0..3 {
            let f = complex_fresnel(f64::from(c), f64::from(AU_ETA[ch]), f64::from(AU_K[ch]));
            let exact = f / (std::f64::consts::PI * f64::from(c * c));
            assert!((f64::from(v[ch]) - exact).abs() <= 1e-4 * exact, "{k} {ch}");
        }
        assert!((flipped.eval(c) - *v).abs().max_element() <= 1e-5 * v.max_element());
    }
    // Relative interpolation error between 60° and 85° from the normal.
    let (mut worst_flipped, mut worst_sphere) = (0.0f32, 0.0f32);
    for step in 0..=250 {
        let theta = (60.0 + 25.0 * step as f32 / 250.0).to_radians();
        let exact = reflectance_modulation(&fresnel, theta.cos());
        let rel = |v: Rgb| ((v - exact).abs() / exact).max_element();
        worst_flipped = worst_flipped.max(rel(flipped.eval(theta.cos())));
        worst_sphere = worst_sphere.max(rel(radial.eval(theta.sin())));
    }
    assert!(
        worst_flipped < 0.25 * worst_sphere,
        "flipped {worst_flipped}, sphere-map radius {worst_sphere}"
    );
    assert!(worst_flipped < 0.05, "flipped {worst_flipped}");
    assert_eq!(flipped.eval(0.0), Rgb::ZERO);
}
