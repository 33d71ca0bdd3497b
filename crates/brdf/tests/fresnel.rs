//! Fresnel terms against known values and an independent complex-arithmetic evaluation.

use lustre_brdf::{fresnel_conductor, fresnel_dielectric, fresnel_schlick};
use lustre_geometry::Rgb;
use support::complex_fresnel;

mod support;

#[test]
fn dielectric_normal_incidence_is_four_percent() {
    // ((n - 1)/(n + 1))² = (0.5/2.5)² = 0.04 for n = 1.5.
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    // Same from inside (the interface flipped).
    assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
    // Grazing incidence reflects everything.
    assert!((fresnel_dielectric(1e-6, 1.5) - 1.0).abs() < 1e-4);
}

#[test]
fn dielectric_brewster_angle_has_no_p_reflection() {
    // At Brewster's angle tan θ = n, rp = 0 and F = rs²/2 with
    // rs = (cos θi - n cos θt)/(cos θi + n cos θt) (Born & Wolf 1.5.2).
    let n = 1.5_f64;
    let theta = n.atan();
    let (ci, si) = (theta.cos(), theta.sin());
    let ct = (1.0 - si * si / (n * n)).sqrt();
    let rs = (ci - n * ct) / (ci + n * ct);
    let expected = 0.5 * rs * rs;
    assert!((f64::from(fresnel_dielectric(ci as f32, 1.5)) - expected).abs() < 1e-6);
}

#[test]
fn total_internal_reflection_beyond_the_critical_angle() {
    // From inside glass (η = 1/1.5), the critical angle is asin(1/1.5) = 41.81°.
    let critical = (1.0_f32 / 1.5).asin();
    for deg in [42.0_f32, 50.0, 70.0, 89.0] {
        let c = deg.to_radians().cos();
        assert_eq!(fresnel_dielectric(-c, 1.5), 1.0, "{deg}°");
    }
    let just_below = (critical - 0.01).cos();
    assert!(fresnel_dielectric(-just_below, 1.5) < 1.0);
}

#[test]
fn conductor_matches_complex_fresnel_equations() {
    for (n, k) in [
        (0.2_f32, 3.0_f32),
        (1.1, 2.1),
        (0.05, 4.0),
        (1.5, 0.0),
        (2.5, 0.5),
    ] {
        for deg in [0.0_f64, 15.0, 35.0, 55.0, 70.0, 80.0, 88.0] {
            let c = deg.to_radians().cos();
            let ours = f64::from(fresnel_conductor(c as f32, Rgb::splat(n), Rgb::splat(k)).x);
            let reference = complex_fresnel(c, f64::from(n), f64::from(k));
            assert!(
                (ours - reference).abs() < 2e-5,
                "n = {n}, k = {k}, θ = {deg}°: {ours} vs {reference}"
            );
        }
    }
}

#[test]
fn conductor_normal_incidence_for_gold_silver_copper() {
    // n, k at 619.9 nm (2.0 eV) from H.-J. Hagemann, W. Gudat and C. Kunz,
    // "Optical constants from the far infrared to the x-ray region: Mg, Al,
    // Cu, Ag, Au, Bi, C, and Al2O3", DESY report SR-74/7 (1974), tables 3
    // and 5; gold also at 632.8 nm from the Sopra material library as
    // published by Filmetrics (n = 0.18104, k = 3.068099). Normal-incidence
    // reflectance is ((n-1)² + k²)/((n+1)² + k²).
    let metals = [
        ("gold 619.9 nm", 0.487_f32, 3.31_f32, 0.85),
        ("silver 619.9 nm", 0.269, 4.18, 0.94),
        ("copper 619.9 nm", 0.272, 3.24, 0.91),
        ("gold 632.8 nm", 0.181_04, 3.068_099, 0.93),
    ];
    for (name, n, k, approx) in metals {
        let (nd, kd) = (f64::from(n), f64::from(k));
        let expected = ((nd - 1.0).powi(2) + kd * kd) / ((nd + 1.0).powi(2) + kd * kd);
        let ours = f64::from(fresnel_conductor(1.0, Rgb::splat(n), Rgb::splat(k)).x);
        assert!(
            (ours - expected).abs() < 1e-6,
            "{name}: {ours} vs {expected}"
        );
        // Noble metals reflect most of the red: within 0.01 of the rounded value.
        assert!(
            (ours - approx).abs() < 0.01,
            "{name}: {ours} vs about {approx}"
        );
    }
}

#[test]
fn schlick_approximation_endpoints() {
    let f0 = Rgb::new(0.04, 0.5, 0.9);
    assert!((fresnel_schlick(1.0, f0) - f0).abs().max_element() < 1e-7);
    assert!((fresnel_schlick(0.0, f0) - Rgb::ONE).abs().max_element() < 1e-7);
    // Schlick 1994 equation 15 against the exact dielectric: within 0.02 for n = 1.5 up to 60°.
    for deg in [0.0_f32, 20.0, 40.0, 60.0] {
        let c = deg.to_radians().cos();
        let s = fresnel_schlick(c, Rgb::splat(0.04)).x;
        assert!((s - fresnel_dielectric(c, 1.5)).abs() < 0.02, "{deg}°");
    }
}
