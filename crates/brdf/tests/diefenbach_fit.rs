//! Diefenbach & Badler 1997, section 5: the chi-square fit of the hardware Phong term to Ward's Gaussian reproduces equation 6.

use glam::Vec3;
use lustre_brdf::Brdf;
use lustre_brdf::diefenbach_fit::{
    DIEFENBACH_AMPLITUDE, DIEFENBACH_CHI_SQUARE, DIEFENBACH_EXPONENT_SCALE, WardFitSetup,
    WardSample, diefenbach_phong_term, fit_phong, fit_phong_to_ward,
};
use lustre_brdf::models::{DiefenbachPhong, Ward, WardNormalisation};
use lustre_geometry::Rgb;

#[test]
fn fit_reproduces_the_paper_coefficients_and_chi_square() {
    let fit = fit_phong_to_ward(&WardFitSetup::paper()).unwrap();
    eprintln!("paper setup: {fit:?}");
    // The paper prints c = .0398 and b = 1.999: half a unit of the last printed digit.
    assert!(
        (fit.amplitude - f64::from(DIEFENBACH_AMPLITUDE)).abs() <= 0.00005,
        "c = {}",
        fit.amplitude
    );
    assert!(
        (fit.exponent_scale - f64::from(DIEFENBACH_EXPONENT_SCALE)).abs() <= 0.0005,
        "b = {}",
        fit.exponent_scale
    );
    // χ² depends on the sampling; this setup is chosen to land near the
    // paper's value, so hold it to a factor 1.5 either way.
    let ratio = fit.chi_square / DIEFENBACH_CHI_SQUARE;
    assert!(
        (1.0 / 1.5..=1.5).contains(&ratio),
        "χ² = {} vs paper {DIEFENBACH_CHI_SQUARE}",
        fit.chi_square
    );
}

#[test]
fn coefficients_are_robust_to_the_sampling_step_for_light_at_normal() {
    for alpha in [0.035, 0.04, 0.05] {
        for step_deg in [0.5f64, 1.0, 2.0] {
            let fit = fit_phong_to_ward(&WardFitSetup {
                alpha,
                theta_i: 0.0,
                step: step_deg.to_radians(),
            })
            .unwrap();
            eprintln!("α = {alpha}, step {step_deg}°: {fit:?}");
            assert!(
                (fit.amplitude - 0.0398).abs() <= 0.00005
                    && (fit.exponent_scale - 1.999).abs() <= 0.0005,
                "α = {alpha}, step {step_deg}°: c = {}, b = {}",
                fit.amplitude,
                fit.exponent_scale
            );
        }
    }
}

#[test]
fn small_alpha_limit_is_one_over_eight_pi_and_two() {
    // cos^n δ ≈ exp(-n δ²/2) and tan δ ≈ δ: b → 2, c → 1/(8π) as α → 0.
    let fit = fit_phong_to_ward(&WardFitSetup {
        alpha: 0.005,
        theta_i: 0.0,
        step: 0.02f64.to_radians(),
    })
    .unwrap();
    assert!((fit.amplitude - 1.0 / (8.0 * std::f64::consts::PI)).abs() < 2e-5);
    assert!((fit.exponent_scale - 2.0).abs() < 2e-4);
}

#[test]
fn the_optimiser_recovers_known_parameters_from_synthetic_data() {
    // Data made by the model itself with c = 0.03, b = 2.4: the fit must
    // return them with χ² ≈ 0 from a distant starting point.
    let alpha = 0.2f64;
    let data: Vec<WardSample> = (0..200)
        .map(|k| {
            let delta = k as f64 * 0.007;
            let n = 2.4 / (alpha * alpha);
            WardSample {
                delta,
                value: 0.03 * n * delta.cos().powf(n),
            }
        })
        .collect();
    let fit = fit_phong(&data, alpha, (0.1, 1.0)).unwrap();
    assert!((fit.amplitude - 0.03).abs() < 1e-8, "{fit:?}");
    assert!((fit.exponent_scale - 2.4).abs() < 1e-7, "{fit:?}");
    assert!(fit.chi_square < 1e-18, "{fit:?}");
}

#[test]
fn bad_setups_are_errors() {
    for setup in [
        WardFitSetup {
            alpha: 0.0,
            ..WardFitSetup::paper()
        },
        WardFitSetup {
            alpha: f64::NAN,
            ..WardFitSetup::paper()
        },
        WardFitSetup {
            step: 0.0,
            ..WardFitSetup::paper()
        },
        WardFitSetup {
            theta_i: 2.0,
            ..WardFitSetup::paper()
        },
    ] {
        assert!(fit_phong_to_ward(&setup).is_err(), "{setup:?}");
    }
}

#[test]
fn equation_6_approximates_cos_theta_i_times_ward() {
    // Light along the normal, viewer in the plane: the hardware term must be
    // close to cos θi · f_Ward (its fit target) where the lobe matters.
    let alpha = 0.1f32;
    let ward = Ward::new(
        Rgb::ZERO,
        Rgb::ONE,
        alpha,
        alpha,
        WardNormalisation::Original,
    )
    .unwrap();
    let phong = DiefenbachPhong::new(Rgb::ZERO, Rgb::ONE, alpha).unwrap();
    let peak = 1.0 / (4.0 * std::f32::consts::PI * alpha * alpha);
    for k in 0..40 {
        let t = (k as f32 * 0.5).to_radians();
        let wo = Vec3::new(t.sin(), 0.0, t.cos());
        let wi = Vec3::Z;
        let target = ward.eval(wi, wo).x * wi.z;
        let hw = phong.hardware_term(wi, wo).x;
        assert!(
            (hw - target).abs() < 0.03 * peak,
            "θr = {t}: {hw} vs {target}"
        );
        let h = (wi + wo).normalize();
        assert!((diefenbach_phong_term(h.z, 1.0, alpha) - hw).abs() <= 1e-4 * peak);
        assert!((phong.eval(wi, wo).x * wi.z - hw).abs() <= 1e-4 * peak);
    }
}
