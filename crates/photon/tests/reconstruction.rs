//! Reconstruction (section 2.2): kernel normalisation, the spatial index against brute force, the point-light irradiance on a plane, and quasi-random against pseudo-random emission.

mod support;

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use lustre_geometry::{Bvh, builtin};
use lustre_photon::{
    BounceSelection, EmissionSampling, EstimatorOptions, Kernel, NoProgress, PointGrid,
    SplatEstimator, Support, TraceOptions, kernel_support, trace_photons,
};
use proptest::prelude::*;

/// ∫ g(r) 2πr dr over the unit disc by the midpoint rule.
fn radial_integral(g: impl Fn(f64) -> f64, steps: usize) -> f64 {
    (0..steps)
        .map(|i| {
            let r = (i as f64 + 0.5) / steps as f64;
            g(r) * 2.0 * PI * r / steps as f64
        })
        .sum()
}

#[test]
fn kernels_integrate_to_one() {
    for kernel in [Kernel::Silverman, Kernel::Gaussian] {
        let radial = radial_integral(|r| f64::from(kernel.eval_r2((r * r) as f32)), 100_000);
        // And on a Cartesian grid over [-1, 1]², without assuming radial symmetry.
        let n = 1000;
        let cell = 2.0 / n as f64;
        let mut grid = 0.0;
        for j in 0..n {
            for i in 0..n {
                let x = Vec2::new(
                    (-1.0 + (i as f64 + 0.5) * cell) as f32,
                    (-1.0 + (j as f64 + 0.5) * cell) as f32,
                );
                grid += f64::from(kernel.eval(x)) * cell * cell;
            }
        }
        eprintln!("{kernel:?}: radial {radial:.7}, grid {grid:.7}");
        assert!((radial - 1.0).abs() < 1e-5, "{kernel:?}");
        assert!((grid - 1.0).abs() < 1e-4, "{kernel:?}");
        // The scaled kernel integrates to one over the disc of radius h.
        let h = 0.37f32;
        let scaled = radial_integral(
            |r| f64::from(kernel.scaled(((r * 0.37) * (r * 0.37)) as f32, h)),
            100_000,
        ) * f64::from(h * h);
        assert!((scaled - 1.0).abs() < 1e-4);
        assert_eq!(kernel.eval_r2(1.0), 0.0);
        assert_eq!(kernel.eval_r2(f32::NAN), 0.0);
    }
    assert!((kernel_support(40.0, 4.0, 10_000) - 0.8).abs() < 1e-6);
    assert_eq!(kernel_support(40.0, 4.0, 0), 0.0);
}

proptest! {
    #[test]
    fn grid_agrees_with_brute_force(
        points in prop::collection::vec((-5.0f32..5.0, -5.0f32..5.0, -0.5f32..0.5), 0..300),
        flat in any::<bool>(),
        cell in 0.01f32..3.0,
        center in (-6.0f32..6.0, -6.0f32..6.0, -1.0f32..1.0),
        radius in 0.0f32..4.0,
    ) {
        let points: Vec<Vec3> = points
            .into_iter()
            .map(|(x, y, z)| Vec3::new(x, y, if flat { 0.0 } else { z }))
            .collect();
        let grid = PointGrid::build(&points, cell);
        prop_assert!(grid.validate().is_ok());
        let c = Vec3::new(center.0, center.1, center.2);
        let expected: Vec<usize> = (0..points.len())
            .filter(|&i| (points[i] - c).length_squared() <= radius * radius)
            .collect();
        prop_assert_eq!(grid.within(c, radius), expected);
        // Points exactly on the query sphere are found too.
        if let Some(&p) = points.first() {
            let r = (p - c).length();
            prop_assert!(grid.within(c, r).contains(&0) || (p - c).length_squared() > r * r);
        }
    }
}

