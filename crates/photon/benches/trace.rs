//! Particle tracing throughput on `glosbox` (section 2.1): photons traced per second and bounces (hit records) per second.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use lustre_geometry::{Bvh, builtin};
use lustre_photon::{NoProgress, PhotonTracer, TraceOptions};

/// Photons per iteration.
const PHOTONS: u64 = 20_000;

fn trace(c: &mut Criterion) {
    let scene = builtin("glosbox").expect("glosbox is built in");
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).expect("glosbox materials are valid");
    let options = TraceOptions {
        photons: PHOTONS,
        seed: 1,
        ..TraceOptions::default()
    };
    let hits = tracer
        .trace(&options, &NoProgress)
        .expect("tracing succeeds")
        .len() as u64;
    let mut group = c.benchmark_group("trace_glosbox");
    group.sample_size(10);
    group.throughput(Throughput::Elements(PHOTONS));
    group.bench_function("photons", |b| {
        b.iter(|| black_box(tracer.trace(&options, &NoProgress).unwrap().len()))
    });
    group.throughput(Throughput::Elements(hits));
    group.bench_function("bounces", |b| {
        b.iter(|| black_box(tracer.trace(&options, &NoProgress).unwrap().len()))
    });
    group.finish();
}

criterion_group!(benches, trace);
criterion_main!(benches);
