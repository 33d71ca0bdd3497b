//! Tests of `lustre_geometry::sampling`: chi-square goodness of fit of every
//! warp against its stated density (as Mitsuba 3's `chi2.py` and pbrt-v4's
//! `bsdfs_test.cpp` do), PCG32 against the reference generator, Sobol'
//! against SciPy's Joe-Kuo implementation and the (0, m, 2)-net property,
//! Halton against hand-computed radical inverses, and frames.
//!
//! Statistical tests run at significance 0.01 overall, split over the
//! [`CHI2_TESTS`] chi-square tests of this file with the Šidák correction.
//! Every generator is seeded explicitly, so each run is deterministic.

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use lustre_geometry::sampling::{
    Frame, HALTON_DIMENSIONS, Halton, LowDiscrepancySequence, ONE_MINUS_EPSILON, Pcg32,
    SOBOL_DIMENSIONS, Sampler, SequenceSampler, Sobol, cosine_hemisphere_pdf, halton,
    nested_uniform_scramble, radical_inverse, sample_concentric_disk, sample_cosine_hemisphere,
    sample_parallelogram, sample_triangle, sample_uniform_cone, sample_uniform_hemisphere,
    sample_uniform_sphere, sobol, sobol_u32, uniform_cone_pdf, uniform_hemisphere_pdf,
    uniform_sphere_pdf, unit_f32_from_bits,
};
use proptest::prelude::*;

// ---------------------------------------------------------------------------
// The chi-square distribution, written from its definition.
// ---------------------------------------------------------------------------

/// ln Γ(x) for x > 0: the recurrence Γ(x) = Γ(x + 1) / x up to x >= 10, then
/// Stirling's series with Bernoulli terms to x^-9 (error below 1e-13 there).
fn ln_gamma(mut x: f64) -> f64 {
    let mut shift = 0.0;
    while x < 10.0 {
        shift -= x.ln();
        x += 1.0;
    }
    let inv = 1.0 / x;
    let inv2 = inv * inv;
    let series = inv
        * (1.0 / 12.0
            - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 / 1188.0))));
    shift + (x - 0.5) * x.ln() - x + 0.5 * (2.0 * PI).ln() + series
}

/// The regularised upper incomplete gamma function Q(a, x) = Γ(a, x) / Γ(a):
/// the power series of P = 1 - Q for x < a + 1, otherwise the continued
/// fraction of Q evaluated with the modified Lentz method.
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = x^a e^-x / Γ(a + 1) Σ_n x^n / ((a + 1) ... (a + n)).
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut n = 1.0;
        while term > sum * 1e-16 {
            term *= x / (a + n);
            sum += term;
            n += 1.0;
        }
        1.0 - sum * log_prefactor.exp()
    } else {
        // Q(a, x) = x^a e^-x / Γ(a) · 1 / (x + 1 - a - 1(1 - a) / (x + 3 - a - 2(2 - a) / ...)).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let i = f64::from(i);
            let an = -i * (i - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        h * log_prefactor.exp()
    }
}

/// P(χ² >= statistic) for `dof` degrees of freedom: Q(dof / 2, statistic / 2).
fn chi2_survival(statistic: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, statistic / 2.0)
}

#[test]
fn chi2_survival_matches_tables() {
    // Two degrees of freedom: the survival function is exactly e^(-x/2).
    for x in [0.1, 1.0, 2.5, 10.0, 40.0] {
        assert!(
            (chi2_survival(x, 2) - (-x / 2.0).exp()).abs() < 1e-12,
            "x = {x}"
        );
    }
    // Critical values (Abramowitz & Stegun table 26.8; checked with SciPy).
    for (x, dof, p) in [
        (3.841458820694124, 1, 0.05),
        (6.634896601021214, 1, 0.01),
        (18.307038053275146, 10, 0.05),
        (23.209251158954356, 10, 0.01),
        (124.34211340400407, 100, 0.05),
        (0.5, 3, 0.9188914116546758),
        (850.0, 799, 0.10271858926232115),
        (1500.0, 1400, 0.031503720989392366),
    ] {
        let q = chi2_survival(x, dof);
        assert!(
            (q - p).abs() < 1e-9 * p.max(1e-3),
            "χ²({x}, {dof}) = {q}, want {p}"
        );
    }
}

/// Number of chi-square tests in this file, for the Šidák correction.
const CHI2_TESTS: usize = 10;

/// Overall significance of the chi-square tests.
const SIGNIFICANCE: f64 = 0.01;

/// The per-test significance after the Šidák correction, 1 - (1 - α)^(1/m).
fn sidak_threshold() -> f64 {
    1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / CHI2_TESTS as f64)
}

/// Pearson's chi-square test of `observed` against `expected` counts, pooling
/// the bins whose expected count is below 5 (smallest first, until the pool
/// reaches 5) as Mitsuba's `chi2.py` does. Returns the p-value, or an error
/// when a bin with no expected count received samples.
fn chi2_p_value(observed: &[f64], expected: &[f64]) -> Result<(f64, f64, usize), String> {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    let (mut statistic, mut bins) = (0.0, 0usize);
    for &i in &order {
        if expected[i] <= 0.0 {
            if observed[i] > 0.0 {
                return Err(format!(
                    "bin {i} received {} samples where the density is zero",
                    observed[i]
                ));
            }
        } else if expected[i] < 5.0 || (pool_exp > 0.0 && pool_exp < 5.0) {
            pool_obs += observed[i];
            pool_exp += expected[i];
        } else {
            statistic += (observed[i] - expected[i]).powi(2) / expected[i];
            bins += 1;
        }
    }
    if pool_exp > 0.0 {
        statistic += (pool_obs - pool_exp).powi(2) / pool_exp;
        bins += 1;
    }
    let dof = bins - 1;
    Ok((chi2_survival(statistic, dof), statistic, dof))
}