#[test]
fn estimator_index_agrees_with_brute_force() {
    let scene = builtin("glosbox").unwrap();
    let bvh = Bvh::build(&scene);
    let options = TraceOptions {
        photons: 20_000,
        seed: 9,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
    for selection in [BounceSelection::All, BounceSelection::Indirect] {
        let est = SplatEstimator::build(
            &scene,
            &map,
            EstimatorOptions {
                support: Support::Scaled(8.0),
                selection,
                ..EstimatorOptions::default()
            },
        )
        .unwrap();
        let camera = scene.camera();
        let mut nonzero = 0;
        for j in 0..12 {
            for i in 0..12 {
                let ndc = Vec2::new(i as f32 / 5.5 - 1.0, j as f32 / 5.5 - 1.0);
                let ray = camera.primary_ray(ndc);
                let Some(hit) = bvh.closest_hit(&ray) else {
                    continue;
                };
                let wo = -ray.direction;
                let fast = est.radiance_at_hit(&hit, wo);
                let slow =
                    est.radiance_brute_force(hit.surface, hit.position, hit.shading_normal, wo);
                assert!(
                    (fast - slow).abs().max_element() <= 1e-4 * slow.max_element().max(1e-3),
                    "{fast} vs {slow}"
                );
                nonzero += usize::from(fast.max_element() > 0.0);
            }
        }
        assert!(nonzero > 50);
    }
}

/// Expected value and standard deviation of the estimate of `E` at `x` from `n` photons of a point light of intensity `intensity` at height `d` over the plane: `E_h(x) = ∫ K_h(x - y) E(y) dy`, `Var = (Φ/n) ∫ K_h² E - E_h²/n` (midpoint rule in polar coordinates around `x`).
fn expected_irradiance(
    kernel: Kernel,
    h: f64,
    x: Vec2,
    d: f64,
    intensity: f64,
    n: f64,
) -> (f64, f64) {
    let e = |y: (f64, f64)| {
        let r2 = y.0 * y.0 + y.1 * y.1 + d * d;
        intensity * d / (r2 * r2.sqrt())
    };
    let (nr, na) = (400, 400);
    let (mut mean, mut second) = (0.0, 0.0);
    for i in 0..nr {
        let r = (i as f64 + 0.5) / nr as f64 * h;
        let k = f64::from(kernel.eval_r2(((r / h) * (r / h)) as f32)) / (h * h);
        for j in 0..na {
            let a = (j as f64 + 0.5) / na as f64 * 2.0 * PI;
            let y = (f64::from(x.x) + r * a.cos(), f64::from(x.y) + r * a.sin());
            let w = r * (h / nr as f64) * (2.0 * PI / na as f64);
            mean += k * e(y) * w;
            second += k * k * e(y) * w;
        }
    }
    let phi = 4.0 * PI * intensity;
    let var = (phi * second - mean * mean) / n;
    (mean, var.max(0.0).sqrt())
}

/// Analytic irradiance of the point light: `E = I cos θ / r²`.
fn analytic_irradiance(x: Vec2, d: f64, intensity: f64) -> f64 {
    let r2 = f64::from(x.length_squared()) + d * d;
    intensity * d / (r2 * r2.sqrt())
}

#[test]
fn point_light_irradiance_on_a_plane() {
    let (d, rho, intensity) = (1.0f64, 0.6f32, 2.0f64);
    let scene = support::point_over_plane(1000.0, d as f32, rho, intensity as f32);
    let bvh = Bvh::build(&scene);
    let n = 200_000u64;
    let map = trace_photons(
        &scene,
        &bvh,
        &TraceOptions {
            photons: n,
            seed: 21,
            ..TraceOptions::default()
        },
        &NoProgress,
    )
    .unwrap();
    let h = 0.25f64;
    for kernel in [Kernel::Silverman, Kernel::Gaussian] {
        let est = SplatEstimator::build(
            &scene,
            &map,
            EstimatorOptions {
                kernel,
                support: Support::Fixed(h as f32),
                selection: BounceSelection::All,
                edges: lustre_photon::Edges::Truncated,
            },
        )
        .unwrap();
        for x in [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.5, 0.0),
            Vec2::new(1.0, 0.3),
        ] {
            let p = Vec3::new(x.x, 0.0, x.y);
            let l = f64::from(est.radiance(0, p, Vec3::Y, Vec3::Y).x);
            let (mean, sigma) = expected_irradiance(kernel, h, x, d, intensity, n as f64);
            let expected = f64::from(rho) / PI * mean;
            let sigma = f64::from(rho) / PI * sigma;
            let analytic = f64::from(rho) / PI * analytic_irradiance(x, d, intensity);
            eprintln!(
                "{kernel:?} at {x}: L = {l:.5}, E[L] = {expected:.5} ± {sigma:.5}, analytic ρ/π E = {analytic:.5} (kernel bias {:+.2}%)",
                100.0 * (expected / analytic - 1.0)
            );
            assert!((l - expected).abs() <= 5.0 * sigma);
        }
    }
    // The kernel bias vanishes as h -> 0: at h = 0.01 the smoothed irradiance is the analytic one within 0.01%.
    for x in [Vec2::ZERO, Vec2::new(1.0, 0.3)] {
        let (m, _) = expected_irradiance(Kernel::Silverman, 0.01, x, d, intensity, 1.0);
        let a = analytic_irradiance(x, d, intensity);
        assert!((m / a - 1.0).abs() < 1e-4, "{m} {a}");
    }
}

