//! Specular and shadow beams against analytic expectations (Duvenhage et al. 2010, section 3.1, equation 1).
//!
//! For a flat mirror lit by a point light L, the reflected rays all come from
//! the mirror image V of L, so the exact irradiance at a fragment F in the
//! beam is `R I cos θ_t / |F - V|²`. Equation 1 takes the flux density as
//! constant over the flux triangle (section 4.5, second approximation), so
//! it differs from the exact value by a factor that only depends on how wide
//! the beam is. With α the angle of a ray from the mean direction n̄ and h
//! the distance from V to the flux plane, the flux triangle's solid angle is
//! `Ω = ∫ cos³α / h² dA`, so the model gives `R I ⟨cos³α⟩ cos θ_m / h²` and
//! the exact value is `R I cos²α_F cos θ_t / h²`: the ratio lies in
//! `[cos³α_max, 1/cos²α_max]` times `cos θ_m / cos θ_t`. The model's
//! incoming direction (the vertex directions interpolated at F's
//! barycentrics b) differs from the true one `∝ Σ b_i (1 + ε_i) d_i`,
//! `0 ≤ ε_i ≤ sec α_max - 1 =: ε`, by an angle δ ≤ asin(ε / cos α_max), and
//! `|cos θ_m - cos θ_t| ≤ δ`.

mod support;

use glam::{DVec3, Vec3};
use lustre_beams::{BeamKind, BeamSet, BuildOptions, PointSource, solid_angle};
use support::{
    INTENSITY, LIGHT, REFLECTANCE, Rng, bounds, lerp3, mirror_triangle, mirror_triangle_scaled,
};

/// Relative rounding allowance of the f32 evaluation (a few hundred ulps over the dozens of operations of one beam).
const F32_ROUNDING: f64 = 1e-5;

fn mirror_set(shadow_beams: bool) -> BeamSet {
    mirror_set_scaled(shadow_beams, 1.0)
}

fn mirror_set_scaled(shadow_beams: bool, scale: f32) -> BeamSet {
    let options = BuildOptions {
        shadow_beams,
        ..BuildOptions::default()
    };
    BeamSet::build(
        &[PointSource::isotropic(LIGHT, INTENSITY)],
        &[mirror_triangle_scaled(0.0, scale)],
        bounds(),
        &options,
    )
    .unwrap()
}

/// The largest angle between a ray from `apex` through a corner and the mean of those directions.
fn half_angle(apex: Vec3, corners: [Vec3; 3]) -> f64 {
    let d = corners.map(|c| (c - apex).as_dvec3().normalize());
    let mean = (d[0] + d[1] + d[2]).normalize();
    d.iter()
        .map(|x| x.dot(mean).clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max)
}

/// The interval `[lo, hi]` of model / exact of the module documentation, for a receiver at exact `cos θ_t`.
fn ratio_bounds(alpha: f64, cos_t: f64) -> (f64, f64) {
    let eps = 1.0 / alpha.cos() - 1.0;
    let delta = (eps / alpha.cos()).asin();
    (
        alpha.cos().powi(3) * (1.0 - delta / cos_t) * (1.0 - F32_ROUNDING),
        (1.0 + delta / cos_t) / alpha.cos().powi(2) * (1.0 + F32_ROUNDING),
    )
}

#[test]
fn mirror_triangle_irradiance_is_that_of_the_mirrored_point_light() {
    // A wide beam (α_max ≈ 0.17 rad) and a narrow one (≈ 0.017 rad).
    for scale in [1.0, 0.1] {
        mirror_case(scale);
    }
}

fn mirror_case(scale: f32) {
    let set = mirror_set_scaled(true, scale);
    let mirror = mirror_triangle_scaled(0.0, scale);
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let alpha = half_angle(image, mirror.vertices);
    let mut rng = Rng::new(1);
    let (mut worst, mut checked) = (0.0f64, 0);
    for _ in 0..4000 {
        // A point on a ray from the image through the mirror, beyond it.
        let x = lerp3(mirror.vertices, rng.barycentrics(0.01));
        let f = image + (x - image) * rng.range(1.05, 2.9);
        assert!(set.beams()[0].contains(f), "{f} is in the reflected cone");
        let to_image = (image - f).as_dvec3();
        let n = loop {
            let n = rng.unit_vector();
            if n.as_dvec3().dot(to_image.normalize()) > 0.3 {
                break n;
            }
        };
        let cos_t = n.as_dvec3().dot(to_image.normalize());
        let r2 = to_image.length_squared();
        let got = set.irradiance_at(f, n).as_dvec3();
        let (lo, hi) = ratio_bounds(alpha, cos_t);
        for c in 0..3 {
            let want = f64::from(REFLECTANCE[c] * INTENSITY[c]) * cos_t / r2;
            let ratio = got[c] / want;
            assert!(
                (lo..=hi).contains(&ratio),
                "{f}: channel {c}: {} vs {want}, ratio {ratio} outside [{lo}, {hi}]",
                got[c]
            );
            worst = worst.max((ratio - 1.0).abs());
        }
        checked += 1;
    }
    assert!(checked > 3000);
    let (lo, hi) = ratio_bounds(alpha, 0.3);
    println!(
        "mirror ×{scale}: α_max = {alpha:.4} rad, worst |ratio - 1| = {worst:.2e}, bound at cos θ = 0.3: [{:.2e}, {:.2e}]",
        1.0 - lo,
        hi - 1.0
    );
}

