//! Streamed photon files (section 2.1, hits stored on disk; incremental refinement): traced in blocks,
//! read in batches, traced in batches on several machines and merged. Each is checked against the
//! in-memory run of the same photons, byte for byte.

use std::path::{Path, PathBuf};

use lustre_geometry::{Bvh, Scene, builtin};
use lustre_photon::trace::batch_range;
use lustre_photon::{
    EmissionSampling, NoProgress, PhotonError, PhotonFileReader, PhotonFileWriter, PhotonTracer,
    Provenance, RECORD_BYTES, TraceOptions, allocate_photons, merge_photon_files, read_photon_file,
    write_photon_file,
};

/// A fresh scratch directory under the target directory.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("stream-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The provenance of a run with `options` in `scene`.
fn provenance(scene: &Scene, options: &TraceOptions) -> Provenance {
    Provenance {
        scene: lustre_photon::scene_fingerprint(scene),
        seed: options.seed,
        emission: options.emission,
        max_bounces: options.max_bounces,
        point_lights: false,
    }
}

/// Traces photons `first[i] .. first[i] + counts[i]` of each light into a file through the streamed tracer.
fn trace_file(
    scene: &Scene,
    path: &Path,
    first: &[u64],
    counts: &[u64],
    options: &TraceOptions,
    known: bool,
) {
    let bvh = Bvh::build(scene);
    let tracer = PhotonTracer::new(scene, &bvh).unwrap();
    let powers: Vec<_> = scene.lights().iter().map(|l| l.power()).collect();
    let mut writer = PhotonFileWriter::create(
        path,
        &powers,
        first.to_vec(),
        tracer.params(),
        known.then(|| provenance(scene, options)),
    )
    .unwrap();
    tracer
        .trace_streamed(
            first,
            counts,
            options,
            &NoProgress,
            &mut |emitted, records| writer.push(emitted, &records),
        )
        .unwrap();
    writer.finish().unwrap();
}

/// The 21-byte records of a file, sorted.
fn sorted_records(path: &Path) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(path).unwrap();
    let header = PhotonFileReader::open(path).unwrap().header().length();
    let mut records: Vec<Vec<u8>> = bytes[header..bytes.len() - 4]
        .chunks_exact(RECORD_BYTES)
        .map(<[u8]>::to_vec)
        .collect();
    records.sort();
    records
}

