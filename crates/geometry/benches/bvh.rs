//! BVH closest-hit throughput: coherent primary rays and incoherent random
//! rays, on `cornell` and on a generated scene of 516,096 triangles.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use lustre_geometry::sampling::sample_uniform_sphere;
use lustre_geometry::{Bvh, Camera, Ray, builtin};
use rayon::prelude::*;

#[path = "common/sphere_grid.rs"]
mod sphere_grid;
use sphere_grid::sphere_grid;

/// Rays per batch in every benchmark.
const RAYS: u32 = 256 * 256;

/// A deterministic stream of numbers in [0, 1) (SplitMix64) for ray generation.
struct Stream(u64);
impl Stream {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// One ray per pixel of a 256×256 image.
fn primary_rays(camera: &Camera) -> Vec<Ray> {
    (0..RAYS)
        .map(|i| {
            camera.primary_ray(Camera::pixel_ndc(
                i % 256,
                i / 256,
                256,
                256,
                Vec2::splat(0.5),
            ))
        })
        .collect()
}

/// Rays from random points inside `lo..hi` in uniformly random directions.
fn random_rays(lo: Vec3, hi: Vec3, seed: u64) -> Vec<Ray> {
    let mut s = Stream(seed);
    (0..RAYS)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(s.next(), s.next(), s.next());
            Ray::new(o, sample_uniform_sphere(Vec2::new(s.next(), s.next())))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let cornell = builtin("cornell").unwrap();
    let cornell_bvh = Bvh::build(&cornell);
    let spheres = sphere_grid();
    assert!(spheres.len() >= 500_000, "{} triangles", spheres.len());
    let spheres_bvh = Bvh::from_triangles(spheres);
    let spheres_camera = Camera::look_at(
        Vec3::new(3.75, 3.75, 16.0),
        Vec3::splat(3.75),
        Vec3::Y,
        45.0,
    );
    let cases = [
        (
            "cornell",
            &cornell_bvh,
            primary_rays(cornell.camera()),
            random_rays(Vec3::splat(-0.95), Vec3::splat(0.95), 1),
        ),
        (
            "spheres-516k",
            &spheres_bvh,
            primary_rays(&spheres_camera),
            random_rays(Vec3::splat(-1.0), Vec3::splat(8.5), 2),
        ),
    ];
    let mut group = c.benchmark_group("bvh-closest-hit");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.sample_size(10);
    for (name, bvh, coherent, incoherent) in &cases {
        group.bench_function(format!("{name}/coherent"), |b| {
            b.iter(|| bvh.closest_hits(coherent))
        });
        group.bench_function(format!("{name}/incoherent"), |b| {
            b.iter(|| bvh.closest_hits(incoherent))
        });
    }
    // Baseline: obvhs alone on the same triangles and coherent rays, with its
    // own Möller-Trumbore test and no hit record, to show what our wrapper costs.
    let spheres = sphere_grid();
    let tris: Vec<obvhs::triangle::Triangle> = spheres
        .iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: t.positions[0].into(),
            v1: t.positions[1].into(),
            v2: t.positions[2].into(),
        })
        .collect();
    let raw = obvhs::cwbvh::builder::build_cwbvh_from_tris(
        &tris,
        obvhs::BvhBuildParams::medium_build(),
        &mut std::time::Duration::default(),
    );
    let ordered: Vec<_> = raw
        .primitive_indices
        .iter()
        .map(|&i| tris[i as usize])
        .collect();
    let raw_rays: Vec<obvhs::ray::Ray> = primary_rays(&spheres_camera)
        .iter()
        .map(|r| obvhs::ray::Ray::new_inf(r.origin.into(), r.direction.into()))
        .collect();
    group.bench_function("spheres-516k/coherent-obvhs-baseline", |b| {
        b.iter(|| {
            raw_rays
                .par_iter()
                .map(|r| {
                    let mut hit = obvhs::ray::RayHit::none();
                    raw.ray_traverse(*r, &mut hit, |ray, id| ordered[id].intersect(ray));
                    hit.t
                })
                .collect::<Vec<f32>>()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