#[test]
fn quasi_random_emission_has_lower_error() {
    let (d, rho, intensity) = (1.0f64, 0.5f32, 1.0f64);
    let scene = support::point_over_plane(1000.0, d as f32, rho, intensity as f32);
    let bvh = Bvh::build(&scene);
    let n = 20_000u64;
    let h = 0.25f64;
    let queries: Vec<Vec2> = (0..16)
        .map(|i| Vec2::new((i % 4) as f32 * 0.4 - 0.6, (i / 4) as f32 * 0.4 - 0.6))
        .collect();
    let expected: Vec<f64> = queries
        .iter()
        .map(|&x| {
            f64::from(rho) / PI
                * expected_irradiance(Kernel::Silverman, h, x, d, intensity, n as f64).0
        })
        .collect();
    let mut rms = Vec::new();
    for emission in [
        EmissionSampling::Random,
        EmissionSampling::Halton,
        EmissionSampling::Sobol,
    ] {
        let mut sum2 = 0.0;
        let mut count = 0.0;
        for seed in 0..8u64 {
            let map = trace_photons(
                &scene,
                &bvh,
                &TraceOptions {
                    photons: n,
                    seed,
                    emission,
                    ..TraceOptions::default()
                },
                &NoProgress,
            )
            .unwrap();
            let est = SplatEstimator::build(
                &scene,
                &map,
                EstimatorOptions {
                    support: Support::Fixed(h as f32),
                    ..EstimatorOptions::default()
                },
            )
            .unwrap();
            for (x, e) in queries.iter().zip(&expected) {
                let l = f64::from(
                    est.radiance(0, Vec3::new(x.x, 0.0, x.y), Vec3::Y, Vec3::Y)
                        .x,
                );
                sum2 += (l / e - 1.0).powi(2);
                count += 1.0;
            }
        }
        let r = (sum2 / count).sqrt();
        eprintln!(
            "{emission:?}: relative RMS error {:.3}% at {n} photons, h = {h}",
            100.0 * r
        );
        rms.push(r);
    }
    assert!(rms[1] < rms[0] && rms[2] < rms[0], "{rms:?}");
}