#[test]
fn streamed_tracing_writes_the_in_memory_runs_file() {
    let dir = scratch("blocks");
    let scene = builtin("glosbox").unwrap();
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).unwrap();
    // More than one block of the streamed tracer.
    let photons = lustre_photon::trace::PHOTONS_PER_BLOCK + 40_000;
    let options = TraceOptions {
        photons,
        seed: 7,
        ..TraceOptions::default()
    };
    let map = tracer.trace(&options, &NoProgress).unwrap();
    let memory = dir.join("memory.lph");
    write_photon_file(&memory, &map, tracer.params()).unwrap();
    let streamed = dir.join("streamed.lph");
    trace_file(&scene, &streamed, &[0], &[photons], &options, false);
    assert_eq!(
        std::fs::read(&memory).unwrap(),
        std::fs::read(&streamed).unwrap()
    );
    // Batches end on photon boundaries and together are the whole file.
    let reader = PhotonFileReader::open_for(&streamed, tracer.params()).unwrap();
    let whole = read_photon_file(&streamed).unwrap();
    for max in [1, 1000, 100_000] {
        let mut records = Vec::new();
        let mut batches = 0;
        for batch in reader.batches(max).unwrap() {
            let batch = batch.unwrap();
            assert_eq!(batch.lights(), whole.lights());
            assert_eq!(batch.records()[0].bounce, 1, "a batch starts a photon");
            let photons = batch.records().iter().filter(|r| r.bounce == 1).count();
            // At most `max` records before the last photon starts.
            let last_start = batch.records().iter().rposition(|r| r.bounce == 1).unwrap();
            assert!(
                last_start <= max,
                "batch of {max}: last photon at {last_start}"
            );
            if max == 1 {
                assert_eq!(photons, 1);
            }
            records.extend_from_slice(batch.records());
            batches += 1;
        }
        assert_eq!(records, whole.records(), "batches of {max}");
        assert!(
            batches >= whole.len().div_ceil(max + 255),
            "{batches} batches of {max}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn batches_of_a_run_merge_into_the_runs_file() {
    let dir = scratch("merge");
    // Five lights: batches split each light's photons.
    let scene = builtin("bathroom").unwrap();
    let options = TraceOptions {
        photons: 20_000,
        seed: 3,
        emission: EmissionSampling::Halton,
        ..TraceOptions::default()
    };
    let powers: Vec<_> = scene.lights().iter().map(|l| l.power()).collect();
    let counts = allocate_photons(&powers, options.photons);
    let single = dir.join("single.lph");
    trace_file(
        &scene,
        &single,
        &vec![0; counts.len()],
        &counts,
        &options,
        true,
    );
    let n = 3;
    let mut parts = Vec::new();
    // Written in reverse: the merge orders the batches by their photon ranges.
    for i in (0..n).rev() {
        let (first, batch) = batch_range(&counts, i, n).unwrap();
        let path = dir.join(format!("batch-{i}.lph"));
        trace_file(&scene, &path, &first, &batch, &options, true);
        parts.push(path);
    }
    let merged = dir.join("merged.lph");
    let header = merge_photon_files(&parts, &merged).unwrap();
    let whole = PhotonFileReader::open(&single).unwrap();
    assert_eq!(&header, whole.header());
    // Same header bytes, same records (batch by batch rather than light by light).
    let (a, b) = (
        std::fs::read(&single).unwrap(),
        std::fs::read(&merged).unwrap(),
    );
    let length = header.length();
    assert_eq!(a[..length], b[..length]);
    assert_eq!(sorted_records(&single), sorted_records(&merged));
    // A merge of the same batch twice, of a run with a gap, or of another seed is refused.
    let overlap = merge_photon_files(&[parts[0].clone(), parts[0].clone()], &dir.join("x.lph"));
    assert!(
        matches!(overlap, Err(PhotonError::Incompatible { .. })),
        "{overlap:?}"
    );
    let gap = merge_photon_files(&[parts[0].clone(), parts[2].clone()], &dir.join("x.lph"));
    assert!(
        matches!(gap, Err(PhotonError::Incompatible { .. })),
        "{gap:?}"
    );
    let other = dir.join("other-seed.lph");
    let (first, batch) = batch_range(&counts, 1, n).unwrap();
    trace_file(
        &scene,
        &other,
        &first,
        &batch,
        &TraceOptions { seed: 4, ..options },
        true,
    );
    let seeds = merge_photon_files(&[parts[0].clone(), other], &dir.join("x.lph"));
    assert!(
        matches!(seeds, Err(PhotonError::Incompatible { .. })),
        "{seeds:?}"
    );
    let unknown = dir.join("unknown.lph");
    trace_file(&scene, &unknown, &first, &batch, &options, false);
    let unknown = merge_photon_files(&[unknown, parts[0].clone()], &dir.join("x.lph"));
    assert!(
        matches!(unknown, Err(PhotonError::Incompatible { .. })),
        "{unknown:?}"
    );
    assert!(
        !dir.join("x.lph").exists(),
        "a refused merge writes nothing"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn appending_continues_the_run() {
    let dir = scratch("append");
    let scene = builtin("cornell").unwrap();
    let options = TraceOptions {
        photons: 5_000,
        seed: 11,
        ..TraceOptions::default()
    };
    let single = dir.join("single.lph");
    trace_file(&scene, &single, &[0], &[5_000], &options, true);
    let path = dir.join("appended.lph");
    trace_file(&scene, &path, &[0], &[3_000], &options, true);
    // Incremental refinement: the next photons of the file's own streams.
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).unwrap();
    let mut writer = PhotonFileWriter::append(&path, tracer.params()).unwrap();
    let h = writer.header().clone();
    let next = h.first[0] + h.lights[0].emitted;
    tracer
        .trace_streamed(&[next], &[2_000], &options, &NoProgress, &mut |e, r| {
            writer.push(e, &r)
        })
        .unwrap();
    writer.finish().unwrap();
    assert_eq!(
        std::fs::read(&single).unwrap(),
        std::fs::read(&path).unwrap()
    );
    // A writer dropped before `finish` leaves the file as it was and no temporary file.
    let before = std::fs::read(&path).unwrap();
    let mut writer = PhotonFileWriter::append(&path, tracer.params()).unwrap();
    writer.push(&[1], &[]).unwrap();
    drop(writer);
    assert_eq!(std::fs::read(&path).unwrap(), before);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 2, "{left:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn tallied_batch_estimates_add_up_to_the_whole_maps() {
    use lustre_photon::{BounceSelection, EstimatorOptions, SplatEstimator, SplatTally, Support};
    let dir = scratch("tally");
    let scene = builtin("glosbox").unwrap();
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).unwrap();
    let options = TraceOptions {
        photons: 20_000,
        seed: 5,
        ..TraceOptions::default()
    };
    let path = dir.join("photons.lph");
    trace_file(&scene, &path, &[0], &[options.photons], &options, true);
    let whole = read_photon_file(&path).unwrap();
    let estimator_options = EstimatorOptions {
        support: Support::GlossySilverman {
            kernel_c: 40.0,
            c: 1.25,
        },
        selection: BounceSelection::Indirect,
        edges: lustre_photon::Edges::Normalised,
        ..EstimatorOptions::default()
    };
    let reference = SplatEstimator::build(&scene, &whole, estimator_options).unwrap();
    let reader = PhotonFileReader::open_for(&path, tracer.params()).unwrap();
    let mut tally = SplatTally::new(tracer.params(), BounceSelection::Indirect);
    for batch in reader.batches(4_000).unwrap() {
        tally
            .add(tracer.params(), batch.unwrap().records())
            .unwrap();
    }
    // One template from the tally; each batch's estimator shares its supports and kernel mass.
    let empty = lustre_photon::PhotonMap::from_parts(whole.lights().to_vec(), Vec::new()).unwrap();
    let template =
        SplatEstimator::build_tallied(&scene, &empty, estimator_options, &tally).unwrap();
    let batches: Vec<SplatEstimator> = reader
        .batches(4_000)
        .unwrap()
        .map(|b| template.with_photons(&b.unwrap()))
        .collect::<Result<_, _>>()
        .unwrap();
    // The same as building each batch's estimator from the tally.
    let first = reader.batches(4_000).unwrap().next().unwrap().unwrap();
    let built = SplatEstimator::build_tallied(&scene, &first, estimator_options, &tally).unwrap();
    assert_eq!(built.splats(), batches[0].splats());
    assert!(batches.len() >= 4, "{} batches", batches.len());
    // Points on every surface: each surface's photons' own positions.
    let mut checked = 0;
    for splat in reference.splats().iter().step_by(97) {
        let s = splat.surface;
        assert!(batches.iter().all(|b| b.support(s) == reference.support(s)));
        let x = splat.position + 0.3 * splat.h * splat.normal.any_orthonormal_vector();
        let wo = splat.normal;
        let expected = reference.radiance(s, x, splat.normal, wo);
        let sum: glam::Vec3 = batches
            .iter()
            .map(|b| b.radiance(s, x, splat.normal, wo))
            .sum();
        let tolerance = 1e-5 * expected.max_element().max(1e-6);
        assert!(
            (sum - expected).abs().max_element() <= tolerance,
            "surface {s}: {sum} against {expected}"
        );
        checked += usize::from(expected.max_element() > 0.0);
    }
    assert!(checked > 20, "{checked} lit points");
    std::fs::remove_dir_all(dir).unwrap();
}
