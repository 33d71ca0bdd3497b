//! Chi-square goodness-of-fit tests of every model's sampler against its pdf.

mod support;

use support::{brdfs, chi2_test, dir, sidak};

/// Significance of the whole family of chi-square tests (pbrt-v4 and Mitsuba 3 use 0.01).
const ALPHA: f64 = 0.01;
/// Draws per test: with 16 × 32 cells most expected counts are in the hundreds.
const SAMPLES: usize = 100_000;

#[test]
fn sampling_matches_pdf_chi_square() {
    let models: Vec<_> = brdfs()
        .into_iter()
        // Pure delta models have no smooth density to test.
        .filter(|(_, b)| !(b.has_delta() && b.pdf(dir(10.0, 0.0), dir(30.0, 20.0)) == 0.0))
        .collect();
    let outgoing = [dir(30.0, 20.0), dir(70.0, 200.0)];
    let tests = models.len() * outgoing.len();
    let threshold = sidak(ALPHA, tests);
    let mut failures = Vec::new();
    for (m, (label, brdf)) in models.iter().enumerate() {
        for (k, wo) in outgoing.iter().enumerate() {
            let out = chi2_test(
                brdf.as_ref(),
                *wo,
                SAMPLES,
                16,
                32,
                1000 + (m * 7 + k) as u64,
            );
            if let Some(reason) = &out.hard_failure {
                failures.push(format!("{label} wo={wo}: {reason}"));
            } else if out.p_value < threshold {
                failures.push(format!(
                    "{label} wo={wo}: chi2 = {:.1}, dof = {}, p = {:.3e} < {:.3e}, ∫pdf = {:.4}",
                    out.chi2, out.dof, out.p_value, threshold, out.pdf_integral
                ));
            }
        }
    }
    assert!(tests >= 30, "only {tests} chi-square tests ran");
    assert!(
        failures.is_empty(),
        "chi-square failures:\n{}",
        failures.join("\n")
    );
}

#[test]
fn chi_square_detects_a_wrong_pdf() {
    // The test must be able to fail: a sampler whose pdf is off by a
    // cos θ factor (the uniform-hemisphere density reported for
    // cosine-distributed draws) must be rejected.
    use glam::{Vec2, Vec3};
    use lustre_brdf::{Brdf, BrdfSample};
    use lustre_geometry::Rgb;
    use lustre_geometry::sampling::sample_cosine_hemisphere;
    #[derive(Debug)]
    struct Wrong;
    impl Brdf for Wrong {
        fn name(&self) -> &'static str {
            "wrong"
        }
        fn eval(&self, _: Vec3, _: Vec3) -> Rgb {
            Rgb::splat(std::f32::consts::FRAC_1_PI)
        }
        fn sample(&self, wo: Vec3, u: Vec2, _: f32) -> Option<BrdfSample> {
            let wi = sample_cosine_hemisphere(u);
            let pdf = self.pdf(wi, wo);
            Some(BrdfSample {
                wi,
                weight: self.eval(wi, wo) * wi.z / pdf,
                pdf,
                delta: false,
            })
        }
        fn pdf(&self, _: Vec3, _: Vec3) -> f32 {
            0.5 * std::f32::consts::FRAC_1_PI
        }
        fn is_reciprocal(&self) -> bool {
            true
        }
        fn is_energy_conserving(&self) -> bool {
            true
        }
    }
    let out = chi2_test(&Wrong, dir(30.0, 0.0), 20_000, 16, 32, 5);
    assert!(
        out.p_value < 1e-6,
        "wrong pdf not detected: p = {}",
        out.p_value
    );
}

#[test]
fn incomplete_gamma_matches_known_values() {
    use support::{chi2_sf, regularized_gamma_p};
    // P(1, x) = 1 - e^{-x} exactly.
    for x in [0.1, 1.0, 3.0, 10.0] {
        assert!((regularized_gamma_p(1.0, x) - (1.0 - f64::exp(-x))).abs() < 1e-12);
    }
    // Chi-square critical values from Abramowitz & Stegun table 26.8:
    // upper 5 % point for 10 dof is 18.307, upper 1 % for 100 dof is 135.807.
    assert!((chi2_sf(18.307, 10) - 0.05).abs() < 1e-4);
    assert!((chi2_sf(135.807, 100) - 0.01).abs() < 1e-4);
    // P(0.5, x) = erf(√x): erf(1) = 0.8427007929 (A&S table 7.1).
    assert!((regularized_gamma_p(0.5, 1.0) - 0.842_700_792_9).abs() < 1e-9);
}