/// Asserts that `observed` fits `expected` at the Šidák-corrected significance.
fn assert_fits(name: &str, observed: &[f64], expected: &[f64]) {
    let total_obs: f64 = observed.iter().sum();
    let total_exp: f64 = expected.iter().sum();
    assert!(
        (total_exp - total_obs).abs() <= 1e-3 * total_obs,
        "{name}: the expected counts sum to {total_exp}, not {total_obs}: the density does not integrate to 1 over the bins"
    );
    let (p, statistic, dof) =
        chi2_p_value(observed, expected).unwrap_or_else(|e| panic!("{name}: {e}"));
    let threshold = sidak_threshold();
    assert!(
        p >= threshold,
        "{name}: χ² = {statistic:.1} with {dof} degrees of freedom, p = {p:.3e} < {threshold:.3e}: the samples do not follow the density"
    );
}

/// Composite Simpson rule with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for i in 1..n {
        sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// Samples per chi-square test.
const SAMPLES: usize = 1_000_000;

// ---------------------------------------------------------------------------
// Directional warps, binned over (cos θ, φ).
// ---------------------------------------------------------------------------

/// A chi-square test of a directional warp: `SAMPLES` directions from `warp`
/// fed by PCG32, binned on a `res_z` × `res_phi` grid over cos θ in
/// `[z_min, z_max]` (the support) and φ in [0, 2π), against `N ∫∫ pdf dcosθ dφ`
/// over each bin, integrated with Simpson's rule.
fn chi2_directions(
    name: &str,
    seed: u64,
    (z_min, z_max): (f64, f64),
    warp: impl Fn(Vec2) -> Vec3,
    pdf: impl Fn(Vec3) -> f64,
) {
    let (res_z, res_phi) = (20, 40);
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut observed = vec![0.0; res_z * res_phi];
    for _ in 0..SAMPLES {
        let d = warp(rng.next_vec2());
        assert!(
            (d.length() - 1.0).abs() < 1e-5,
            "{name}: {d} is not a unit vector"
        );
        let z = f64::from(d.z);
        assert!(
            z >= z_min - 1e-6 && z <= z_max + 1e-6,
            "{name}: cos θ = {z} lies outside the support [{z_min}, {z_max}]"
        );
        let phi = f64::from(d.y).atan2(f64::from(d.x)).rem_euclid(2.0 * PI);
        let iz = (((z - z_min) / (z_max - z_min) * res_z as f64) as usize).min(res_z - 1);
        let ip = ((phi / (2.0 * PI) * res_phi as f64) as usize).min(res_phi - 1);
        observed[iz * res_phi + ip] += 1.0;
    }
    let mut expected = vec![0.0; res_z * res_phi];
    let dz = (z_max - z_min) / res_z as f64;
    let dphi = 2.0 * PI / res_phi as f64;
    for iz in 0..res_z {
        for ip in 0..res_phi {
            let (z0, p0) = (z_min + iz as f64 * dz, ip as f64 * dphi);
            let integral = simpson(
                |z| {
                    simpson(
                        |phi| {
                            let r = (1.0 - z * z).max(0.0).sqrt();
                            pdf(Vec3::new(
                                (r * phi.cos()) as f32,
                                (r * phi.sin()) as f32,
                                z as f32,
                            ))
                        },
                        p0,
                        p0 + dphi,
                        4,
                    )
                },
                z0,
                z0 + dz,
                4,
            );
            expected[iz * res_phi + ip] = integral * SAMPLES as f64;
        }
    }
    assert_fits(name, &observed, &expected);
}

#[test]
fn uniform_sphere_follows_its_pdf() {
    chi2_directions(
        "uniform sphere",
        1,
        (-1.0, 1.0),
        sample_uniform_sphere,
        |_| f64::from(uniform_sphere_pdf()),
    );
}

#[test]
fn uniform_hemisphere_follows_its_pdf() {
    chi2_directions(
        "uniform hemisphere",
        2,
        (0.0, 1.0),
        sample_uniform_hemisphere,
        |_| f64::from(uniform_hemisphere_pdf()),
    );
}

#[test]
fn cosine_hemisphere_follows_its_pdf() {
    chi2_directions(
        "cosine hemisphere",
        3,
        (0.0, 1.0),
        sample_cosine_hemisphere,
        |d| f64::from(cosine_hemisphere_pdf(d.z)),
    );
}

#[test]
fn uniform_cone_follows_its_pdf() {
    for (k, cos_max) in [0.3_f32, 0.95].into_iter().enumerate() {
        chi2_directions(
            &format!("uniform cone, cos_max = {cos_max}"),
            4 + k as u64,
            (f64::from(cos_max), 1.0),
            |u| sample_uniform_cone(u, cos_max),
            |_| f64::from(uniform_cone_pdf(cos_max)),
        );
    }
}

#[test]
fn chi2_rejects_a_wrong_density() {
    // The test has teeth: uniform hemisphere samples against the cosine
    // density, and uniform sphere samples distorted by a few percent.
    let wrong = std::panic::catch_unwind(|| {
        chi2_directions(
            "uniform hemisphere against cos θ / π",
            6,
            (0.0, 1.0),
            sample_uniform_hemisphere,
            |d| f64::from(cosine_hemisphere_pdf(d.z)),
        )
    });
    assert!(
        wrong.is_err(),
        "a uniform hemisphere passed as cosine-weighted"
    );
    let distorted = std::panic::catch_unwind(|| {
        chi2_directions(
            "distorted sphere",
            7,
            (-1.0, 1.0),
            |u| sample_uniform_sphere(Vec2::new(u.x.powf(1.03), u.y)),
            |_| f64::from(uniform_sphere_pdf()),
        )
    });
    assert!(
        distorted.is_err(),
        "a 3% distortion of the sphere went unnoticed"
    );
}