/// [`expected_irradiance`] on the square `[-half, half]²` only, where the photons can land: the truncated estimate's mean and standard deviation, and the kernel's mass on the square `M = ∫_S K_h(x - y) dy`, by the same polar midpoint rule.
fn expected_on_square(
    h: f64,
    x: Vec2,
    d: f64,
    intensity: f64,
    n: f64,
    half: f64,
) -> (f64, f64, f64) {
    let e = |y: (f64, f64)| {
        let r2 = y.0 * y.0 + y.1 * y.1 + d * d;
        intensity * d / (r2 * r2.sqrt())
    };
    let (nr, na) = (400, 720);
    let (mut mean, mut second, mut mass) = (0.0, 0.0, 0.0);
    for i in 0..nr {
        let r = (i as f64 + 0.5) / nr as f64 * h;
        let k = f64::from(Kernel::Silverman.eval_r2(((r / h) * (r / h)) as f32)) / (h * h);
        for j in 0..na {
            let a = (j as f64 + 0.5) / na as f64 * 2.0 * PI;
            let y = (f64::from(x.x) + r * a.cos(), f64::from(x.y) + r * a.sin());
            if y.0.abs() > half || y.1.abs() > half {
                continue;
            }
            let w = r * (h / nr as f64) * (2.0 * PI / na as f64);
            mean += k * e(y) * w;
            second += k * k * e(y) * w;
            mass += k * w;
        }
    }
    let phi = 4.0 * PI * intensity;
    let var = (phi * second - mean * mean) / n;
    (mean, var.max(0.0).sqrt(), mass)
}

/// A point light 0.5 m over a 1 m square: with normalised edges the estimate at the square's centre, an edge and a corner is the irradiance the photons bring there averaged over the part of the kernel on the square (`E_h / M`, within 5 σ and the 1 % of M's grid), where the truncated estimate falls to about ½ on the edge and ¼ at the corner (`E_h`).
#[test]
fn normalised_edges_undo_the_kernel_cut_at_a_square_s_edges() {
    let (d, half, rho, intensity) = (0.5f64, 0.5f64, 0.6f32, 1.0f64);
    let scene = support::point_over_plane(half as f32, d as f32, rho, intensity as f32);
    let bvh = Bvh::build(&scene);
    let n = 400_000u64;
    let map = trace_photons(
        &scene,
        &bvh,
        &TraceOptions {
            photons: n,
            seed: 5,
            ..TraceOptions::default()
        },
        &NoProgress,
    )
    .unwrap();
    let h = 0.2f64;
    let build = |edges| {
        SplatEstimator::build(
            &scene,
            &map,
            EstimatorOptions {
                support: Support::Fixed(h as f32),
                edges,
                ..EstimatorOptions::default()
            },
        )
        .unwrap()
    };
    let (truncated, normalised) = (
        build(lustre_photon::Edges::Truncated),
        build(lustre_photon::Edges::Normalised),
    );
    for (x, m_expected) in [
        (Vec2::ZERO, 1.0),
        (Vec2::new(0.5, 0.0), 0.5),
        (Vec2::new(0.5, 0.5), 0.25),
        (Vec2::new(-0.45, 0.2), 0.0),
    ] {
        let (mean, sigma, mass) = expected_on_square(h, x, d, intensity, n as f64, half);
        if m_expected > 0.0 {
            assert!((mass - m_expected).abs() < 1e-3, "M at {x}: {mass}");
        }
        let p = Vec3::new(x.x, 0.0, x.y);
        let radiance = |est: &SplatEstimator| f64::from(est.radiance(0, p, Vec3::Y, Vec3::Y).x);
        let scale = f64::from(rho) / PI;
        let (lt, ln) = (radiance(&truncated), radiance(&normalised));
        eprintln!(
            "at {x}: M = {mass:.4}; truncated {lt:.5} vs E[L] {:.5} ± {:.5}; normalised {ln:.5} vs {:.5} ± {:.5}",
            scale * mean,
            scale * sigma,
            scale * mean / mass,
            scale * sigma / mass,
        );
        assert!(
            (lt - scale * mean).abs() <= 5.0 * scale * sigma,
            "truncated at {x}"
        );
        let bound = 5.0 * scale * sigma / mass + 0.01 * scale * mean / mass;
        assert!(
            (ln - scale * mean / mass).abs() <= bound,
            "normalised at {x}"
        );
    }
}
