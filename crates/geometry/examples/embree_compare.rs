//! Our half of the Embree comparison that `cargo xtask bench embree` runs.
//!
//! `embree_compare <dir> [runs]` builds the benches' sphere grid (516,096
//! triangles, `benches/common/sphere_grid.rs`), makes one million coherent
//! rays (one primary ray per pixel of a 1000×1000 image) and one million
//! incoherent rays (random origins inside the grid's bounds, uniformly random
//! directions), and writes into `<dir>`:
//!
//! - `triangles.f32`: the triangles, 9 little-endian `f32` each (three corners);
//! - `<set>.rays.f32`: the rays of `<set>` (`coherent`, `incoherent`), 6 `f32`
//!   each (origin, direction), `t` in `[0, ∞)`;
//! - `<set>.ours.t.f32` and `<set>.ours.id.i32`: our closest hit of every ray
//!   (distance, scene-wide triangle id; `inf` and `-1` for a miss);
//! - `ours.json`: the settings and the wall time of every run of every query,
//!   in nanoseconds, each run tracing all rays of a set on this one thread.
//!
//! The queries timed are [`Bvh::closest_hit`] (the full hit record),
//! [`Bvh::closest_hit_lean`] (distance, id and barycentrics only), and the
//! full record as `closest_hit` made it before the eight-wide BVH: obvhs'
//! CWBVH (`build_cwbvh_from_tris`, medium settings) traversed with our
//! Möller-Trumbore test, then [`Bvh::hit_record`] (the [`Before`] below).

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use lustre_geometry::{Bvh, Camera, Hit, LeanHit, Ray, WorldTriangle, intersect_triangle};
use obvhs::cwbvh::CwBvh;

#[path = "../benches/common/cwbvh.rs"]
mod cwbvh;
#[path = "../benches/common/rays.rs"]
mod rays;
#[path = "../benches/common/sphere_grid.rs"]
mod sphere_grid;

/// Image side of the coherent rays (one ray per pixel).
const SIDE: u32 = 1000;

/// The closest-hit query before the eight-wide BVH, rebuilt from public parts.
struct Before {
    cwbvh: CwBvh,
    /// Corners in CWBVH leaf order.
    ordered: Vec<[Vec3; 3]>,
}

impl Before {
    /// obvhs' CWBVH over the triangles with the medium settings, as `Bvh::from_triangles` built it before.
    fn new(triangles: &[WorldTriangle]) -> Self {
        let (cwbvh, ordered) = cwbvh::cwbvh(triangles);
        let ordered = ordered
            .iter()
            .map(|t| [t.v0, t.v1, t.v2].map(Vec3::from))
            .collect();
        Self { cwbvh, ordered }
    }

