//! Duvenhage et al. 2010, sections 1.2 and 4.2: the normalised 2D Gaussian over the scatter angle, its triangle volume, and its relation to Beckmann's α.

mod support;

use glam::{Vec2, Vec3};
use lustre_brdf::microfacet::Distribution;
use lustre_brdf::scatter_distribution::ScatterDistribution;
use lustre_geometry::material::MicrofacetDistribution;
use support::Rng;

#[test]
fn gaussian_integrates_to_one_over_the_plane() {
    for variance in [0.001f32, 0.02, 0.3] {
        let g = ScatterDistribution::new(variance).unwrap();
        let s = f64::from(variance).sqrt();
        // Midpoint rule on [-10σ, 10σ]² with 400² cells.
        let n = 400;
        let h = 20.0 * s / n as f64;
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let p = Vec2::new(
                    (-10.0 * s + (i as f64 + 0.5) * h) as f32,
                    (-10.0 * s + (j as f64 + 0.5) * h) as f32,
                );
                sum += f64::from(g.density(p)) * h * h;
            }
        }
        assert!((sum - 1.0).abs() < 1e-4, "σ² = {variance}: ∫ρ = {sum}");
        assert!((g.density(Vec2::ZERO) - g.peak()).abs() < 1e-6 * g.peak());
    }
}

#[test]
fn exact_triangle_volume_agrees_with_brute_force_and_limits() {
    let g = ScatterDistribution::new(0.01).unwrap();
    // A huge triangle around the origin holds all the mass.
    let big = g.triangle_volume_exact(
        Vec2::new(-50.0, -50.0),
        Vec2::new(50.0, -50.0),
        Vec2::new(0.0, 80.0),
    );
    assert!((big - 1.0).abs() < 1e-9, "{big}");
    // Brute force: midpoint rule over the bounding box with an inside test.
    let tris = [
        [
            Vec2::new(-0.1, -0.05),
            Vec2::new(0.12, -0.02),
            Vec2::new(0.0, 0.15),
        ],
        [
            Vec2::new(0.05, 0.02),
            Vec2::new(0.3, 0.1),
            Vec2::new(0.1, 0.25),
        ],
    ];
    for [a, b, c] in tris {
        let exact = g.triangle_volume_exact(a, b, c);
        let inside = |p: Vec2| {
            let s = |u: Vec2, v: Vec2| (v - u).perp_dot(p - u);
            let (d1, d2, d3) = (s(a, b), s(b, c), s(c, a));
            (d1 >= 0.0 && d2 >= 0.0 && d3 >= 0.0) || (d1 <= 0.0 && d2 <= 0.0 && d3 <= 0.0)
        };
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let n = 1000;
        let (hx, hy) = ((hi.x - lo.x) / n as f32, (hi.y - lo.y) / n as f32);
        let mut brute = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let p = lo + Vec2::new((i as f32 + 0.5) * hx, (j as f32 + 0.5) * hy);
                if inside(p) {
                    brute += f64::from(g.density(p)) * f64::from(hx * hy);
                }
            }
        }
        // The brute force's own error: the triangle's boundary cells, ~3n of n² cells.
        assert!(
            (exact - brute).abs() < 5e-3 * exact.max(0.01),
            "{exact} vs {brute}"
        );
    }
}

/// The error bound of planar facets through a function's values: on a facet T of diameter h, linear interpolation errs by at most ½ M₂ h², M₂ the largest second directional derivative, so the volume errs by at most ½ M₂ h² area(T). For the Gaussian M₂ = peak/σ² (at the centre). The approximation's facets have diameter at most the largest distance between O, A, B, C.
fn facet_bound(g: &ScatterDistribution, a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let pts = [Vec2::ZERO, a, b, c];
    let mut diam = 0.0f32;
    for p in pts {
        for q in pts {
            diam = diam.max(p.distance(q));
        }
    }
    let m2 = f64::from(g.peak()) / f64::from(g.variance);
    // Facets cover at most the triangle plus its fan from O: area ≤ area(OAB) + area(OBC) + area(OCA).
    let fan = 0.5 * f64::from(a.perp_dot(b).abs() + b.perp_dot(c).abs() + c.perp_dot(a).abs());
    0.5 * m2 * f64::from(diam * diam) * fan
}