#[test]
fn the_beam_volume_is_the_reflected_cone() {
    let set = mirror_set(false);
    let mirror = mirror_triangle(0.0);
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let mut rng = Rng::new(2);
    for _ in 0..2000 {
        // Just outside one edge of the mirror, seen from the image.
        let mut b = rng.barycentrics(0.0);
        let k = (rng.f32() * 3.0) as usize % 3;
        b[k] = -0.02;
        let s = b.iter().sum::<f32>();
        let b = b.map(|x| x / s);
        let x = lerp3(mirror.vertices, b);
        let t = rng.range(1.05, 4.0);
        let outside = image + (x - image) * t;
        assert!(!set.beams()[0].contains(outside), "{outside}");
        assert_eq!(set.irradiance_at(outside, -Vec3::Y).max_element(), 0.0);
        // Below the mirror (behind the generator plane) nothing is reflected.
        let inside = lerp3(mirror.vertices, rng.barycentrics(0.05));
        let below = inside - Vec3::Y * rng.range(0.01, 2.0);
        assert!(!set.beams()[0].contains(below));
    }
}

/// `∫ (L - x)·n / |L - x|³ dA` over the triangle by the midpoint rule on `k²` congruent sub-triangles (4^levels), in f64.
fn solid_angle_quadrature(l: Vec3, tri: [Vec3; 3], levels: u32) -> f64 {
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let l = l.as_dvec3();
    let n = (b - a).cross(c - a);
    let area2 = n.length();
    let n = n / area2;
    let k = 1usize << levels;
    let (u, v) = ((b - a) / k as f64, (c - a) / k as f64);
    let mut sum = 0.0;
    let f = |x: DVec3| {
        let d = l - x;
        d.dot(n).abs() / d.length().powi(3)
    };
    for i in 0..k {
        for j in 0..k - i {
            let p = a + u * i as f64 + v * j as f64;
            sum += f(p + (u + v) / 3.0);
            if i + j + 1 < k {
                sum += f(p + (u + v) * (2.0 / 3.0));
            }
        }
    }
    sum * 0.5 * area2 / (k * k) as f64
}

#[test]
fn solid_angle_matches_quadrature() {
    let mirror = mirror_triangle(0.0);
    let exact = f64::from(solid_angle(LIGHT, mirror.vertices));
    let q6 = solid_angle_quadrature(LIGHT, mirror.vertices, 6);
    let q7 = solid_angle_quadrature(LIGHT, mirror.vertices, 7);
    // The midpoint rule's error falls 4× per level; |q7 - q6| bounds it.
    let err = (q7 - q6).abs();
    assert!(
        (exact - q7).abs() <= err + 1e-6 * exact,
        "{exact} vs {q7} ± {err}"
    );
}

