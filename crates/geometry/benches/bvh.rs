//! BVH closest-hit throughput: coherent primary rays and incoherent random
//! rays, on `cornell` and on a generated scene of 516,096 triangles.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use lustre_geometry::{Bvh, Camera, builtin};
use rayon::prelude::*;

#[path = "common/cwbvh.rs"]
mod cwbvh;
#[path = "common/rays.rs"]
mod rays;
#[path = "common/sphere_grid.rs"]
mod sphere_grid;
use sphere_grid::sphere_grid;

/// Side of the image whose pixels the coherent rays pass through.
const SIDE: u32 = 256;

/// Rays per batch in every benchmark.
const RAYS: u32 = SIDE * SIDE;

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
            rays::primary_rays(cornell.camera(), SIDE),
            rays::random_rays(Vec3::splat(-0.95), Vec3::splat(0.95), RAYS, 1),
        ),
        (
            "spheres-516k",
            &spheres_bvh,
            rays::primary_rays(&spheres_camera, SIDE),
            rays::random_rays(Vec3::splat(-1.0), Vec3::splat(8.5), RAYS, 2),
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
    let (raw, ordered) = cwbvh::cwbvh(&spheres);
    let raw_rays: Vec<obvhs::ray::Ray> = rays::primary_rays(&spheres_camera, SIDE)
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