#[test]
fn directional_pdfs_integrate_to_one() {
    // ∫ pdf dω = ∫_0^π ∫_0^2π pdf(θ) sin θ dφ dθ, with Simpson's rule in θ
    // (the densities do not depend on φ).
    let integrate = |pdf: &dyn Fn(f64) -> f64, theta_max: f64| {
        2.0 * PI * simpson(|theta| pdf(theta.cos()) * theta.sin(), 0.0, theta_max, 2000)
    };
    let sphere = integrate(&|_| f64::from(uniform_sphere_pdf()), PI);
    assert!((sphere - 1.0).abs() < 1e-6, "uniform sphere: {sphere}");
    let hemisphere = integrate(&|_| f64::from(uniform_hemisphere_pdf()), PI / 2.0);
    assert!(
        (hemisphere - 1.0).abs() < 1e-6,
        "uniform hemisphere: {hemisphere}"
    );
    // Over the whole sphere: the density must vanish below the horizon.
    let cosine = integrate(&|c| f64::from(cosine_hemisphere_pdf(c as f32)), PI);
    assert!((cosine - 1.0).abs() < 1e-6, "cosine hemisphere: {cosine}");
    for cos_max in [-0.5_f32, 0.0, 0.3, 0.9, 0.999] {
        let cone = integrate(
            &|_| f64::from(uniform_cone_pdf(cos_max)),
            f64::from(cos_max).acos(),
        );
        assert!((cone - 1.0).abs() < 1e-5, "cone {cos_max}: {cone}");
    }
}

// ---------------------------------------------------------------------------
// Area warps, binned on a planar grid.
// ---------------------------------------------------------------------------

/// Area of a convex polygon (shoelace formula).
fn polygon_area(poly: &[[f64; 2]]) -> f64 {
    let mut twice = 0.0;
    for i in 0..poly.len() {
        let [x0, y0] = poly[i];
        let [x1, y1] = poly[(i + 1) % poly.len()];
        twice += x0 * y1 - x1 * y0;
    }
    0.5 * twice.abs()
}

/// The part of a convex polygon inside the axis-aligned rectangle (Sutherland-Hodgman clipping).
fn clip_to_rect(poly: &[[f64; 2]], [x0, y0, x1, y1]: [f64; 4]) -> Vec<[f64; 2]> {
    let mut out = poly.to_vec();
    // Each half-plane as (axis, bound, keep_greater).
    for (axis, bound, greater) in [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)] {
        let input = std::mem::take(&mut out);
        let inside = |p: [f64; 2]| {
            if greater {
                p[axis] >= bound
            } else {
                p[axis] <= bound
            }
        };
        for i in 0..input.len() {
            let (p, q) = (input[i], input[(i + 1) % input.len()]);
            let cross = |p: [f64; 2], q: [f64; 2]| {
                let t = (bound - p[axis]) / (q[axis] - p[axis]);
                [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
            };
            match (inside(p), inside(q)) {
                (true, true) => out.push(q),
                (true, false) => out.push(cross(p, q)),
                (false, true) => {
                    out.push(cross(p, q));
                    out.push(q);
                }
                (false, false) => {}
            }
        }
    }
    out
}

/// A chi-square test of a planar warp: `SAMPLES` points binned on a `res` ×
/// `res` grid over `[x0, x1] × [y0, y1]`, against `N · area(bin ∩ shape) / area(shape)`.
fn chi2_planar(
    name: &str,
    seed: u64,
    [x0, y0, x1, y1]: [f64; 4],
    warp: impl Fn(Vec2) -> Vec2,
    bin_area: impl Fn([f64; 4]) -> f64,
    total_area: f64,
) {
    let res = 20;
    let mut rng = Pcg32::new(seed, 0xa2ea);
    let mut observed = vec![0.0; res * res];
    let (w, h) = ((x1 - x0) / res as f64, (y1 - y0) / res as f64);
    for _ in 0..SAMPLES {
        let p = warp(rng.next_vec2());
        let (x, y) = (f64::from(p.x), f64::from(p.y));
        assert!(
            x >= x0 - 1e-6 && x <= x1 + 1e-6 && y >= y0 - 1e-6 && y <= y1 + 1e-6,
            "{name}: {p} lies outside the bounding box"
        );
        let ix = (((x - x0) / w).max(0.0) as usize).min(res - 1);
        let iy = (((y - y0) / h).max(0.0) as usize).min(res - 1);
        observed[iy * res + ix] += 1.0;
    }
    let mut expected = vec![0.0; res * res];
    for iy in 0..res {
        for ix in 0..res {
            let (bx, by) = (x0 + ix as f64 * w, y0 + iy as f64 * h);
            expected[iy * res + ix] =
                SAMPLES as f64 * bin_area([bx, by, bx + w, by + h]) / total_area;
        }
    }
    assert_fits(name, &observed, &expected);
}

#[test]
fn triangle_sampling_is_uniform() {
    // A scalene triangle in the plane z = 0.5 (points must stay in it).
    let corners = [[0.1, 0.0], [1.0, 0.2], [0.3, 0.9]];
    let [a, b, c] = corners.map(|[x, y]| Vec3::new(x as f32, y as f32, 0.5));
    chi2_planar(
        "triangle",
        8,
        [0.0, 0.0, 1.0, 1.0],
        |u| {
            let p = sample_triangle(u, [a, b, c]);
            assert!((p.z - 0.5).abs() < 1e-6, "{p} left the triangle's plane");
            p.truncate()
        },
        |rect| polygon_area(&clip_to_rect(&corners, rect)),
        polygon_area(&corners),
    );
}

#[test]
fn parallelogram_sampling_is_uniform() {
    // A sheared parallelogram: origin (0.1, 0.1), edges (0.6, 0.1) and (0.3, 0.7).
    let corners = [[0.1, 0.1], [0.7, 0.2], [1.0, 0.9], [0.4, 0.8]];
    let (origin, eu, ev) = (
        Vec3::new(0.1, 0.1, -2.0),
        Vec3::new(0.6, 0.1, 0.0),
        Vec3::new(0.3, 0.7, 0.0),
    );
    // The stated density is 1 / |edge_u × edge_v|; check it against the shoelace area.
    let area = polygon_area(&corners);
    assert!((f64::from(eu.cross(ev).length()) - area).abs() < 1e-6);
    chi2_planar(
        "parallelogram",
        9,
        [0.0, 0.0, 1.0, 1.0],
        |u| {
            let p = sample_parallelogram(u, origin, eu, ev);
            assert!(
                (p.z + 2.0).abs() < 1e-6,
                "{p} left the parallelogram's plane"
            );
            p.truncate()
        },
        |rect| polygon_area(&clip_to_rect(&corners, rect)),
        area,
    );
}