#[test]
fn flux_through_a_receiver_that_catches_the_whole_beam_is_the_beam_flux() {
    let set = mirror_set(false);
    let beam = set.beams()[0];
    assert_eq!(beam.kind, BeamKind::Reflected);
    let mirror = mirror_triangle(0.0);
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    // Receiver: the plane y = 2, facing the mirror; the beam's footprint is
    // the mirror projected from the image.
    let y = 2.0f32;
    let foot = mirror
        .vertices
        .map(|v| image + (v - image) * ((y - image.y) / (v.y - image.y)));
    let (mut lo, mut hi) = (foot[0], foot[0]);
    for p in foot {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let pad = 0.05 * (hi - lo).length();
    let (x0, x1, z0, z1) = (lo.x - pad, hi.x + pad, lo.z - pad, hi.z + pad);
    let n = 400usize;
    let sub = 16usize;
    let (dx, dz) = ((x1 - x0) / n as f32, (z1 - z0) / n as f32);
    let cell = f64::from(dx) * f64::from(dz);
    let at = |i: usize, j: usize, a: f32, b: f32| {
        Vec3::new(x0 + (i as f32 + a) * dx, y, z0 + (j as f32 + b) * dz)
    };
    let (mut total, mut e_max, mut boundary) = (0.0f64, 0.0f64, 0usize);
    for i in 0..n {
        for j in 0..n {
            // Cells the beam's edge crosses (corners disagree on
            // containment) are split into sub × sub midpoint cells.
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(a, b)| beam.contains(at(i, j, a, b)));
            let k = if corners.iter().any(|&c| c != corners[0]) {
                boundary += 1;
                sub
            } else {
                1
            };
            for a in 0..k {
                for b in 0..k {
                    let p = at(
                        i,
                        j,
                        (a as f32 + 0.5) / k as f32,
                        (b as f32 + 0.5) / k as f32,
                    );
                    let e = f64::from(set.irradiance_at(p, -Vec3::Y).y);
                    total += e * cell / (k * k) as f64;
                    e_max = e_max.max(e);
                }
            }
        }
    }
    let omega = solid_angle_quadrature(LIGHT, mirror.vertices, 7);
    let phi = f64::from(INTENSITY.y * REFLECTANCE.y) * omega;
    // Bounds: the ratio of the module documentation (cos θ_t ≥ cos α_max
    // on this receiver, which faces the mean direction within a degree), the
    // midpoint rule's error on sub-cells the edge crosses (at most E_max
    // each, and at most 2 sub + 1 of them per crossed cell),
    // and the solid angle's quadrature error.
    let alpha = half_angle(image, mirror.vertices);
    let tilt = {
        let d = mirror.vertices.map(|c| (c - image).as_dvec3().normalize());
        (d[0] + d[1] + d[2]).normalize().y.acos()
    };
    let (rlo, rhi) = ratio_bounds(alpha, (alpha + tilt).cos());
    let quad = boundary as f64 * (2 * sub + 1) as f64 * cell / (sub * sub) as f64 * e_max
        + (solid_angle_quadrature(LIGHT, mirror.vertices, 6) - omega).abs() * phi / omega;
    let (want_lo, want_hi) = (phi * rlo - quad, phi * rhi + quad);
    println!(
        "flux: ∫E dA = {total:.6}, Φ_s = {phi:.6}, relative error {:.2e}, allowed [{:.2e}, {:.2e}]",
        total / phi - 1.0,
        want_lo / phi - 1.0,
        want_hi / phi - 1.0
    );
    assert!(
        (want_lo..=want_hi).contains(&total),
        "{total} not in [{want_lo}, {want_hi}]"
    );
}

#[test]
fn shadow_beam_cancels_the_direct_light_behind_the_scatterer() {
    let set = mirror_set(true);
    let mirror = mirror_triangle(0.0);
    let shadow = set
        .beams()
        .iter()
        .find(|b| b.kind == BeamKind::Shadow)
        .unwrap();
    assert!(shadow.flux.max_element() < 0.0);
    let alpha = half_angle(LIGHT, mirror.vertices);
    let mut rng = Rng::new(3);
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let x = lerp3(mirror.vertices, rng.barycentrics(0.01));
        let f = LIGHT + (x - LIGHT) * rng.range(1.05, 2.5);
        let to_light = (LIGHT - f).as_dvec3().normalize();
        let n = loop {
            let n = rng.unit_vector();
            if n.as_dvec3().dot(to_light) > 0.3 {
                break n;
            }
        };
        let direct = set.direct_irradiance(f, n).as_dvec3();
        let total = direct + set.irradiance_at(f, n).as_dvec3();
        let (lo, hi) = ratio_bounds(alpha, n.as_dvec3().dot(to_light));
        for c in 0..3 {
            // shadow / direct must lie in [lo, hi]: what remains is within
            // (1 - lo, hi - 1) of the direct light.
            let ratio = 1.0 - total[c] / direct[c];
            assert!((lo..=hi).contains(&ratio), "{f}: {ratio} ∉ [{lo}, {hi}]");
            worst = worst.max((ratio - 1.0).abs());
        }
        // Beside the shadow the direct light stays whole.
        let beside = f + Vec3::new(3.0, 0.0, 0.0);
        assert_eq!(set.irradiance_at(beside, Vec3::Y), Vec3::ZERO, "{beside}");
    }
    println!("shadow: worst |shadow/direct - 1| = {worst:.2e}");
}