#[test]
fn triangle_volume_approximation_is_within_the_facet_error_bound() {
    let g = ScatterDistribution::new(0.02).unwrap();
    let s = 0.02f32.sqrt();
    let mut rng = Rng::new(2010);
    let (mut inside_cases, mut outside_cases) = (0, 0);
    let mut worst_ratio = 0.0f64;
    for k in 0..3000 {
        // Triangles of diameter up to σ/2 placed near the origin (even k,
        // mostly the inside case) or within 1.5σ of it (odd k, mostly
        // outside), where the facet bound (½ M₂ h² per unit area, about
        // h²/(2σ²) of the volume) is informative.
        let reach = if k % 2 == 0 { 0.1 } else { 1.5 };
        let centre = Vec2::new(rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0) * reach * s;
        let v: Vec<Vec2> = (0..3)
            .map(|_| centre + Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * 0.35 * s)
            .collect();
        let (a, b, c) = (v[0], v[1], v[2]);
        if (b - a).perp_dot(c - a).abs() < 1e-3 * s * s {
            continue;
        }
        let approx = f64::from(g.triangle_volume(a, b, c));
        let exact = g.triangle_volume_exact(a, b, c);
        let bound = facet_bound(&g, a, b, c);
        assert!(
            (approx - exact).abs() <= bound,
            "{a} {b} {c}: approx {approx}, exact {exact}, bound {bound}"
        );
        worst_ratio = worst_ratio.max((approx - exact).abs() / bound);
        let sgn = |u: Vec2, w: Vec2| (w - u).perp_dot(-u);
        let ins = [sgn(a, b), sgn(b, c), sgn(c, a)];
        if ins.iter().all(|&x| x > 0.0) || ins.iter().all(|&x| x < 0.0) {
            inside_cases += 1;
        } else {
            outside_cases += 1;
        }
    }
    eprintln!("largest error / bound: {worst_ratio}");
    assert!(
        inside_cases > 200 && outside_cases > 200,
        "{inside_cases} {outside_cases}"
    );
}

#[test]
fn triangle_volume_approximation_converges_at_second_order() {
    // Planar facets are exact for linear functions, so halving the triangle
    // (about the origin, inside case; and off the origin, outside case)
    // divides the error by about four.
    let g = ScatterDistribution::new(0.02).unwrap();
    let s = 0.02f32.sqrt();
    let shapes = [
        [
            Vec2::new(1.0, 0.1),
            Vec2::new(-0.6, 0.9),
            Vec2::new(-0.4, -1.1),
        ],
        [
            Vec2::new(0.3, 0.4),
            Vec2::new(1.4, 0.6),
            Vec2::new(0.7, 1.5),
        ],
    ];
    for shape in shapes {
        let err = |scale: f32| {
            let [a, b, c] = shape.map(|p| p * scale * s);
            let approx = f64::from(g.triangle_volume(a, b, c));
            (approx - g.triangle_volume_exact(a, b, c)).abs() / g.triangle_volume_exact(a, b, c)
        };
        let (e1, e2, e4) = (err(0.4), err(0.2), err(0.1));
        for (big, small) in [(e1, e2), (e2, e4)] {
            let order = (big / small).log2();
            assert!(
                (1.7..2.3).contains(&order),
                "{shape:?}: errors {e1} {e2} {e4}"
            );
        }
    }
    // A domain far larger than the Gaussian: facets overshoot, the clamp gives the exact 1.
    let (a, b, c) = (
        Vec2::new(-5.0, -5.0),
        Vec2::new(5.0, -5.0),
        Vec2::new(0.0, 8.0),
    );
    assert_eq!(g.triangle_volume(a, b, c), 1.0);
    assert!((g.triangle_volume_exact(a, b, c) - 1.0).abs() < 1e-9);
}

#[test]
fn volume_is_continuous_across_the_flux_triangle_edge() {
    // The paper's requirement: no jump between fragments just inside and just outside.
    let g = ScatterDistribution::new(0.02).unwrap();
    let (a, b, c) = (
        Vec2::new(-0.2, 0.0),
        Vec2::new(0.25, 0.0),
        Vec2::new(0.05, 0.3),
    );
    let eps = 1e-5;
    for x in [-0.15f32, 0.0, 0.1, 0.2] {
        // Shift the domain so the origin sits just inside / outside edge AB.
        let o_in = Vec2::new(x, eps);
        let o_out = Vec2::new(x, -eps);
        let vin = g.triangle_volume(a - o_in, b - o_in, c - o_in);
        let vout = g.triangle_volume(a - o_out, b - o_out, c - o_out);
        assert!((vin - vout).abs() < 1e-3 * vin, "x = {x}: {vin} vs {vout}");
    }
}

#[test]
fn beckmann_relation_holds_for_sampled_normals_at_normal_incidence() {
    // Sample Beckmann normals (density D cos θh), reflect wo = +Z, and measure
    // the per-axis variance of the scatter angle: σ² = 2α² for small α.
    for alpha in [0.02f32, 0.05] {
        let dist = Distribution::new(MicrofacetDistribution::Beckmann, alpha, "test").unwrap();
        let mut rng = Rng::new(4242);
        let n = 200_000;
        let (mut sx, mut sy) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let h = dist.sample_h(rng.vec2());
            let wi = 2.0 * h.z * h - Vec3::Z;
            let theta = f64::from(wi.z.clamp(-1.0, 1.0).acos());
            let r = f64::from((wi.x * wi.x + wi.y * wi.y).sqrt()).max(1e-30);
            sx += (theta * f64::from(wi.x) / r).powi(2);
            sy += (theta * f64::from(wi.y) / r).powi(2);
        }
        let want = f64::from(
            ScatterDistribution::from_beckmann_alpha(alpha)
                .unwrap()
                .variance,
        );
        // Monte-Carlo error of a variance: √(2/n) = 0.3 %; small-angle
        // corrections O(α²): below 1 %. Tolerance 2 %.
        for m in [sx / n as f64, sy / n as f64] {
            assert!((m / want - 1.0).abs() < 0.02, "α = {alpha}: {m} vs {want}");
        }
        let slope = ScatterDistribution::from_slope_variance(alpha * alpha / 2.0).unwrap();
        assert!((slope.variance - want as f32).abs() < 1e-9);
    }
    assert!(ScatterDistribution::new(0.0).is_err());
    assert!(ScatterDistribution::from_beckmann_alpha(f32::NAN).is_err());
}

