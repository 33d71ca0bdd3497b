//! The `pool` caustic from beams against a photon density estimate of the same light paths (light → water surface → floor) traced by `lustre-photon`.
//!
//! Every path from the light to the pool floor crosses the water once: the
//! light is above the pool, the water covers the whole floor and the walls
//! rise above it, and a refracted ray going down inside the box meets
//! nothing before the floor. So the photons that reach the floor after one
//! refraction are exactly the floor records with `bounce == 2`, and the beams
//! that carry that light are the refracted ones (the shadow beams take out
//! the direct light the water intercepts, the reflected beams go up). Both
//! refract with the water's shading normal interpolated over each flat
//! triangle: the photon tracer's frame on a curved surface, the beams' vertex
//! rays (section 3.1's warped volumes).
//!
//! The bound per floor cell, derived:
//!
//! - The beam model's own approximation (equation 1's constant density over
//!   the flux triangle, section 4.5). A water triangle's refracted rays have
//!   no common apex, so the cardioid's closed form does not apply; the error
//!   is measured instead. The same water triangles cut into m × m
//!   sub-triangles (corners and normals interpolated as the shading normal
//!   is) give beams B_m whose density varies less across each, a field that
//!   converges to the exact refracted irradiance as m grows. A cell's flux
//!   errs only through the beams that straddle its edges (a beam inside a
//!   cell brings all its flux `Φ_s = I Ω (1 - F)`, with F at the triangle's
//!   centroid: across a water triangle F moves by below 1e-3 of 1 - F, and
//!   the sub-triangles take their own), each by its density's variation
//!   times its area: second order in the beam size overall, so
//!   `|B_1 - B_m|` is `(1 - 1/m²)` of the scene's error. The bound takes
//!   `m/(m - 1) |B_1 - B_m|`, which would hold even for first order
//!   convergence.
//! - The quadrature of each field over the cell (midpoint rule on `k × k`
//!   points): its error is estimated by the difference between `k` and `2k`
//!   points (the `2k` values are used), for B_1 and B_m.
//! - The photon estimate `Σ φ_i / A`: the photons landing in the cell are a
//!   Poisson-like count, so its standard error is `√(Σ φ_i²) / A` (if
//!   anything an overestimate for the default Sobol emission, whose strata
//!   spread the photons more evenly; the mean z² comes out at 0.98); a cell
//!   passes within 4.5 standard errors (deterministic seed; over the 256
//!   cells a false alarm has probability about 2e-3, 256 · 6.8e-6).
//!   `PHOTONS` = 128 million give about 0.6 % per cell, so the bound is
//!   about ±3 % of a cell's irradiance, while the waves move a cell's
//!   irradiance by 4.7 % (median) and up to 18 % from that of flat water:
//!   the beams of flat water fall outside the bound in 161 of the 256 cells
//!   (the test asserts a quarter). About 7 s in release and in the dev
//!   profile on two idle cores, most of it tracing.

use std::time::Instant;

use glam::Vec3;
use lustre_beams::{BeamInput, BeamKind, BeamSet, BuildOptions, Scatterer};
use lustre_geometry::Bvh;
use lustre_geometry::builtin::pool::{WATER_LEVEL, pool};
use lustre_photon::{NoProgress, PhotonTracer, SurfaceParams, TraceOptions};
use rayon::prelude::*;

/// Side of the floor cells, m.
const CELL: f32 = 0.125;
/// Photons emitted (one run, streamed in blocks).
const PHOTONS: u64 = 128_000_000;
/// Sub-triangles per water triangle edge of the refined beams.
const REFINE: usize = 4;

/// `s` cut into `m × m` sub-triangles of the same winding, corners and
/// normals interpolated barycentrically (the normals renormalised, as a hit's
/// shading normal is).
fn subdivided(s: &Scatterer, m: usize) -> Vec<Scatterer> {
    let at = |i: usize, j: usize| {
        let (b1, b2) = (i as f32 / m as f32, j as f32 / m as f32);
        let b0 = 1.0 - b1 - b2;
        let p = s.vertices[0] * b0 + s.vertices[1] * b1 + s.vertices[2] * b2;
        let n = (s.normals[0] * b0 + s.normals[1] * b1 + s.normals[2] * b2).normalize();
        (p, n)
    };
    let triangle = |corners: [(usize, usize); 3]| {
        let c = corners.map(|(i, j)| at(i, j));
        Scatterer {
            vertices: c.map(|(p, _)| p),
            normals: c.map(|(_, n)| n),
            material: s.material,
            slab_face: s.slab_face,
        }
    };
    let mut out = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m - i {
            out.push(triangle([(i, j), (i + 1, j), (i, j + 1)]));
            if i + j + 1 < m {
                out.push(triangle([(i + 1, j), (i + 1, j + 1), (i, j + 1)]));
            }
        }
    }
    out
}