#[test]
fn flux_through_a_flux_plane_is_the_beam_flux_for_every_kind() {
    // On a receiver that is itself a flux plane (normal -n̄, a fixed
    // distance along n̄) A_⊥ is the same at every point, so ∫ E dA over
    // the flux triangle is Φ_s ⟨cos θ_m⟩ exactly, θ_m the angle of the
    // interpolated direction from n̄: within [Φ_s cos α_max, Φ_s]. Checks
    // containment and A_⊥ of reflected, refracted, transmitted and shadow
    // beams alike (equation 1 conserves the beam flux).
    use lustre_beams::{ScatterMaterial, Scatterer};
    use lustre_geometry::Rgb;
    let materials = [
        mirror_triangle(0.0).material,
        ScatterMaterial::Interface {
            ior: 1.33,
            transmittance: Rgb::ONE,
            roughness: 0.0,
        },
        ScatterMaterial::ThinSlab {
            ior: 1.5,
            transmittance: Rgb::splat(0.8),
            roughness: 0.0,
        },
    ];
    for material in materials {
        let tri = Scatterer {
            material,
            ..mirror_triangle(0.0)
        };
        let set = BeamSet::build(
            &[PointSource::isotropic(LIGHT, INTENSITY)],
            &[tri],
            bounds(),
            &BuildOptions::default(),
        )
        .unwrap();
        for beam in set.beams() {
            let n = beam.wavefront_normal;
            let centroid = (beam.vertices[0] + beam.vertices[1] + beam.vertices[2]) / 3.0;
            let plane_point = centroid + n * 1.5;
            let ft = beam.flux_triangle(plane_point).unwrap();
            let (u, v) = n.any_orthonormal_pair();
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for x in ft.vertices {
                let q = Vec3::new((x - plane_point).dot(u), (x - plane_point).dot(v), 0.0);
                lo = lo.min(q);
                hi = hi.max(q);
            }
            let m = 500usize;
            let (du, dv) = ((hi.x - lo.x) / m as f32, (hi.y - lo.y) / m as f32);
            let cell = f64::from(du) * f64::from(dv);
            let (mut total, mut e_max, mut boundary) = (0.0f64, 0.0f64, 0usize);
            for i in 0..m {
                for j in 0..m {
                    let at = |a: f32, b: f32| {
                        plane_point
                            + u * (lo.x + (i as f32 + a) * du)
                            + v * (lo.y + (j as f32 + b) * dv)
                    };
                    let e = f64::from(beam.irradiance(at(0.5, 0.5), -n).y);
                    total += e * cell;
                    e_max = e_max.max(e.abs());
                    let c = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                        .map(|(a, b)| beam.contains(at(a, b)));
                    if c.iter().any(|&x| x != c[0]) {
                        boundary += 1;
                    }
                }
            }
            let phi = f64::from(beam.flux.y);
            let cos_min = beam
                .directions
                .iter()
                .map(|d| f64::from(d.dot(n)))
                .fold(1.0, f64::min);
            let quad = boundary as f64 * cell * e_max;
            let (a, b) = (phi * cos_min, phi);
            let (want_lo, want_hi) = (a.min(b) - quad, a.max(b) + quad);
            println!(
                "flux plane {:?}: ∫E dA / Φ_s = {:.5}, allowed [{:.5}, {:.5}]",
                beam.kind,
                total / phi,
                want_lo / phi,
                want_hi / phi
            );
            assert!(
                (want_lo..=want_hi).contains(&total),
                "{:?}: {total} ∉ [{want_lo}, {want_hi}]",
                beam.kind
            );
        }
    }
}

#[test]
fn beams_with_one_apex_tile_the_space_behind_a_quad() {
    // A planar mirror quad of two triangles: the shadow beams (apex: the
    // light) and the reflected beams (apex: the light's image) share the
    // plane through the apex and the diagonal, whatever the flux plane, so
    // every point of the cone through the quad lies in exactly one of them.
    use lustre_beams::Scatterer;
    let m = mirror_triangle(0.0).material;
    let (a, b, c, d) = (
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(0.5, 0.0, -0.5),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(-0.5, 0.0, 0.5),
    );
    let quad = [Scatterer::flat([a, c, b], m), Scatterer::flat([a, d, c], m)];
    let set = BeamSet::build(
        &[PointSource::isotropic(LIGHT, INTENSITY)],
        &quad,
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let mut rng = Rng::new(5);
    for (kind, apex, sign) in [
        (BeamKind::Reflected, image, 1.0f32),
        (BeamKind::Shadow, LIGHT, -1.0),
    ] {
        for _ in 0..5000 {
            // A point of the quad, seen from the apex, beyond it.
            let x = Vec3::new(rng.range(-0.499, 0.499), 0.0, rng.range(-0.499, 0.499));
            let f = apex + (x - apex) * rng.range(1.05, 2.5);
            assert!(sign * f.y > 0.0);
            let holding = set
                .beams()
                .iter()
                .filter(|b| b.kind == kind && b.contains(f))
                .count();
            // On the diagonal (x = z) both hold it.
            let on_diagonal = (x.x - x.z).abs() < 1e-5;
            assert!(
                holding == 1 || (on_diagonal && holding == 2),
                "{kind:?} {f}: {holding}"
            );
        }
    }
}