#[test]
fn concentric_disk_is_uniform() {
    // area(rect ∩ unit disc) = ∫ |[y0, y1] ∩ [-√(1-x²), √(1-x²)]| dx, by Simpson.
    let disc_area = |[x0, y0, x1, y1]: [f64; 4]| {
        simpson(
            |x| {
                let half = (1.0 - x * x).max(0.0).sqrt();
                (y1.min(half) - y0.max(-half)).max(0.0)
            },
            x0,
            x1,
            256,
        )
    };
    // The same integral over the whole square gives π: the quadrature is sound.
    assert!((disc_area([-1.0, -1.0, 1.0, 1.0]) - PI).abs() < 1e-3);
    chi2_planar(
        "concentric disk",
        10,
        [-1.0, -1.0, 1.0, 1.0],
        |u| {
            let p = sample_concentric_disk(u);
            assert!(p.length() <= 1.0 + 1e-6, "{p} lies outside the unit disc");
            p
        },
        disc_area,
        PI,
    );
}

// ---------------------------------------------------------------------------
// PCG32
// ---------------------------------------------------------------------------

#[test]
fn pcg32_matches_the_reference_demo() {
    // pcg32-demo.c of the reference C implementation, pcg32_srandom_r(42, 54).
    let mut rng = Pcg32::new(42, 54);
    let expected = [
        0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e,
    ];
    for want in expected {
        assert_eq!(rng.next_u32(), want);
    }
}

#[test]
fn pcg32_is_reproducible_and_streams_differ() {
    let draw = |seed, stream| {
        let mut rng = Pcg32::new(seed, stream);
        (0..1000).map(|_| rng.next_u32()).collect::<Vec<_>>()
    };
    assert_eq!(draw(7, 3), draw(7, 3));
    for (a, b) in [((7, 3), (7, 4)), ((7, 3), (8, 3)), ((0, 0), (0, 1))] {
        let (x, y) = (draw(a.0, a.1), draw(b.0, b.1));
        let same = x.iter().zip(&y).filter(|(p, q)| p == q).count();
        // Two independent streams agree at a position with probability 2^-32.
        assert!(
            same <= 1,
            "{a:?} and {b:?} agree at {same} of 1000 positions"
        );
    }
}

#[test]
fn pcg32_advance_equals_repeated_draws() {
    for n in [0_u64, 1, 2, 3, 17, 1000, 65_537] {
        let mut stepped = Pcg32::new(99, 5);
        for _ in 0..n {
            stepped.next_u32();
        }
        let mut jumped = Pcg32::new(99, 5);
        jumped.advance(n);
        assert_eq!(jumped, stepped, "advance({n})");
        assert_eq!(jumped.next_u32(), stepped.next_u32());
        // And back again: the period is 2^64.
        let mut back = stepped.clone();
        back.advance((n + 1).wrapping_neg());
        assert_eq!(back, Pcg32::new(99, 5), "advance(-{})", n + 1);
    }
}

#[test]
fn pcg32_workers_take_disjoint_substreams() {
    // Worker k advanced by k * 100 draws reproduces draws k*100.. of one generator.
    let mut single = Pcg32::new(1234, 1);
    let all: Vec<u32> = (0..400).map(|_| single.next_u32()).collect();
    let base = Pcg32::new(1234, 1);
    for k in 0..4 {
        let mut worker = base.advanced(k * 100);
        let chunk: Vec<u32> = (0..100).map(|_| worker.next_u32()).collect();
        assert_eq!(chunk, all[(k as usize) * 100..(k as usize + 1) * 100]);
    }
}

proptest! {
    #[test]
    fn pcg32_advance_composes(seed: u64, stream: u64, a: u64, b: u64) {
        let rng = Pcg32::new(seed, stream);
        prop_assert_eq!(rng.advanced(a).advanced(b), rng.advanced(a.wrapping_add(b)));
    }
}

#[test]
fn pcg32_floats_have_uniform_moments() {
    let mut rng = Pcg32::new(2024, 11);
    let n = SAMPLES as f64;
    let (mut sum, mut sum_sq) = (0.0, 0.0);
    for _ in 0..SAMPLES {
        let x = f64::from(rng.next_f32());
        assert!((0.0..1.0).contains(&x));
        sum += x;
        sum_sq += x * x;
    }
    let mean = sum / n;
    let variance = sum_sq / n - mean * mean;
    // Standard errors of the mean (σ² = 1/12) and of the variance
    // ((μ₄ - σ⁴) / n with μ₄ = 1/80); the bound is 5 of them, p < 6e-7.
    let se_mean = (1.0 / 12.0 / n).sqrt();
    let se_var = ((1.0 / 80.0 - 1.0 / 144.0) / n).sqrt();
    assert!((mean - 0.5).abs() < 5.0 * se_mean, "mean {mean}");
    assert!(
        (variance - 1.0 / 12.0).abs() < 5.0 * se_var,
        "variance {variance}"
    );
}

#[test]
fn pcg32_bytes_are_uniform() {
    // High and low bytes of next_u32 in 256 bins each (two chi-square tests).
    let mut rng = Pcg32::new(77, 78);
    let mut high = vec![0.0; 256];
    let mut low = vec![0.0; 256];
    for _ in 0..SAMPLES {
        let x = rng.next_u32();
        high[(x >> 24) as usize] += 1.0;
        low[(x & 0xff) as usize] += 1.0;
    }
    let expected = vec![SAMPLES as f64 / 256.0; 256];
    assert_fits("PCG32 high byte", &high, &expected);
    assert_fits("PCG32 low byte", &low, &expected);
}