/// The refracted beams' irradiance at a floor point (normal +y), green channel.
fn refracted(set: &BeamSet, p: Vec3) -> f64 {
    set.candidates(p)
        .into_iter()
        .map(|i| &set.beams()[i as usize])
        .filter(|b| b.kind == BeamKind::Refracted)
        .map(|b| f64::from(b.irradiance(p, Vec3::Y).y))
        .sum()
}

#[test]
fn pool_caustic_matches_a_photon_density_estimate() {
    let scene = pool();
    let set = BeamSet::from_scene(&scene, &BuildOptions::default()).unwrap();
    let input = BeamInput::from_scene(&scene).unwrap();
    let pieces: Vec<Scatterer> = input
        .scatterers
        .iter()
        .flat_map(|s| subdivided(s, REFINE))
        .collect();
    assert_eq!(pieces.len(), input.scatterers.len() * REFINE * REFINE);
    let options = BuildOptions {
        shadow_beams: false,
        ..BuildOptions::default()
    };
    let refined = BeamSet::build(&input.lights, &pieces, scene.bounds(), &options).unwrap();
    assert_eq!(set.stats().total_internal_reflection, 0);
    assert_eq!(refined.stats().total_internal_reflection, 0);

    // The photons, streamed in blocks (one run of PHOTONS photons, bounded memory).
    let started = Instant::now();
    let bvh = Bvh::build(&scene);
    let trace = TraceOptions {
        photons: PHOTONS,
        seed: 11,
        max_bounces: 2,
        ..TraceOptions::default()
    };
    let params = SurfaceParams::new(&scene);
    let floor = scene
        .surfaces()
        .iter()
        .position(|s| scene.meshes()[s.mesh as usize].name == "floor")
        .unwrap() as u32;
    assert_eq!(scene.lights().len(), 1);
    let photon_power = f64::from(scene.lights()[0].power().y) / PHOTONS as f64;
    // Cells of the floor square [-1, 1]².
    let n = (2.0 / CELL) as usize;
    let cell_min = |i: usize| -1.0 + i as f32 * CELL;
    let (mut sum, mut sum2) = (vec![0.0f64; n * n], vec![0.0f64; n * n]);
    let (mut records, mut floor_records) = (0usize, 0usize);
    PhotonTracer::new(&scene, &bvh)
        .unwrap()
        .trace_streamed(&[0], &[PHOTONS], &trace, &NoProgress, &mut |_, block| {
            records += block.len();
            for r in block {
                if r.surface != floor || r.bounce != 2 {
                    continue;
                }
                floor_records += 1;
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
                let w = photon_power * f64::from(r.rho.y);
                sum[i as usize * n + j as usize] += w;
                sum2[i as usize * n + j as usize] += w * w;
            }
            Ok(())
        })
        .unwrap();
    let traced = started.elapsed();
    // ∫ E over a cell by the midpoint rule on k × k points, of both fields: (B_1, B_m).
    let integrate = |i: usize, j: usize, k: usize| -> (f64, f64) {
        let h = CELL / k as f32;
        let (mut e1, mut em) = (0.0, 0.0);
        for a in 0..k {
            for b in 0..k {
                let p = Vec3::new(
                    cell_min(i) + (a as f32 + 0.5) * h,
                    0.0,
                    cell_min(j) + (b as f32 + 0.5) * h,
                );
                e1 += refracted(&set, p);
                em += refracted(&refined, p);
            }
        }
        let da = f64::from(h) * f64::from(h);
        (e1 * da, em * da)
    };
    // Per cell: the photons, their variance, B_1, its quadrature error, the model error.
    let cells: Vec<[f64; 5]> = (0..n * n)
        .into_par_iter()
        .map(|c| {
            let (i, j) = (c / n, c % n);
            let (coarse1, coarse_m) = integrate(i, j, 12);
            let (model, fine_m) = integrate(i, j, 24);
            let quad = (model - coarse1).abs() + (fine_m - coarse_m).abs();
            let m = REFINE as f64;
            let approximation = m / (m - 1.0) * (model - fine_m).abs();
            [sum[c], sum2[c], model, quad, approximation]
        })
        .collect();
    let area = f64::from(CELL) * f64::from(CELL);
    let (mut worst, mut chi2) = (0.0f64, 0.0f64);
    let mut total = [0.0f64; 5];
    for (c, &[photons, var, model, quad, approximation]) in cells.iter().enumerate() {
        let se = var.sqrt();
        let slack = quad + approximation + 4.5 * se;
        assert!(
            (model - slack..=model + slack).contains(&photons),
            "cell ({}, {}): photons {:.4e} W/m², beams {:.4e} W/m², allowed ±{:.4e} (se {:.4e}, quadrature {:.4e}, model {:.4e})",
            c / n,
            c % n,
            photons / area,
            model / area,
            slack / area,
            se / area,
            quad / area,
            approximation / area
        );
        for (t, v) in total
            .iter_mut()
            .zip([photons, var, model, quad, approximation])
        {
            *t += v;
        }
        let spread = (var + quad * quad + approximation * approximation)
            .sqrt()
            .max(1e-30);
        let z = (photons - model) / spread;
        chi2 += z * z;
        worst = worst.max(z.abs());
        if std::env::var_os("BEAMS_CELLS").is_some() {
            println!(
                "({:2}, {:2}) photons {:.4e} beams {:.4e} rel {:+.4} se {:.4} quad {:.4} model {:.4} z {:+.2}",
                c / n,
                c % n,
                photons / area,
                model / area,
                photons / model - 1.0,
                se / model,
                quad / model,
                approximation / model,
                z
            );
        }
    }
    let [photons, var, model, quad, approximation] = total;
    let slack = quad + approximation + 4.5 * var.sqrt();
    println!(
        "all cells: photons / beams - 1 = {:+.4}, standard error {:.4}, allowed ±{:.4}",
        photons / model - 1.0,
        var.sqrt() / model,
        slack / model
    );
    assert!((model - slack..=model + slack).contains(&photons));
    println!(
        "{PHOTONS} photons: {records} records, {floor_records} floor records after one refraction; traced in {:.1} s, cells integrated in {:.1} s",
        traced.as_secs_f64(),
        (started.elapsed() - traced).as_secs_f64()
    );
    assert_eq!(cells.len(), 256);
    // The bound is tight enough to see the waves: the beams of flat water at
    // the mean level (the same triangles flattened, normals straight up) fall
    // outside it in most cells.
    let flat: Vec<Scatterer> = input
        .scatterers
        .iter()
        .map(|s| Scatterer {
            vertices: s.vertices.map(|v| Vec3::new(v.x, WATER_LEVEL, v.z)),
            normals: [Vec3::Y; 3],
            material: s.material,
            slab_face: s.slab_face,
        })
        .collect();
    let flat = BeamSet::build(&input.lights, &flat, scene.bounds(), &options).unwrap();
    let flat: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|c| {
            let (i, j) = (c / n, c % n);
            let h = CELL / 24.0;
            let mut e = 0.0;
            for a in 0..24 {
                for b in 0..24 {
                    let p = Vec3::new(
                        cell_min(i) + (a as f32 + 0.5) * h,
                        0.0,
                        cell_min(j) + (b as f32 + 0.5) * h,
                    );
                    e += refracted(&flat, p);
                }
            }
            e * f64::from(h) * f64::from(h)
        })
        .collect();
    let rejected = cells
        .iter()
        .zip(&flat)
        .filter(|&(&[photons, var, _, quad, approximation], &e)| {
            (photons - e).abs() > quad + approximation + 4.5 * var.sqrt()
        })
        .count();
    let mut waves: Vec<f64> = cells
        .iter()
        .zip(&flat)
        .map(|(c, &e)| (c[2] / e - 1.0).abs())
        .collect();
    waves.sort_by(f64::total_cmp);
    println!(
        "flat water: {rejected} of {} cells outside the bound; the waves change a cell's irradiance by {:.3} (median), {:.3} (largest)",
        cells.len(),
        waves[waves.len() / 2],
        waves[waves.len() - 1]
    );
    assert!(rejected > cells.len() / 4, "{rejected}");
    println!(
        "pool: {} cells of {CELL} m, photons vs beams: worst |z| = {worst:.2}, mean z² = {:.2} (z: difference over the combined spread)",
        cells.len(),
        chi2 / cells.len() as f64
    );
}