/// Snell's law for the unit direction `w` through a facet with unit normal `h` facing it, `eta` = far index over near index.
fn refract(w: Vec3, h: Vec3, eta: f32) -> Vec3 {
    let cos_i = -w.dot(h);
    let r = 1.0 / eta;
    let cos_t = (1.0 - r * r * (1.0 - cos_i * cos_i)).sqrt();
    (r * w + (r * cos_i - cos_t) * h).normalize()
}

/// Per-axis mean square of the angle of `d` from -Z.
fn angle_moments(d: Vec3) -> (f64, f64) {
    let theta = f64::from((-d.z).clamp(-1.0, 1.0).acos());
    let r = f64::from((d.x * d.x + d.y * d.y).sqrt()).max(1e-30);
    (
        (theta * f64::from(d.x) / r).powi(2),
        (theta * f64::from(d.y) / r).powi(2),
    )
}

#[test]
fn refracted_and_thin_slab_relations_hold_for_sampled_normals_at_normal_incidence() {
    // Light going down (-Z) through Beckmann facets: through one interface
    // σ² = (1 - 1/η)² α²/2, through a slab with both faces rough
    // σ² = (η - 1)² α².
    for (alpha, eta) in [(0.05f32, 1.5f32), (0.1, 1.33)] {
        let dist = Distribution::new(MicrofacetDistribution::Beckmann, alpha, "test").unwrap();
        let mut rng = Rng::new(77);
        let n = 200_000;
        let (mut one, mut slab) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
        for _ in 0..n {
            let h1 = dist.sample_h(rng.vec2());
            let inside = refract(-Vec3::Z, h1, eta);
            let (x, y) = angle_moments(inside);
            one = (one.0 + x, one.1 + y);
            // The exit face's facet normal faces the ray coming from inside.
            let h2 = dist.sample_h(rng.vec2());
            let out = refract(inside, h2, 1.0 / eta);
            let (x, y) = angle_moments(out);
            slab = (slab.0 + x, slab.1 + y);
        }
        let want_one = f64::from(
            ScatterDistribution::from_beckmann_alpha_refracted(alpha, eta)
                .unwrap()
                .variance,
        );
        let want_slab = f64::from(
            ScatterDistribution::from_beckmann_alpha_thin_slab(alpha, eta)
                .unwrap()
                .variance,
        );
        // Monte-Carlo error of a variance √(2/n) = 0.3 %; small-angle
        // corrections O(α²) below 1 %: 2 %, as for reflection.
        for (m, want) in [
            (one.0 / n as f64, want_one),
            (one.1 / n as f64, want_one),
            (slab.0 / n as f64, want_slab),
            (slab.1 / n as f64, want_slab),
        ] {
            assert!(
                (m / want - 1.0).abs() < 0.02,
                "α = {alpha}, η = {eta}: {m} vs {want}"
            );
        }
    }
    assert!(ScatterDistribution::from_beckmann_alpha_refracted(0.1, 1.0).is_err());
    assert!(ScatterDistribution::from_beckmann_alpha_thin_slab(0.1, 1.0).is_err());
}

#[test]
fn integrated_triangle_volume_is_within_1e_3_of_the_exact_one() {
    // Random triangles of scatter angles around and beside the peak, from
    // much narrower than σ to much wider, for the σ of Beckmann α 0.02 to 0.5.
    let mut rng = Rng::new(11);
    let mut worst = 0.0f64;
    for variance in [0.0008f32, 0.02, 0.5] {
        let g = ScatterDistribution::new(variance).unwrap();
        let s = variance.sqrt();
        for _ in 0..2000 {
            let scale = s * 10f32.powf(3.0 * rng.f32() - 1.5);
            let offset = Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * 4.0 * scale;
            let mut corner = || offset + Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * 2.0 * scale;
            let (a, b, c) = (corner(), corner(), corner());
            let exact = g.triangle_volume_exact(a, b, c);
            let integrated = f64::from(g.triangle_volume_integrated(a, b, c));
            let err = (integrated - exact).abs();
            worst = worst.max(err);
            assert!(
                err <= 1e-3,
                "σ² {variance}: {a} {b} {c}: integrated {integrated}, exact {exact}"
            );
        }
    }
    eprintln!("integrated against exact: worst {worst:.2e}");
}
