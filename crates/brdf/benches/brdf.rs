//! Criterion bench: evaluations/s and samples/s per model (Throughput::Elements), small sample sizes so the whole run stays near a minute.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use lustre_brdf::table::BrdfTable;
use lustre_brdf::{BoxedBrdf, MODEL_NAMES, from_model};
use lustre_geometry::material::MaterialModel;

/// Direction pairs and random numbers per iteration.
const BATCH: usize = 1024;

/// A fixed batch of upper-hemisphere direction pairs and uniform numbers (SplitMix64, seed 1).
fn inputs() -> Vec<(Vec3, Vec3, Vec2, f32)> {
    let mut s = 1u64;
    let mut next = || {
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let upper = |a: f32, b: f32| {
        let c = 0.02 + 0.98 * a;
        let r = (1.0 - c * c).sqrt();
        let p = std::f32::consts::TAU * b;
        Vec3::new(r * p.cos(), r * p.sin(), c)
    };
    (0..BATCH)
        .map(|_| {
            let (a, b, c, d) = (next(), next(), next(), next());
            let (e, f, g) = (next(), next(), next());
            (upper(a, b), upper(c, d), Vec2::new(e, f), g)
        })
        .collect()
}

/// Every registered model with its default parameters, plus a 3D BRDF table of Oren-Nayar.
fn models() -> Vec<(String, BoxedBrdf)> {
    let mut v: Vec<(String, BoxedBrdf)> = MODEL_NAMES
        .iter()
        .filter(|&&n| n != "diffuse")
        .map(|&n| {
            let m = MaterialModel::Named {
                model: n.into(),
                params: Default::default(),
            };
            (
                n.to_owned(),
                from_model(&m).expect("default parameters build"),
            )
        })
        .collect();
    let on = from_model(&MaterialModel::Named {
        model: "oren-nayar-full".into(),
        params: Default::default(),
    })
    .expect("oren-nayar-full builds");
    let table = BrdfTable::with_error_bound(on.as_ref(), 0.05).expect("table builds");
    v.push(("brdf-table(oren-nayar-full)".into(), Box::new(table)));
    v
}

/// Evaluations and samples of every model, 1024 per iteration.
fn bench(c: &mut Criterion) {
    let inputs = inputs();
    let mut eval = c.benchmark_group("eval");
    eval.throughput(Throughput::Elements(BATCH as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_millis(300));
    let models = models();
    for (name, b) in &models {
        eval.bench_function(name.as_str(), |bench| {
            bench.iter(|| {
                let mut acc = Vec3::ZERO;
                for &(wi, wo, _, _) in &inputs {
                    acc += b.eval(black_box(wi), black_box(wo));
                }
                acc
            })
        });
    }
    eval.finish();
    let mut sample = c.benchmark_group("sample");
    sample
        .throughput(Throughput::Elements(BATCH as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_millis(300));
    for (name, b) in &models {
        sample.bench_function(name.as_str(), |bench| {
            bench.iter(|| {
                let mut acc = 0.0f32;
                for &(_, wo, u, l) in &inputs {
                    if let Some(s) = b.sample(black_box(wo), black_box(u), l) {
                        acc += s.pdf;
                    }
                }
                acc
            })
        });
    }
    sample.finish();
}

/// The criterion group (in a private module: the macro's function has no doc comment).
mod group {
    use super::{bench, criterion_group};
    criterion_group!(benches, bench);
}

criterion_main!(group::benches);