#[test]
fn floats_never_reach_one() {
    assert_eq!(unit_f32_from_bits(0), 0.0);
    assert_eq!(unit_f32_from_bits(u32::MAX), ONE_MINUS_EPSILON);
    const { assert!(ONE_MINUS_EPSILON < 1.0) };
    // Every one of the 2^24 values is exact, strictly increasing and below one.
    let mut previous = -1.0_f32;
    for top in 0..(1_u32 << 24) {
        let x = unit_f32_from_bits((top << 8) | 0xff);
        assert!(x > previous && x < 1.0, "{top}: {x}");
        assert_eq!(f64::from(x), f64::from(top) / f64::from(1_u32 << 24));
        previous = x;
    }
    let mut rng = Pcg32::new(5, 6);
    let v = rng.clone().next_vec2();
    assert_eq!(v, Vec2::new(rng.next_f32(), rng.next_f32()));
}

// ---------------------------------------------------------------------------
// Sobol'
// ---------------------------------------------------------------------------

/// Unscrambled Sobol' points from SciPy 1.17 (`qmc.Sobol(d=32, scramble=False,
/// bits=32)`, `fast_forward(i)`), which also uses new-joe-kuo-6.21201 but
/// walks the sequence in Gray-code order: its point `i` is our point `i ^ (i >> 1)`.
#[rustfmt::skip]
const SCIPY_SOBOL: [(u32, [u32; 32]); 13] = [
    (1, [0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000, 0x80000000]),
    (2, [0xc0000000, 0x40000000, 0x40000000, 0x40000000, 0xc0000000, 0xc0000000, 0x40000000, 0xc0000000, 0xc0000000, 0xc0000000, 0xc0000000, 0xc0000000, 0x40000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0x40000000, 0xc0000000, 0x40000000, 0x40000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0x40000000]),
    (3, [0x40000000, 0xc0000000, 0xc0000000, 0xc0000000, 0x40000000, 0x40000000, 0xc0000000, 0x40000000, 0x40000000, 0x40000000, 0x40000000, 0x40000000, 0xc0000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0xc0000000, 0x40000000, 0xc0000000, 0xc0000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0x40000000, 0xc0000000, 0xc0000000]),
    (5, [0xe0000000, 0xe0000000, 0x20000000, 0x60000000, 0xe0000000, 0xa0000000, 0xe0000000, 0x60000000, 0x60000000, 0x20000000, 0x60000000, 0xe0000000, 0xe0000000, 0x20000000, 0xe0000000, 0x60000000, 0xe0000000, 0x60000000, 0x60000000, 0xa0000000, 0xa0000000, 0xa0000000, 0xe0000000, 0x60000000, 0x60000000, 0x60000000, 0xe0000000, 0x20000000, 0xa0000000, 0xa0000000, 0xe0000000, 0xa0000000]),
    (100, [0x6a000000, 0x42000000, 0xc6000000, 0xba000000, 0xe2000000, 0xbe000000, 0x06000000, 0x7a000000, 0xa2000000, 0xb2000000, 0x76000000, 0xae000000, 0x7a000000, 0xda000000, 0x52000000, 0x7e000000, 0xae000000, 0xbe000000, 0xd6000000, 0x56000000, 0xc2000000, 0x66000000, 0x02000000, 0x7e000000, 0x06000000, 0x02000000, 0xf2000000, 0xaa000000, 0x3e000000, 0xba000000, 0xb6000000, 0x6a000000]),
    (1000, [0x38400000, 0x18c00000, 0x84c00000, 0xad400000, 0x47c00000, 0xe8400000, 0x0bc00000, 0xe6400000, 0x80400000, 0x11c00000, 0x15c00000, 0x41400000, 0x29400000, 0x62400000, 0x24c00000, 0x5ec00000, 0xb8400000, 0x58400000, 0xfdc00000, 0xb9c00000, 0x85c00000, 0x8cc00000, 0xf3400000, 0x8a400000, 0x95400000, 0xe8400000, 0x0a400000, 0xfac00000, 0x0f400000, 0x57400000, 0x25c00000, 0x25400000]),
    (12345, [0xa4140000, 0xd03c0000, 0x290c0000, 0x86dc0000, 0xe3740000, 0x0f140000, 0x20940000, 0x1d040000, 0xcd440000, 0x6dfc0000, 0x13040000, 0x994c0000, 0xee540000, 0xf11c0000, 0x08d40000, 0xa40c0000, 0x10040000, 0x0d0c0000, 0x51c40000, 0x57ec0000, 0x33040000, 0x14cc0000, 0x9b640000, 0xdcdc0000, 0x70fc0000, 0x4bb40000, 0x5db40000, 0x7b640000, 0x16740000, 0x678c0000, 0x49740000, 0xa97c0000]),
    (65535, [0x00010000, 0xffff0000, 0x90550000, 0xc3050000, 0x40bb0000, 0x8bbb0000, 0x84670000, 0xba490000, 0xe5250000, 0x29f50000, 0x2c0f0000, 0x12670000, 0xef370000, 0x54090000, 0x75df0000, 0x7ab10000, 0x28fb0000, 0x2fb30000, 0x21c10000, 0x70030000, 0x91030000, 0x6d010000, 0x0b430000, 0x47430000, 0x4af30000, 0xad710000, 0xbfb30000, 0xac910000, 0x15470000, 0xfa7d0000, 0xcc270000, 0x824f0000]),
    (1048653, [0xd6001800, 0xae007800, 0xaff87800, 0x135cb800, 0x73b0f800, 0x6180f800, 0xf01f0800, 0xb3f39800, 0x8bdb1800, 0xedc77800, 0x02753800, 0x8c7f1800, 0x703a1800, 0x52252800, 0xd873b800, 0x1f9ca800, 0xb88a2800, 0x280e6800, 0xb3966800, 0x9083c800, 0x3c2ad800, 0x470bc800, 0x87763800, 0x78676800, 0xe5d8a800, 0xb800f800, 0x2c057800, 0x3e95b800, 0xfeee8800, 0x1caf7800, 0x86e98800, 0x801ad800]),
    (123456789, [0xf9d46f20, 0xcadcd1a0, 0x01a3d160, 0xe8a64f20, 0xdff6b920, 0xd9f2c960, 0xf9adc120, 0xb138e220, 0xa43f45a0, 0x6767c1a0, 0xcb3b54e0, 0xfb281660, 0x5d9b1f20, 0xb8924360, 0xf8ec1720, 0xafcdb320, 0xf8a14720, 0xf60aa720, 0x2de12ba0, 0xf9c614e0, 0x3d12aae0, 0x6255e760, 0x1c048120, 0xb14c3460, 0xe46b5e20, 0x167b1da0, 0x67c92820, 0xa7b740e0, 0x74f85420, 0x233e5ae0, 0xc6de97e0, 0x7c196a20]),
    (2147483647, [0x00000002, 0xaaaaaaaa, 0x8e00eeee, 0x200200a2, 0x200fb67a, 0x80d6d6d6, 0x8020f866, 0xcc95a082, 0x880a04a2, 0xb992e922, 0xdfa0041a, 0xce06a74a, 0xcdb6077a, 0xbee00042, 0xd52d529a, 0xfd836266, 0xe186b2d6, 0xfb6db616, 0x180b600e, 0x2e00000e, 0xea02000e, 0xa3a20006, 0x0788200a, 0x25db2002, 0xdeeb5e02, 0x31606a0a, 0xd1ab1e0a, 0x1c235a0e, 0x2f61b32e, 0x341aa9e6, 0x37e26aea, 0x45ea452e]),
    (3735928559, [0x1986df8d, 0xfbdd9a3b, 0xba6d6621, 0x56e9df9f, 0x6c52a639, 0x53fd6bd7, 0xf2aca34b, 0x023e034d, 0x243f5d9d, 0x05bf8ad5, 0x84cbe049, 0x11ca7589, 0xe59f6ffb, 0x34d9d3df, 0xf13272e1, 0xfb930a89, 0x00cc5afb, 0xb2c5ae51, 0x995849c7, 0xe214688f, 0x7aa46389, 0x2a601381, 0xaaedb78d, 0xcab38989, 0xaf81fa81, 0x54f61587, 0x8b193587, 0x207a0281, 0xa4426211, 0x366f76f5, 0x35747699, 0x877a3f37]),
    (4294967295, [0x00000001, 0xffffffff, 0xc5005555, 0x50050093, 0xb00ddb9d, 0x40bbbbbb, 0xc0104477, 0x87639641, 0x84350611, 0x82ff78f1, 0x81d00a2d, 0x87239795, 0x824706d7, 0x261000a3, 0xd91d919d, 0x72c4d755, 0x9349cb97, 0x1fbefb9d, 0xb400f0eb, 0xf100000b, 0x4103000d, 0x7771000d, 0x86f59009, 0xabcd300d, 0xe4fc2505, 0xd932110b, 0x49b6c903, 0x4b504b0d, 0x437318d5, 0x323c3f39, 0x225142dd, 0x2f0de0f3]),
];

