//! The full Oren-Nayar model (Oren & Nayar 1994, equations 27-28): Lambert at σ = 0, and agreement with an independent f64 transcription of the paper's formulas.

mod support;

use std::f64::consts::PI;

use glam::Vec3;
use lustre_brdf::Brdf;
use lustre_brdf::models::{Lambert, OrenNayarFull, OrenNayarQualitative};
use lustre_geometry::Rgb;
use support::{Rng, dir, integrate_cell};

/// `∫ f cos θi dωi` of one channel on a 32 × 32 grid of (cos θ, φ) cells, 6 × 6 midpoints each, without the model's sampler.
fn quadrature_albedo(b: &dyn Brdf, wo: Vec3, ch: usize) -> f64 {
    let g = |wi: Vec3| f64::from(b.eval(wi, wo)[ch]) * f64::from(wi.z);
    let mut s = 0.0;
    for c in 0..32 {
        for p in 0..32 {
            s += integrate_cell(
                &g,
                c as f64 / 32.0,
                (c + 1) as f64 / 32.0,
                p as f64 / 32.0 * 2.0 * PI,
                (p + 1) as f64 / 32.0 * 2.0 * PI,
                6,
            );
        }
    }
    s
}

#[test]
fn full_model_at_sigma_zero_is_lambert() {
    let rho = Rgb::new(0.8, 0.5, 0.2);
    let full = OrenNayarFull::new(rho, 0.0).unwrap();
    let lambert = Lambert::new(rho).unwrap();
    let mut rng = Rng::new(5);
    for _ in 0..500 {
        let (wi, wo) = (rng.upper(0.01), rng.upper(0.01));
        let (a, b) = (full.eval(wi, wo), lambert.eval(wi, wo));
        assert!((a - b).abs().max_element() < 1e-6, "{a} vs {b}");
    }
    for wo in [dir(0.0, 0.0), dir(45.0, 30.0), dir(80.0, 200.0)] {
        for ch in 0..3 {
            // The albedo of ρ/π is ρ; the quadrature's own error is below 1e-5.
            let q = quadrature_albedo(&full, wo, ch);
            assert!((q - f64::from(rho[ch])).abs() < 1e-4, "quadrature {q}");
            let a = full.albedo(wo)[ch];
            assert!((a - rho[ch]).abs() < 1e-4, "albedo {a} vs ρ {}", rho[ch]);
        }
    }
}

/// Oren & Nayar 1994, equations 27-28, transcribed in f64 from the paper for one channel: `(L1r + L2r) / (E0 cos θi)`.
fn paper_full(rho: f64, sigma: f64, ti: f64, tr: f64, dphi: f64) -> f64 {
    let (alpha, beta) = (ti.max(tr), ti.min(tr));
    let s2 = sigma * sigma;
    let c1 = 1.0 - 0.5 * s2 / (s2 + 0.33);
    let c2 = if dphi.cos() >= 0.0 {
        0.45 * s2 / (s2 + 0.09) * alpha.sin()
    } else {
        0.45 * s2 / (s2 + 0.09) * (alpha.sin() - (2.0 * beta / PI).powi(3))
    };
    let c3 = 0.125 * s2 / (s2 + 0.09) * (4.0 * alpha * beta / (PI * PI)).powi(2);
    let l1 = rho / PI
        * (c1
            + dphi.cos() * c2 * beta.tan()
            + (1.0 - dphi.cos().abs()) * c3 * ((alpha + beta) / 2.0).tan());
    let l2 =
        0.17 * rho * rho / PI * s2 / (s2 + 0.13) * (1.0 - dphi.cos() * (2.0 * beta / PI).powi(2));
    l1.max(0.0) + l2
}

#[test]
fn full_model_matches_the_paper_equations() {
    let mut rng = Rng::new(77);
    for _ in 0..2000 {
        let sigma = rng.f32() * 1.2;
        let rho = 0.1 + 0.9 * rng.f32();
        let ti = f64::from(rng.f32()) * 1.5;
        let tr = f64::from(rng.f32()) * 1.5;
        let (pi, pr) = (
            f64::from(rng.f32()) * 2.0 * PI,
            f64::from(rng.f32()) * 2.0 * PI,
        );
        let d = |t: f64, p: f64| {
            Vec3::new(
                (t.sin() * p.cos()) as f32,
                (t.sin() * p.sin()) as f32,
                t.cos() as f32,
            )
        };
        let b = OrenNayarFull::new(Rgb::splat(rho), sigma).unwrap();
        let got = f64::from(b.eval(d(ti, pi), d(tr, pr)).x);
        let want = paper_full(f64::from(rho), f64::from(sigma), ti, tr, pr - pi);
        assert!(
            (got - want).abs() <= 2e-4 * want.abs().max(0.1),
            "σ = {sigma}, θi = {ti}, θr = {tr}: {got} vs paper {want}"
        );
    }
}

#[test]
fn full_and_qualitative_models_differ_only_by_the_terms_the_qualitative_one_drops() {
    // With the light along the normal β = 0: C3 and the (2β/π) factors vanish,
    // so the full model is the qualitative one plus the interreflection term
    // 0.17 ρ²/π σ²/(σ² + 0.13) (equation 28 at β = 0).
    let (rho, sigma) = (0.7f32, 0.4f32);
    let full = OrenNayarFull::new(Rgb::splat(rho), sigma).unwrap();
    let qual = OrenNayarQualitative::new(Rgb::splat(rho), sigma).unwrap();
    let s2 = f64::from(sigma * sigma);
    let l2 = 0.17 * f64::from(rho * rho) / PI * s2 / (s2 + 0.13);
    for theta in [10.0, 40.0, 70.0] {
        let wo = dir(theta, 0.0);
        let diff = f64::from(full.eval(Vec3::Z, wo).x - qual.eval(Vec3::Z, wo).x);
        assert!((diff - l2).abs() < 1e-5, "θ = {theta}: {diff} vs {l2}");
    }
}
