//! The `cardioid` caustic from beams against a photon density estimate of the same light paths (light → ring → floor) traced by `lustre-photon`.
//!
//! Inside the ring both see the same paths: the ring is convex, so a ray
//! from a ring point to a floor point inside it meets nothing else, and
//! photons that reach the floor after one ring reflection are exactly the
//! records with `bounce == 2` on the floor (the floor cannot reach itself).
//!
//! The bound per floor cell, derived:
//!
//! - The beam model's own approximation (equation 1's constant density
//!   over the flux triangle, section 4.5): every ring triangle is a flat
//!   mirror, so its reflected rays come from the light's mirror image V_b,
//!   and `tests/specular.rs` shows the model's irradiance is the exact one
//!   times a factor in `[cos³α_b (1 - δ_b / cos θ), sec²α_b (1 + δ_b / cos θ)]`
//!   (α_b the beam's half-angle about its mean direction, θ the true
//!   incidence angle from V_b, `δ_b = asin((sec α_b - 1) / cos α_b)`).
//!   Integrated over a cell this gives `[L, U]` for the exact flux.
//! - The quadrature of the beam irradiance over the cell (midpoint rule on
//!   `k × k` points): its error is estimated by the difference between
//!   `k` and `2k` points (the `2k` value is used).
//! - The photon estimate `Σ φ_i / A`: the photons landing in the cell are
//!   a Poisson-like count, so its standard error is `√(Σ φ_i²) / A`; a cell
//!   passes within 4.5 standard errors (deterministic seed; over ~150
//!   cells a false alarm has probability below 1e-3).

use glam::Vec3;
use lustre_beams::{BeamKind, BeamSet, BuildOptions};
use lustre_geometry::Bvh;
use lustre_geometry::builtin::cardioid::{LIGHT_POSITION, RING_RADIUS, cardioid};
use lustre_photon::{NoProgress, SurfaceParams, TraceOptions, trace_photons};

const CELL: f32 = 0.125;
const PHOTONS: u64 = 12_000_000;