#[test]
fn sobol_matches_scipy_joe_kuo() {
    const { assert!(SOBOL_DIMENSIONS >= 32) };
    for (i, row) in SCIPY_SOBOL {
        let index = i ^ (i >> 1);
        for (dim, &want) in row.iter().enumerate() {
            assert_eq!(
                sobol_u32(index, dim),
                want,
                "SciPy point {i} (our index {index}), dimension {dim}"
            );
        }
    }
}

#[test]
fn sobol_first_points_by_hand() {
    // Dimension 0 is van der Corput; dimension 1 has s = 1, m_1 = 1, so
    // v_k = v_{k-1} ^ (v_{k-1} >> 1): v = 1/2, 3/4, 5/8, ...
    let vdc = [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875];
    let second = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
    for i in 0..8 {
        assert_eq!(sobol(i, 0), vdc[i as usize]);
        assert_eq!(sobol(i, 1), second[i as usize]);
    }
}

/// Whether `cells` holds every value of `0..count` exactly once.
fn is_permutation(cells: impl Iterator<Item = u64>, count: u64) -> bool {
    let mut seen = vec![false; count as usize];
    for c in cells {
        if c >= count || seen[c as usize] {
            return false;
        }
        seen[c as usize] = true;
    }
    seen.iter().all(|&s| s)
}

#[test]
fn sobol_dimensions_are_01_sequences() {
    // Every block of 2^m consecutive points (starting at a multiple of 2^m)
    // puts one point in each of the 2^m strata of [0, 1), for every dimension,
    // plain and scrambled.
    for sequence in [
        Sobol::new(),
        Sobol::scrambled(1),
        Sobol::scrambled(0xdead_beef),
    ] {
        for dim in 0..SOBOL_DIMENSIONS {
            for m in 0..=10_u32 {
                for block in 0..3_u32 {
                    let start = block << m;
                    let cells = (start..start + (1 << m)).map(|i| {
                        (f64::from(sequence.sample(i, dim)) * f64::from(1_u32 << m)) as u64
                    });
                    assert!(
                        is_permutation(cells, 1 << m),
                        "{sequence:?}: dimension {dim}, block {block} of 2^{m} points is not stratified"
                    );
                }
            }
        }
    }
}

/// Whether the first 2^m points of dimensions (d0, d1) form a (0, m, 2)-net:
/// every elementary interval 2^-m1 × 2^-(m - m1) holds exactly one point.
fn is_0m2_net(sample: impl Fn(u32, usize) -> f32, (d0, d1): (usize, usize), m: u32) -> bool {
    (0..=m).all(|m1| {
        let m2 = m - m1;
        let cells = (0..1_u32 << m).map(|i| {
            let x = (f64::from(sample(i, d0)) * f64::from(1_u32 << m1)) as u64;
            let y = (f64::from(sample(i, d1)) * f64::from(1_u32 << m2)) as u64;
            x * (1 << m2) + y
        });
        is_permutation(cells, 1 << m)
    })
}

#[test]
fn sobol_first_two_dimensions_form_0m2_nets() {
    for sequence in [Sobol::new(), Sobol::scrambled(3), Sobol::scrambled(4)] {
        for m in 0..=10 {
            assert!(
                is_0m2_net(|i, d| sequence.sample(i, d), (0, 1), m),
                "{sequence:?}: the first 2^{m} points are not a (0, {m}, 2)-net"
            );
        }
    }
    // The property is specific: dimensions 2 and 3 are not a (0, m, 2)-net
    // for every m (their t-value is positive), so the check can fail.
    assert!((0..=10).any(|m| !is_0m2_net(sobol, (2, 3), m)));
}

