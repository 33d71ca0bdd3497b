//! Glossy beams (Duvenhage et al. 2010, section 4.2): continuous across the flux triangle's edges, and equal to the specular beam as σ → 0.

mod support;

use glam::Vec3;
use lustre_beams::{Beam, BeamKind, BeamSet, BuildOptions, PointSource};
use support::{INTENSITY, LIGHT, Rng, bounds, lerp3, mirror_triangle};

fn reflected(roughness: f32) -> Beam {
    let set = BeamSet::build(
        &[PointSource::isotropic(LIGHT, INTENSITY)],
        &[mirror_triangle(roughness)],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    *set.beams()
        .iter()
        .find(|b| b.kind == BeamKind::Reflected)
        .unwrap()
}

/// Irradiance (green) at `p` for a receiver facing the beam.
fn e(beam: &Beam, p: Vec3) -> f64 {
    f64::from(beam.irradiance(p, -beam.wavefront_normal).y)
}

/// Points on the flux triangle's edges at several depths, with the unit direction into the triangle across that edge (in the flux plane).
fn edge_points(beam: &Beam, rng: &mut Rng, count: usize) -> Vec<(Vec3, Vec3, f32)> {
    let mirror = mirror_triangle(0.0);
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let mut out = Vec::new();
    while out.len() < count {
        let x = lerp3(mirror.vertices, rng.barycentrics(0.1));
        let f0 = image + (x - image) * rng.range(1.2, 2.8);
        let ft = beam.flux_triangle(f0).unwrap();
        let k = out.len() % 3;
        let (a, b, c) = (
            ft.vertices[k],
            ft.vertices[(k + 1) % 3],
            ft.vertices[(k + 2) % 3],
        );
        let on_edge = a + (b - a) * rng.range(0.1, 0.9);
        let mut inward = beam.wavefront_normal.cross(b - a).normalize();
        if inward.dot(c - on_edge) < 0.0 {
            inward = -inward;
        }
        out.push((on_edge, inward, (b - a).length()));
    }
    out
}

#[test]
fn glossy_beams_are_continuous_across_the_flux_triangle_edges() {
    // E is Lipschitz with slopes s_in, s_out on either side of an edge, so
    // over steps of h: |E(+h) - E(-h)| = h (s_in + s_out) + O(h²) while the
    // neighbouring differences |E(3h) - E(h)|, |E(-h) - E(-3h)| are
    // 2h s_in, 2h s_out + O(h²): the jump across is at most their mean, up
    // to the O(h²) curvature term (taken as half of it again) and f32
    // rounding of E (1e-5 relative). A step (the specular beam) breaks this.
    let mut rng = Rng::new(11);
    for roughness in [0.01f32, 0.05, 0.2] {
        let glossy = reflected(roughness);
        let specular = reflected(0.0);
        let mut worst = 0.0f64;
        for (p, inward, len) in edge_points(&glossy, &mut rng, 300) {
            let h = 2e-3 * len;
            let at = |beam: &Beam, s: f32| e(beam, p + inward * (s * h));
            let bound = |beam: &Beam| {
                let (i1, i3, o1, o3) =
                    (at(beam, 1.0), at(beam, 3.0), at(beam, -1.0), at(beam, -3.0));
                let across = (i1 - o1).abs();
                let sides = 0.5 * ((i3 - i1).abs() + (o1 - o3).abs());
                (across, 1.5 * sides + 1e-5 * i1.abs().max(o1.abs()))
            };
            let (across, allowed) = bound(&glossy);
            assert!(
                across <= allowed,
                "α = {roughness}, {p}: jump {across} > {allowed}"
            );
            worst = worst.max(across / allowed);
            let (s_across, s_allowed) = bound(&specular);
            assert!(s_across > s_allowed, "the specular beam steps at the edge");
        }
        println!("continuity α = {roughness}: worst jump / allowed = {worst:.3}");
    }
}

#[test]
fn glossy_beams_approach_the_specular_beam_as_sigma_vanishes() {
    let specular = reflected(0.0);
    let mirror = mirror_triangle(0.0);
    let image = Vec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let mut rng = Rng::new(12);
    let points: Vec<(Vec3, bool)> = (0..400)
        .map(|i| {
            let mut b = rng.barycentrics(0.1);
            let inside = i % 2 == 0;
            if !inside {
                b[i % 3] = -0.1;
                let s = b.iter().sum::<f32>();
                b = b.map(|x| x / s);
            }
            let x = lerp3(mirror.vertices, b);
            (image + (x - image) * rng.range(1.2, 2.8), inside)
        })
        .collect();
    let mut previous = f64::INFINITY;
    for roughness in [0.05f32, 0.02, 0.005, 0.001, 1e-4] {
        let glossy = reflected(roughness);
        let mut err = 0.0f64;
        for &(p, inside) in &points {
            let (g, s) = (e(&glossy, p), e(&specular, p));
            assert_eq!(s > 0.0, inside, "{p}");
            err = err.max(
                (g - s).abs()
                    / e(&specular, p)
                        .max(1e-30)
                        .max(if inside { 0.0 } else { 1.0 }),
            );
        }
        println!(
            "σ → 0: α = {roughness}: max |E_glossy - E_specular| (relative inside) = {err:.3e}"
        );
        assert!(err <= previous, "α = {roughness}: {err} > {previous}");
        previous = err;
    }
    // At α = 1e-4 (σ = 1.4e-4 rad) the domain ABC is hundreds of σ across
    // inside (P_E clamps to 1) and hundreds of σ away outside (exp
    // underflows in f32): the two beams agree exactly.
    assert_eq!(previous, 0.0);
}

#[test]
fn glossy_light_reaches_outside_the_specular_beam_and_fades() {
    // Outside the specular beam the volume P_E (clamped to one) falls with
    // the distance to it, and the beam lights where the specular one does
    // not.
    let specular = reflected(0.0);
    let glossy = reflected(0.05);
    let dist = glossy.distribution.unwrap();
    let mut rng = Rng::new(13);
    for (p, inward, len) in edge_points(&specular, &mut rng, 30) {
        let volumes: Vec<f32> = (1..12)
            .map(|k| {
                let q = p - inward * (k as f32 * 0.05 * len);
                let ft = glossy.flux_triangle(q).unwrap();
                glossy.scatter_volume(&dist, &ft, q).min(1.0)
            })
            .collect();
        for w in volumes.windows(2) {
            assert!(w[1] <= w[0], "{volumes:?}");
        }
        assert!(volumes[0] > 0.0 && volumes[10] < volumes[0], "{volumes:?}");
        let q = p - inward * (0.05 * len);
        assert!(e(&glossy, q) > 0.0);
        assert_eq!(e(&specular, q), 0.0);
    }
}
