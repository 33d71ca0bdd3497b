//! Photon Maps' boundary correction (`lustre_density::boundary`): the probed area fraction against the exact area of a disc clipped by a polygon, and the corrected estimate of a uniform impact density at a corner, on an edge and inside a square, whose mean is known exactly.

use std::f64::consts::PI;

use glam::{DVec2, Vec2, Vec3};
use lustre_density::boundary::{DIRECTIONS, DiscPattern};
use lustre_density::{ImpactMap, PrimaryRay, RaySegment, RaySet, SegmentHit};
use lustre_geometry::{Bvh, Rgb, WorldTriangle};

/// A small deterministic generator (a 64-bit LCG's high bits), uniform on `[0, 1)`.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A world triangle with a flat normal.
fn triangle(positions: [Vec3; 3]) -> WorldTriangle {
    let n = (positions[1] - positions[0])
        .cross(positions[2] - positions[0])
        .normalize();
    WorldTriangle {
        positions,
        normals: [n; 3],
        uvs: [Vec2::ZERO; 3],
        surface: 0,
        material: 0,
    }
}

/// A convex polygon in the plane `y = height` (points `(x, z)`), fanned into triangles.
fn fan(polygon: &[DVec2], height: f32) -> Vec<WorldTriangle> {
    let p = |q: DVec2| Vec3::new(q.x as f32, height, q.y as f32);
    (1..polygon.len() - 1)
        .map(|i| triangle([p(polygon[0]), p(polygon[i]), p(polygon[i + 1])]))
        .collect()
}

/// The area of the disc of radius `r` at the origin inside the triangle `(0, a, b)`, signed like the triangle.
fn disc_in_triangle(a: DVec2, b: DVec2, r: f64) -> f64 {
    let sector = |u: DVec2, v: DVec2| 0.5 * r * r * u.perp_dot(v).atan2(u.dot(v));
    let d = b - a;
    let (qa, qb, qc) = (d.dot(d), a.dot(d), a.dot(a) - r * r);
    let disc = qb * qb - qa * qc;
    if disc <= 0.0 {
        return sector(a, b);
    }
    let s = disc.sqrt();
    let (t1, t2) = ((-qb - s) / qa, (-qb + s) / qa);
    if t2 <= 0.0 || t1 >= 1.0 {
        return sector(a, b);
    }
    let p1 = a + t1.max(0.0) * d;
    let p2 = a + t2.min(1.0) * d;
    sector(a, p1) + 0.5 * p1.perp_dot(p2) + sector(p2, b)
}

/// The exact area of the disc of radius `r` at `c` inside a polygon (any winding).
fn clipped_disc_area(polygon: &[DVec2], c: DVec2, r: f64) -> f64 {
    (0..polygon.len())
        .map(|i| disc_in_triangle(polygon[i] - c, polygon[(i + 1) % polygon.len()] - c, r))
        .sum::<f64>()
        .abs()
}

/// The unit square and a convex pentagon whose edges run at odd angles.
fn polygons() -> [Vec<DVec2>; 2] {
    let square = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, 0.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(0.0, 1.0),
    ];
    let pentagon = (0..5)
        .map(|i| {
            let a = 0.37 + 2.0 * PI * i as f64 / 5.0 + 0.2 * (i as f64).sin();
            DVec2::new(0.5 + 0.6 * a.cos(), 0.4 + 0.5 * a.sin())
        })
        .collect();
    [square, pentagon]
}

#[test]
fn the_exact_clipped_disc_area_is_right_where_it_is_known() {
    let [square, _] = polygons();
    let r = 0.2;
    let cases = [
        (DVec2::new(0.5, 0.5), 1.0),
        (DVec2::new(0.5, 0.0), 0.5),
        (DVec2::new(0.0, 0.0), 0.25),
        (DVec2::new(1.0, 1.0), 0.25),
        (DVec2::new(0.5, -0.1), 1.0 / 3.0 - 3f64.sqrt() / (4.0 * PI)),
        (DVec2::new(3.0, 3.0), 0.0),
    ];
    for (c, fraction) in cases {
        let got = clipped_disc_area(&square, c, r) / (PI * r * r);
        assert!(
            (got - fraction).abs() < 1e-12,
            "at {c}: {got} against {fraction}"
        );
    }
}

