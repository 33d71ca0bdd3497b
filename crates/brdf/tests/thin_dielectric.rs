//! The thin slab: its reflectance is the sum over internal reflections, it transmits along the incident direction.

mod support;

use glam::{Vec2, Vec3};
use lustre_brdf::{fresnel_dielectric, from_model};
use support::{dir, named};

#[test]
fn thin_slab_reflectance_sums_the_internal_reflections() {
    let b = from_model(&named(
        "thin-dielectric",
        &[("ior", &[1.5]), ("transmittance", &[1.0])],
    ))
    .unwrap();
    for theta in [0.0f32, 30.0, 60.0, 85.0] {
        let wo = dir(theta, 40.0);
        let f = f64::from(fresnel_dielectric(wo.z, 1.5));
        // Light reflected at the first face, or entering and bouncing 2k + 1
        // times inside before leaving back: F + (1-F)² F Σ F^(2k).
        let mut r = f;
        let mut inside = (1.0 - f) * (1.0 - f) * f;
        for _ in 0..200 {
            r += inside;
            inside *= f * f;
        }
        let albedo = b.albedo(wo);
        assert!((f64::from(albedo.x) - 1.0).abs() < 1e-6, "no absorption");
        // The reflected lobe is drawn with probability R.
        let reflected = b.sample(wo, Vec2::ZERO, (r as f32) * 0.999).unwrap();
        let transmitted = b.sample(wo, Vec2::ZERO, (r as f32) * 1.001 + 1e-6).unwrap();
        assert!(
            (f64::from(reflected.pdf) - r).abs() < 1e-6,
            "θ = {theta}: {} vs {r}",
            reflected.pdf
        );
        assert_eq!(reflected.wi, Vec3::new(-wo.x, -wo.y, wo.z));
        assert_eq!(transmitted.wi, -wo);
        assert!((f64::from(transmitted.pdf) - (1.0 - r)).abs() < 1e-6);
    }
    let tinted = from_model(&named(
        "thin-dielectric",
        &[("transmittance", &[0.9, 0.5, 0.2])],
    ))
    .unwrap();
    let wo = dir(20.0, 0.0);
    let r = f64::from(tinted.sample(wo, Vec2::ZERO, 0.0).unwrap().pdf);
    let a = tinted.albedo(wo);
    for (c, t) in [0.9f64, 0.5, 0.2].iter().enumerate() {
        assert!((f64::from(a[c]) - (r + (1.0 - r) * t)).abs() < 1e-6);
    }
    assert!(from_model(&named("thin-dielectric", &[("roughness", &[-0.1])])).is_err());
    assert!(from_model(&named("thin-dielectric", &[("ior", &[0.0])])).is_err());
}