#[test]
fn sobol_scrambles_differ_by_seed() {
    let (a, b, plain) = (Sobol::scrambled(1), Sobol::scrambled(2), Sobol::new());
    for dim in [0, 1, 7, SOBOL_DIMENSIONS - 1] {
        let same_ab = (0..1024)
            .filter(|&i| a.sample_u32(i, dim) == b.sample_u32(i, dim))
            .count();
        let same_plain = (0..1024)
            .filter(|&i| a.sample_u32(i, dim) == plain.sample_u32(i, dim))
            .count();
        assert!(
            same_ab <= 1 && same_plain <= 1,
            "dimension {dim}: {same_ab}, {same_plain}"
        );
        assert!((0..1024).all(|i| a.sample(i, dim) < 1.0));
    }
    // The same seed is the same scramble; dimensions are scrambled independently.
    assert_eq!(Sobol::scrambled(1).sample_u32(77, 3), a.sample_u32(77, 3));
    let dims_agree = (0..1024)
        .filter(|&i| a.sample_u32(i, 2) ^ sobol_u32(i, 2) == a.sample_u32(i, 3) ^ sobol_u32(i, 3))
        .count();
    assert!(dims_agree < 1024);
}

#[test]
fn nested_uniform_scramble_permutes_every_level() {
    // For each seed, the top m bits of the output depend bijectively on the top m bits of the input.
    for seed in [0_u32, 1, 0x1234_5678, u32::MAX] {
        for m in [1_u32, 4, 12] {
            let cells = (0..1_u32 << m)
                .map(|k| u64::from(nested_uniform_scramble(k << (32 - m), seed) >> (32 - m)));
            assert!(is_permutation(cells, 1 << m), "seed {seed}, level {m}");
        }
    }
}

// ---------------------------------------------------------------------------
// Halton
// ---------------------------------------------------------------------------

#[test]
fn halton_bases_are_the_first_primes() {
    const { assert!(HALTON_DIMENSIONS >= 32) };
    let mut primes = Vec::new();
    let mut candidate = 2_u32;
    while primes.len() < HALTON_DIMENSIONS {
        if primes.iter().all(|p| !candidate.is_multiple_of(*p)) {
            primes.push(candidate);
        }
        candidate += 1;
    }
    for (dim, &p) in primes.iter().enumerate() {
        assert_eq!(Halton::base(dim), p, "dimension {dim}");
    }
}

#[test]
fn halton_first_points_by_hand() {
    // Base 2: 1 = 1₂ -> 0.1₂, 2 = 10₂ -> 0.01₂, 3 = 11₂ -> 0.11₂, ...
    let base2 = [
        0.0,
        1.0 / 2.0,
        1.0 / 4.0,
        3.0 / 4.0,
        1.0 / 8.0,
        5.0 / 8.0,
        3.0 / 8.0,
        7.0 / 8.0,
    ];
    // Base 3: 1 -> 0.1₃, 2 -> 0.2₃, 3 = 10₃ -> 0.01₃, 4 = 11₃ -> 0.11₃, ...
    let base3 = [0.0, 3.0, 6.0, 1.0, 4.0, 7.0, 2.0, 5.0, 8.0].map(|k| k / 9.0);
    for (i, want) in base2.iter().enumerate() {
        assert_eq!(f64::from(halton(i as u64, 0)), *want, "base 2, index {i}");
    }
    for (i, want) in base3.iter().enumerate() {
        let got = f64::from(halton(i as u64, 1));
        assert!(
            (got - want).abs() < 1e-7 && got <= *want,
            "base 3, index {i}: {got}"
        );
    }
    // 1234 = 14414₅, mirrored 0.41441₅ = 2746 / 3125.
    assert!((f64::from(radical_inverse(5, 1234)) - 2746.0 / 3125.0).abs() < 1e-7);
    assert_eq!(Halton::new().sample(11, 4), halton(11, 4));
}

#[test]
fn halton_is_stratified_in_powers_of_its_base() {
    // The first b^k points of dimension d hold one point per interval
    // [j / b^k, (j + 1) / b^k). Plain points sit on the interval starts, so
    // they are rounded; scrambled ones lie inside and are floored.
    for dim in 0..8 {
        let b = u64::from(Halton::base(dim));
        let mut count = b;
        while count <= 4096 {
            let plain =
                (0..count).map(|i| (f64::from(halton(i, dim)) * count as f64).round() as u64);
            assert!(
                is_permutation(plain, count),
                "plain, dimension {dim}, {count} points"
            );
            for seed in [1, 2] {
                let halton = Halton::scrambled(seed);
                let cells =
                    (0..count).map(|i| (f64::from(halton.sample(i, dim)) * count as f64) as u64);
                assert!(
                    is_permutation(cells, count),
                    "scrambled {seed}, dimension {dim}, {count} points"
                );
            }
            count *= b;
        }
    }
}

#[test]
fn halton_first_two_dimensions_are_stratified_jointly() {
    // The first 2^a 3^c points of dimensions 0 and 1 put one point in each
    // box [i / 2^a, (i+1) / 2^a) × [j / 3^c, (j+1) / 3^c) (Chinese remainder theorem).
    for sequence in [Halton::new(), Halton::scrambled(9)] {
        for a in 0..=5_u32 {
            for c in 0..=3_u32 {
                let (nx, ny) = (1_u64 << a, 3_u64.pow(c));
                // A nudge of 1e-4 of a box puts plain points sitting on a box's start (and
                // rounded down to f32) inside it; no point lies that close below a box edge.
                let cells = (0..nx * ny).map(|i| {
                    let x = (f64::from(sequence.sample(i, 0)) * nx as f64 + 1e-4) as u64;
                    let y = (f64::from(sequence.sample(i, 1)) * ny as f64 + 1e-4) as u64;
                    x * ny + y
                });
                assert!(
                    is_permutation(cells, nx * ny),
                    "{sequence:?}: 2^{a} 3^{c} points"
                );
            }
        }
    }
}