    /// The full closest-hit record by the CWBVH traversal (the old `Bvh::closest_hit`).
    fn closest_hit(&self, bvh: &Bvh, ray: &Ray) -> Option<Hit> {
        let mut hit = obvhs::ray::RayHit::none();
        let mut best = None;
        let direction = ray.direction + Vec3::ZERO;
        let r = obvhs::ray::Ray::new(ray.origin.into(), direction.into(), ray.t_min, ray.t_max);
        self.cwbvh.ray_traverse(r, &mut hit, |r, slot| {
            let segment = Ray::segment(ray.origin, direction, r.tmin, r.tmax);
            match intersect_triangle(&segment, self.ordered[slot]) {
                Some(h) => {
                    best = Some((slot, h));
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        let (slot, h) = best?;
        let lean = LeanHit {
            triangle: self.cwbvh.primitive_indices[slot],
            t: h.t,
            u: h.u,
            v: h.v,
        };
        Some(bvh.hit_record(ray, lean))
    }
}

/// Writes `values` as little-endian 32-bit words to `path`.
fn write_words(path: &Path, values: impl Iterator<Item = [u8; 4]>) -> std::io::Result<()> {
    let bytes: Vec<u8> = values.flatten().collect();
    std::fs::write(path, bytes)
}

/// The median of `values` (the mean of the middle two for an even count).
fn median(values: &[u128]) -> u128 {
    let mut v = values.to_vec();
    v.sort_unstable();
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2
    }
}

/// Wall time in nanoseconds of `runs` passes of `trace` over `rays`, one thread.
fn time_runs<T>(rays: &[Ray], runs: usize, mut trace: impl FnMut(&Ray) -> T) -> Vec<u128> {
    let mut out = Vec::with_capacity(rays.len());
    (0..runs)
        .map(|_| {
            out.clear();
            let start = Instant::now();
            for ray in rays {
                out.push(trace(black_box(ray)));
            }
            let ns = start.elapsed().as_nanos();
            black_box(&out);
            ns
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1);
    let dir = PathBuf::from(args.next().ok_or("usage: embree_compare <dir> [runs]")?);
    let runs: usize = match args.next() {
        Some(r) => r.to_str().ok_or("runs: not UTF-8")?.parse()?,
        None => 5,
    };
    if runs == 0 {
        return Err("runs must be at least 1".into());
    }
    std::fs::create_dir_all(&dir)?;
    let triangles = sphere_grid::sphere_grid();
    write_words(
        &dir.join("triangles.f32"),
        triangles
            .iter()
            .flat_map(|t| t.positions)
            .flat_map(|p| p.to_array())
            .map(f32::to_le_bytes),
    )?;
    let before_bvh = Before::new(&triangles);
    let build = Instant::now();
    let bvh = Bvh::from_triangles(triangles);
    let build_ms = build.elapsed().as_secs_f64() * 1e3;
    let camera = Camera::look_at(
        Vec3::new(3.75, 3.75, 16.0),
        Vec3::splat(3.75),
        Vec3::Y,
        45.0,
    );
    let sets = [
        ("coherent", rays::primary_rays(&camera, SIDE)),
        (
            "incoherent",
            rays::random_rays(Vec3::splat(-1.0), Vec3::splat(8.5), SIDE * SIDE, 2),
        ),
    ];
    let mut json = String::new();
    let _ = write!(
        json,
        "{{\"triangles\": {}, \"runs\": {runs}, \"build_ms\": {build_ms:.1}, \"sets\": {{",
        bvh.len()
    );
    for (k, (name, rays)) in sets.iter().enumerate() {
        write_words(
            &dir.join(format!("{name}.rays.f32")),
            rays.iter()
                .flat_map(|r| [r.origin, r.direction])
                .flat_map(|p| p.to_array())
                .map(f32::to_le_bytes),
        )?;
        let hits: Vec<_> = rays.iter().map(|r| bvh.closest_hit_lean(r)).collect();
        write_words(
            &dir.join(format!("{name}.ours.t.f32")),
            hits.iter()
                .map(|h| h.map_or(f32::INFINITY, |h| h.t).to_le_bytes()),
        )?;
        write_words(
            &dir.join(format!("{name}.ours.id.i32")),
            hits.iter()
                .map(|h| h.map_or(-1, |h| h.triangle as i32).to_le_bytes()),
        )?;
        // Each query's runs interleave with the other's, so that a burst of
        // load on the machine touches both alike.
        let (mut full, mut lean, mut before) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..runs {
            full.extend(time_runs(rays, 1, |r| bvh.closest_hit(r)));
            lean.extend(time_runs(rays, 1, |r| bvh.closest_hit_lean(r)));
            before.extend(time_runs(rays, 1, |r| before_bvh.closest_hit(&bvh, r)));
        }
        let list = |v: &[u128]| v.iter().map(u128::to_string).collect::<Vec<_>>().join(", ");
        let _ = write!(
            json,
            "{}\"{name}\": {{\"rays\": {}, \"hits\": {}, \"full_ns\": [{}], \"lean_ns\": [{}], \"cwbvh_full_ns\": [{}]}}",
            if k > 0 { ", " } else { "" },
            rays.len(),
            hits.iter().filter(|h| h.is_some()).count(),
            list(&full),
            list(&lean),
            list(&before)
        );
        println!(
            "{name}: {} rays, full record {:.2} M rays/s, lean {:.2} M rays/s, CWBVH full record {:.2} M rays/s (medians of {runs})",
            rays.len(),
            rays.len() as f64 / median(&full) as f64 * 1e3,
            rays.len() as f64 / median(&lean) as f64 * 1e3,
            rays.len() as f64 / median(&before) as f64 * 1e3,
        );
    }
    json.push_str("}}\n");
    std::fs::write(dir.join("ours.json"), json)?;
    Ok(())
}