/// The probed fraction (64 directions) against the exact clipped-disc area at 2000 random discs over the square and the pentagon: within 0.01 of `π r²` everywhere, 0.002 in RMS (each direction's covered radii are exact, so the error is the midpoint rule's over the angle, largest where an edge's end or a corner makes the radius kink); ½ on an edge and ¼ at the square's corners up to rounding, where the directions' symmetry splits the disc evenly.
#[test]
fn probed_fraction_matches_the_exact_clipped_disc_area() {
    assert_eq!(DIRECTIONS, 64);
    let pattern = DiscPattern::default();
    let mut rng = Lcg(17);
    let (mut worst, mut sum2, mut count) = (0.0f64, 0.0f64, 0usize);
    for polygon in polygons() {
        let bvh = Bvh::from_triangles(fan(&polygon, 0.0));
        for _ in 0..1000 {
            let c = DVec2::new(1.6 * rng.next() - 0.3, 1.6 * rng.next() - 0.3);
            let r = 0.02 + 0.4 * rng.next();
            let exact = clipped_disc_area(&polygon, c, r) / (PI * r * r);
            let x = Vec3::new(c.x as f32, 0.0, c.y as f32);
            let got = pattern.fraction(&bvh, x, Vec3::Y, r as f32).unwrap_or(0.0);
            let error = got - exact;
            worst = worst.max(error.abs());
            sum2 += error * error;
            count += 1;
        }
        // A vertex on each edge, the disc reaching no other edge: exactly half.
        for i in 0..polygon.len() {
            let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
            let c = 0.5 * (a + b);
            let x = Vec3::new(c.x as f32, 0.0, c.y as f32);
            let got = pattern
                .fraction(&bvh, x, Vec3::Y, 0.05)
                .expect("on the polygon");
            assert!((got - 0.5).abs() <= 1e-6, "on edge {i}: {got}");
        }
    }
    let rms = (sum2 / count as f64).sqrt();
    eprintln!(
        "probed fraction against the exact area: worst {worst:.4}, RMS {rms:.4} of π r² over {count} discs"
    );
    assert!(worst <= 0.01, "worst {worst}");
    assert!(rms <= 0.002, "RMS {rms}");
    let [square, _] = polygons();
    let bvh = Bvh::from_triangles(fan(&square, 0.0));
    for corner in &square {
        let x = Vec3::new(corner.x as f32, 0.0, corner.y as f32);
        let got = pattern
            .fraction(&bvh, x, Vec3::Y, 0.3)
            .expect("on the square");
        assert!((got - 0.25).abs() <= 1e-6, "at {corner}: {got}");
    }
    // Nothing to probe: no fraction.
    assert_eq!(
        pattern.fraction(&bvh, Vec3::new(5.0, 0.0, 5.0), Vec3::Y, 0.3),
        None
    );
}

/// A plane tilted from the vertex normal but within the filter counts its own area in the ball, not its projection (its part of each direction weighs `1 / cos`; the radii are exact, so the ellipse the ball's disc projects to is too); one tilted past the filter counts nothing; a second compatible layer under the first (the ceiling above the light) is counted once.
#[test]
fn tilted_planes_count_their_own_area_and_layers_count_once() {
    let pattern = DiscPattern::default();
    let big = [
        DVec2::new(-2.0, -2.0),
        DVec2::new(2.0, -2.0),
        DVec2::new(2.0, 2.0),
        DVec2::new(-2.0, 2.0),
    ];
    let plane = Bvh::from_triangles(fan(&big, 0.0));
    for cos in [0.95f32, 0.92] {
        let n = Vec3::new((1.0 - cos * cos).sqrt(), cos, 0.0);
        let got = pattern
            .fraction(&plane, Vec3::ZERO, n, 0.3)
            .expect("compatible");
        eprintln!("tilt cos {cos}: fraction {got:.4}");
        assert!((got - 1.0).abs() <= 1e-4, "cos {cos}: {got}");
    }
    let n = Vec3::new(0.6, 0.8, 0.0);
    assert_eq!(pattern.fraction(&plane, Vec3::ZERO, n, 0.3), None);
    let mut layers = fan(&big, 0.0);
    layers.extend(fan(&big, 0.01));
    let layers = Bvh::from_triangles(layers);
    let got = pattern
        .fraction(&layers, Vec3::ZERO, Vec3::Y, 0.3)
        .expect("compatible");
    assert!((got - 1.0).abs() <= 1e-6, "two layers: {got}");
}