#[test]
fn halton_scrambles_differ_by_seed_and_stay_below_one() {
    let (a, b) = (Halton::scrambled(1), Halton::scrambled(2));
    for dim in [0, 1, 5, HALTON_DIMENSIONS - 1] {
        let same = (0..1000)
            .filter(|&i| a.sample(i, dim) == b.sample(i, dim))
            .count();
        assert!(same <= 2, "dimension {dim}: {same} equal values");
        assert!((0..1000).all(|i| (0.0..1.0).contains(&a.sample(i, dim))));
    }
    assert!((0..1000).all(|i| halton(u64::MAX - i, 0) < 1.0));
}

// ---------------------------------------------------------------------------
// Samplers
// ---------------------------------------------------------------------------

#[test]
fn sequence_sampler_walks_dimensions_then_pads() {
    let sobol = Sobol::scrambled(5);
    let mut sampler = SequenceSampler::new(sobol, 42);
    sampler.start_point(9);
    for dim in 0..SOBOL_DIMENSIONS {
        assert_eq!(sampler.dimension(), dim);
        assert_eq!(sampler.next_1d(), sobol.sample(9, dim));
    }
    let padding: Vec<f32> = (0..8).map(|_| sampler.next_1d()).collect();
    assert!(padding.iter().all(|x| (0.0..1.0).contains(x)));
    // Restarting the point gives the same numbers; another point different padding.
    sampler.start_point(9);
    let again: Vec<f32> = (0..SOBOL_DIMENSIONS + 8)
        .map(|_| sampler.next_1d())
        .collect();
    assert_eq!(again[SOBOL_DIMENSIONS..], padding[..]);
    sampler.start_point(10);
    let other: Vec<f32> = (0..SOBOL_DIMENSIONS + 8)
        .map(|_| sampler.next_1d())
        .collect();
    assert_ne!(other[SOBOL_DIMENSIONS..], padding[..]);

    let mut plain = SequenceSampler::new(Halton::new(), 0);
    plain.start_point(5);
    assert_eq!(plain.next_2d(), Vec2::new(halton(5, 0), halton(5, 1)));
    assert_eq!(plain.index(), 5);
    assert_eq!(Halton::new().dimensions(), HALTON_DIMENSIONS);
}

#[test]
fn samplers_are_interchangeable() {
    fn mean_cosine(sampler: &mut dyn Sampler, n: usize) -> f64 {
        (0..n)
            .map(|_| f64::from(sample_cosine_hemisphere(sampler.next_2d()).z))
            .sum::<f64>()
            / n as f64
    }
    // E[cos θ] under the cosine density is 2/3.
    let n = 4096;
    let mut rng = Pcg32::new(3, 4);
    let mut sobol = SequenceSampler::new(Sobol::scrambled(3), 3);
    let mut halton = SequenceSampler::new(Halton::scrambled(3), 3);
    assert!((mean_cosine(&mut rng, n) - 2.0 / 3.0).abs() < 0.02);
    // Low-discrepancy points: one 2D point per index, dimensions 0 and 1.
    let lds = |s: &mut dyn FnMut(u64) -> Vec2| {
        (0..n as u64)
            .map(|i| f64::from(sample_cosine_hemisphere(s(i)).z))
            .sum::<f64>()
            / n as f64
    };
    let sobol_mean = lds(&mut |i| {
        sobol.start_point(i);
        sobol.next_2d()
    });
    let halton_mean = lds(&mut |i| {
        halton.start_point(i);
        halton.next_2d()
    });
    assert!((sobol_mean - 2.0 / 3.0).abs() < 1e-3, "Sobol' {sobol_mean}");
    assert!(
        (halton_mean - 2.0 / 3.0).abs() < 2e-3,
        "Halton {halton_mean}"
    );
    let mut pcg = Pcg32::new(1, 2);
    let mut copy = pcg.clone();
    assert_eq!(Sampler::next_2d(&mut pcg), copy.next_vec2());
    assert_eq!(Sampler::next_1d(&mut pcg), copy.next_f32());
}

// ---------------------------------------------------------------------------
// Frames
// ---------------------------------------------------------------------------

/// Unit normals: uniform over the sphere, tilted a hair from ±Z, or exactly ±Z or on the equator.
fn unit_normal() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        (-1.0_f32..=1.0, 0.0_f32..std::f32::consts::TAU).prop_map(|(z, phi)| {
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z).normalize()
        }),
        (-1e-3_f32..1e-3, -1e-3_f32..1e-3, prop::bool::ANY).prop_map(|(x, y, up)| Vec3::new(
            x,
            y,
            if up { 1.0 } else { -1.0 }
        )
        .normalize()),
        prop::sample::select(vec![
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::X,
            Vec3::NEG_Y,
            Vec3::new(0.6, 0.8, 0.0),
            Vec3::new(0.6, 0.8, -0.0),
            Vec3::new(0.0, 0.0, 1.0 - f32::EPSILON).normalize(),
        ]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn frame_is_orthonormal_and_right_handed(n in unit_normal(), v in prop::array::uniform3(-10.0_f32..10.0)) {
        let frame = Frame::from_normal(n);
        let tol = 1e-5;
        prop_assert!(frame.s.is_finite() && frame.t.is_finite());
        prop_assert!((frame.s.length() - 1.0).abs() < tol, "|s| = {}", frame.s.length());
        prop_assert!((frame.t.length() - 1.0).abs() < tol, "|t| = {}", frame.t.length());
        prop_assert!(frame.s.dot(frame.t).abs() < tol);
        prop_assert!(frame.s.dot(n).abs() < tol);
        prop_assert!(frame.t.dot(n).abs() < tol);
        prop_assert!(frame.s.cross(frame.t).distance(n) < tol, "s × t = {} for n = {n}", frame.s.cross(frame.t));
        prop_assert_eq!(frame.n, n);
        let v = Vec3::from_array(v);
        prop_assert!(frame.to_world(frame.to_local(v)).distance(v) < 1e-4 * v.length().max(1.0));
        prop_assert!((frame.to_local(n) - Vec3::Z).length() < tol);
    }
}