#[test]
fn cardioid_caustic_matches_a_photon_density_estimate() {
    let scene = cardioid();
    let set = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let bvh = Bvh::build(&scene);
    let options = TraceOptions {
        photons: PHOTONS,
        seed: 7,
        max_bounces: 2,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
    let params = SurfaceParams::new(&scene);
    let floor = scene
        .surfaces()
        .iter()
        .position(|s| scene.meshes()[s.mesh as usize].name == "floor")
        .unwrap() as u32;
    // Cells of the floor square [-1, 1]² whose corners lie inside the ring
    // (a margin of one cell from it).
    let n = (2.0 / CELL) as usize;
    let cell_min = |i: usize| -1.0 + i as f32 * CELL;
    let inside = |i: usize, j: usize| {
        [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(a, b)| {
            let (x, z) = (cell_min(i + a), cell_min(j + b));
            (x * x + z * z).sqrt() < RING_RADIUS - CELL
        })
    };
    let (mut sum, mut sum2) = (vec![0.0f64; n * n], vec![0.0f64; n * n]);
    for r in map.records() {
        if r.surface != floor || r.bounce != 2 {
            continue;
        }
        let p = params
            .world_position(r.surface, r.triangle, r.position)
            .unwrap();
        let (i, j) = (
            ((p.x + 1.0) / CELL).floor() as isize,
            ((p.z + 1.0) / CELL).floor() as isize,
        );
        if i < 0 || j < 0 || i >= n as isize || j >= n as isize {
            continue;
        }
        let w = f64::from(map.photon_power(r).y);
        sum[i as usize * n + j as usize] += w;
        sum2[i as usize * n + j as usize] += w * w;
    }
    // Per reflected beam: its mirror-image apex and half-angle bounds.
    let beams: Vec<(usize, Vec3, f64)> = set
        .beams()
        .iter()
        .enumerate()
        .filter(|(_, b)| b.kind == BeamKind::Reflected)
        .map(|(k, b)| {
            let [a, bb, c] = b.vertices;
            let normal = (bb - a).cross(c - a).normalize();
            let image = LIGHT_POSITION - 2.0 * (LIGHT_POSITION - a).dot(normal) * normal;
            let d = b.vertices.map(|v| (v - image).as_dvec3().normalize());
            let mean = (d[0] + d[1] + d[2]).normalize();
            let alpha = d
                .iter()
                .map(|x| x.dot(mean).clamp(-1.0, 1.0).acos())
                .fold(0.0, f64::max);
            (k, image, alpha)
        })
        .collect();
    // ∫ E over a cell by the midpoint rule on k × k points: (model, L, U).
    let integrate = |i: usize, j: usize, k: usize| -> (f64, f64, f64) {
        let (mut e, mut lo, mut hi) = (0.0, 0.0, 0.0);
        let h = CELL / k as f32;
        for a in 0..k {
            for b in 0..k {
                let p = Vec3::new(
                    cell_min(i) + (a as f32 + 0.5) * h,
                    0.0,
                    cell_min(j) + (b as f32 + 0.5) * h,
                );
                for &(index, image, alpha) in &beams {
                    let v = f64::from(set.beams()[index].irradiance(p, Vec3::Y).y);
                    if v == 0.0 {
                        continue;
                    }
                    let cos_t = (image - p).as_dvec3().normalize().y;
                    let eps = 1.0 / alpha.cos() - 1.0;
                    let delta = (eps / alpha.cos()).asin();
                    e += v;
                    // exact = model / ratio, ratio in [r_lo, r_hi].
                    let r_lo = alpha.cos().powi(3) * (1.0 - delta / cos_t);
                    let r_hi = (1.0 + delta / cos_t) / alpha.cos().powi(2);
                    lo += v / r_hi;
                    hi += v / r_lo.max(1e-6);
                }
            }
        }
        let da = f64::from(h) * f64::from(h);
        (e * da, lo * da, hi * da)
    };
    let area = f64::from(CELL) * f64::from(CELL);
    let (mut cells, mut worst, mut chi2) = (0usize, 0.0f64, 0.0f64);
    // Over all cells together: photons, their variance, model, L, U, quadrature.
    let mut total = [0.0f64; 6];
    for i in 0..n {
        for j in 0..n {
            if !inside(i, j) {
                continue;
            }
            let (coarse, _, _) = integrate(i, j, 12);
            let (model, lo, hi) = integrate(i, j, 24);
            let quad = (model - coarse).abs();
            let photons = sum[i * n + j];
            let se = sum2[i * n + j].sqrt();
            let (allowed_lo, allowed_hi) = (lo - quad - 4.5 * se, hi + quad + 4.5 * se);
            assert!(
                (allowed_lo..=allowed_hi).contains(&photons),
                "cell ({i}, {j}): photons {:.4e} W/m², beams {:.4e} W/m², allowed [{:.4e}, {:.4e}]",
                photons / area,
                model / area,
                allowed_lo / area,
                allowed_hi / area
            );
            for (t, v) in total
                .iter_mut()
                .zip([photons, se * se, model, lo, hi, quad])
            {
                *t += v;
            }
            let spread = (se * se + quad * quad + (0.5 * (hi - lo)).powi(2))
                .sqrt()
                .max(1e-30);
            let z = (photons - model) / spread;
            chi2 += z * z;
            worst = worst.max(z.abs());
            cells += 1;
            if std::env::var_os("BEAMS_CELLS").is_some() {
                println!(
                    "({i:2}, {j:2}) photons {:.4e} beams {:.4e} rel {:+.3} se {:.3} model [{:+.3}, {:+.3}] quad {:.3}",
                    photons / area,
                    model / area,
                    photons / model - 1.0,
                    se / model,
                    lo / model - 1.0,
                    hi / model - 1.0,
                    quad / model
                );
            }
        }
    }
    let [photons, var, model, lo, hi, quad] = total;
    let (allowed_lo, allowed_hi) = (lo - quad - 4.5 * var.sqrt(), hi + quad + 4.5 * var.sqrt());
    println!(
        "all cells: photons / beams - 1 = {:+.4}, standard error {:.4}, allowed [{:+.4}, {:+.4}]",
        photons / model - 1.0,
        var.sqrt() / model,
        allowed_lo / model - 1.0,
        allowed_hi / model - 1.0
    );
    assert!((allowed_lo..=allowed_hi).contains(&photons));
    let total_photons: f64 = sum.iter().sum();
    println!(
        "{} records, {} floor records after one ring reflection",
        map.records().len(),
        map.records()
            .iter()
            .filter(|r| r.surface == floor && r.bounce == 2)
            .count()
    );
    assert!(cells > 100, "{cells}");
    assert!(total_photons > 0.0);
    println!(
        "cardioid: {cells} cells of {CELL} m, photons vs beams: worst |z| = {worst:.2}, mean z² = {:.2} (z: difference over the combined spread)",
        chi2 / cells as f64
    );
}