/// `count` impacts uniform over the unit square at `y = 0` from above, power `power` each.
fn uniform_impacts(rng: &mut Lcg, count: usize, power: f32) -> RaySet {
    let rays = (0..count)
        .map(|j| {
            let position = Vec3::new(rng.next() as f32, 0.0, rng.next() as f32);
            let hit = SegmentHit {
                triangle: 0,
                mesh: 0,
                mobile: false,
                position,
                normal: Vec3::Y,
                distance: 1.0,
            };
            PrimaryRay {
                light: 0,
                index: j as u64,
                segments: vec![RaySegment::new(
                    position + Vec3::Y,
                    Vec3::NEG_Y,
                    Some(hit),
                    Rgb::splat(power),
                )],
            }
        })
        .collect();
    RaySet {
        rays,
        emitted_per_light: vec![count as u64],
    }
}

/// A uniform density over the unit square, `N` impacts of power `E / N`, so the irradiance is `E` everywhere on it. With `U` the square's fraction covered by the part of the `k`-th neighbour's disc on the square, `U ~ Beta(k, N − k + 1)` wherever the disc stays inside the square's corner, edge or interior, so `E[k φ / U] = E k/(k−1)` and its relative variance is `(k−1)(N−1) / (N(k−2)) − 1`. The corrected estimate divides by the probed area, ¼ or ½ of `π r_k²` at the corner and on the edge up to rounding (the pattern's symmetry), so its mean over independent trials must be `E k/(k−1)` at all three; García et al.'s plain `π r_k²` gives ¼ and ½ of that.
#[test]
fn corrected_estimate_is_unbiased_at_a_corner_and_on_an_edge() {
    let (count, k, trials, e) = (4000usize, 50usize, 300usize, 2.0f64);
    let bvh = Bvh::from_triangles(fan(&polygons()[0], 0.0));
    let points = [
        ("corner", Vec3::new(0.0, 0.0, 0.0), 0.25),
        ("edge", Vec3::new(0.5, 0.0, 0.0), 0.5),
        ("inside", Vec3::new(0.5, 0.0, 0.5), 1.0),
    ];
    let (n, kf) = (count as f64, k as f64);
    let mean = e * kf / (kf - 1.0);
    let rel_var = (kf - 1.0) * (n - 1.0) / (n * (kf - 2.0)) - 1.0;
    let sigma_of_mean = mean * (rel_var / trials as f64).sqrt();
    let mut rng = Lcg(3);
    let mut sums = [(0.0f64, 0.0f64); 3];
    for _ in 0..trials {
        let rays = uniform_impacts(&mut rng, count, (e / n) as f32);
        let map = ImpactMap::build(&rays);
        for (i, &(_, x, _)) in points.iter().enumerate() {
            sums[i].0 += map.irradiance(Some(&bvh), x, Vec3::Y, k).x;
            sums[i].1 += map.irradiance(None, x, Vec3::Y, k).x;
        }
    }
    for (i, &(name, _, fraction)) in points.iter().enumerate() {
        let corrected = sums[i].0 / trials as f64;
        let plain = sums[i].1 / trials as f64;
        // The area's part of the bias, separately: the plain estimate is the corrected one times the fraction, trial by trial, so their means are too.
        assert!(
            (plain / corrected - fraction).abs() <= 1e-6,
            "{name}: plain {plain} over corrected {corrected} is not {fraction}"
        );
        // The rest is the noise around the known mean E k/(k−1).
        let z = (corrected - mean) / sigma_of_mean;
        eprintln!(
            "{name}: corrected mean {:.4} E (expected {:.4} ± {:.4}, z {z:.2}), plain {:.4} E",
            corrected / e,
            mean / e,
            sigma_of_mean / e,
            plain / e
        );
        assert!(
            z.abs() <= 5.0,
            "{name}: mean {corrected} against {mean} ± {sigma_of_mean}"
        );
    }
}
