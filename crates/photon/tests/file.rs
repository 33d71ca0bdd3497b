//! The 21-byte hit-record file (section 3.1): round trip, quantisation bounds, append, corrupt and truncated files.

use std::path::PathBuf;

use glam::{Vec2, Vec3};
use lustre_geometry::{Bvh, Rgb, builtin};
use lustre_photon::file::surface_table;
use lustre_photon::quantise::{
    DIRECTION_ERROR_BOUND, decode_direction, decode_rgbe, dequantise_coordinate, encode_direction,
    encode_rgbe, quantise_coordinate,
};
use lustre_photon::{
    NoProgress, PhotonError, PhotonMap, PhotonTracer, SurfaceParams, TraceOptions,
    append_photon_file, read_photon_file, read_photon_file_for, write_photon_file,
};
use proptest::prelude::*;

/// A fresh empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lustre-photon-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A small traced map of the Cornell box and its parameterisation.
fn cornell_map(photons: u64, seed: u64) -> (PhotonMap, SurfaceParams) {
    let scene = builtin("glosbox").unwrap();
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh).unwrap();
    let options = TraceOptions {
        photons,
        seed,
        ..TraceOptions::default()
    };
    (
        tracer.trace(&options, &NoProgress).unwrap(),
        tracer.params().clone(),
    )
}

/// Angle between unit vectors, robust near zero.
fn angle(a: Vec3, b: Vec3) -> f32 {
    2.0 * ((a - b).length() * 0.5).clamp(0.0, 1.0).asin()
}

/// Asserts the decoded record is within the documented bounds of the original.
fn assert_within_bounds(a: &lustre_photon::HitRecord, b: &lustre_photon::HitRecord, extent: Vec2) {
    assert_eq!(
        (a.surface, a.triangle, a.light, a.bounce),
        (b.surface, b.triangle, b.light, b.bounce)
    );
    let tol = extent * (2.0f32).powi(-24) + a.position.abs() * f32::EPSILON;
    assert!(
        ((a.position - b.position).abs() - tol).max_element() <= 0.0,
        "{a:?} {b:?}"
    );
    assert!(
        angle(a.direction, b.direction) <= DIRECTION_ERROR_BOUND,
        "{a:?} {b:?}"
    );
    assert!(
        ((a.rho - b.rho).abs().max_element()) <= a.rho.max_element() / 255.0,
        "{a:?} {b:?}"
    );
}

#[test]
fn round_trip_is_within_quantisation_bounds() {
    let dir = scratch("round-trip");
    let path = dir.join("photons.lph");
    let (map, params) = cornell_map(3_000, 1);
    write_photon_file(&path, &map, &params).unwrap();
    let len = std::fs::metadata(&path).unwrap().len() as usize;
    let table = surface_table(&params);
    let header = 44 + 28 * map.lights().len() + 17 * table.len() + 4;
    assert_eq!(len, header + 21 * map.len() + 4, "21 bytes per record");
    let back = read_photon_file_for(&path, &params).unwrap();
    assert_eq!(back.lights(), map.lights());
    assert_eq!(back.len(), map.len());
    for (a, b) in map.records().iter().zip(back.records()) {
        assert_within_bounds(a, b, table[a.surface as usize].range.extent);
    }
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn append_adds_photons_without_touching_earlier_records() {
    let dir = scratch("append");
    let path = dir.join("photons.lph");
    let (a, params) = cornell_map(1_000, 1);
    let (b, _) = cornell_map(500, 2);
    write_photon_file(&path, &a, &params).unwrap();
    let before = std::fs::read(&path).unwrap();
    append_photon_file(&path, &b, &params).unwrap();
    let merged = read_photon_file(&path).unwrap();
    assert_eq!(merged.emitted(), 1_500);
    assert_eq!(merged.len(), a.len() + b.len());
    let mut expected = read_photon_file_for(&path, &params).unwrap();
    expected =
        PhotonMap::from_parts(expected.lights().to_vec(), expected.records().to_vec()).unwrap();
    assert_eq!(merged, expected);
    // The first file's record bytes are kept verbatim.
    let after = std::fs::read(&path).unwrap();
    let header = before.len() - 4 - 21 * a.len();
    assert_eq!(
        &after[header..header + 21 * a.len()],
        &before[header..before.len() - 4]
    );
    // Same as writing the merged map in one go.
    let mut whole = a.clone();
    whole.append(b.clone()).unwrap();
    let single = dir.join("single.lph");
    write_photon_file(&single, &whole, &params).unwrap();
    assert_eq!(std::fs::read(&single).unwrap(), after);
    // A map of other lights is refused and leaves the file alone.
    let other = PhotonMap::new([Rgb::ONE]);
    assert!(matches!(
        append_photon_file(&path, &other, &params),
        Err(PhotonError::LightMismatch(_))
    ));
    assert_eq!(std::fs::read(&path).unwrap(), after);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn truncated_and_corrupt_files_are_typed_errors() {
    let dir = scratch("corrupt");
    let path = dir.join("photons.lph");
    let (map, params) = cornell_map(20, 3);
    write_photon_file(&path, &map, &params).unwrap();
    let good = std::fs::read(&path).unwrap();
    let bad = dir.join("bad.lph");
    for len in 0..good.len() {
        std::fs::write(&bad, &good[..len]).unwrap();
        let e = read_photon_file(&bad).unwrap_err();
        assert!(
            matches!(e, PhotonError::Truncated { .. }),
            "length {len}: {e}"
        );
    }
    let mut longer = good.clone();
    longer.push(0);
    std::fs::write(&bad, &longer).unwrap();
    assert!(matches!(
        read_photon_file(&bad),
        Err(PhotonError::TrailingBytes { .. })
    ));
    for at in 0..good.len() {
        for bit in [0x01u8, 0x80] {
            let mut b = good.clone();
            b[at] ^= bit;
            std::fs::write(&bad, &b).unwrap();
            assert!(read_photon_file(&bad).is_err(), "flipped byte {at}");
        }
    }
    let mut v2 = good.clone();
    v2[8] = 3;
    std::fs::write(&bad, &v2).unwrap();
    assert!(matches!(
        read_photon_file(&bad),
        Err(PhotonError::UnsupportedVersion { found: 3, .. })
    ));
    std::fs::write(&bad, b"not a photon file at all, just some text").unwrap();
    assert!(matches!(
        read_photon_file(&bad),
        Err(PhotonError::BadMagic { .. })
    ));
    assert!(matches!(
        read_photon_file(&dir.join("missing.lph")),
        Err(PhotonError::Io { .. })
    ));
    assert!(matches!(
        write_photon_file(&dir.join("no/such/dir/x.lph"), &map, &params),
        Err(PhotonError::Io { .. })
    ));
    // A file of another scene is refused by the checked reader.
    let plane = builtin("cornell").unwrap();
    let mut moved = plane.clone();
    moved
        .set_object_transform(
            moved.object_by_name("small-box").unwrap(),
            glam::Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)),
        )
        .unwrap();
    assert!(matches!(
        read_photon_file_for(&path, &SurfaceParams::new(&moved)),
        Err(PhotonError::SceneMismatch { .. })
    ));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn direction_bound_holds_on_a_dense_set() {
    // A Fibonacci sphere of 200k directions plus the axes and octant diagonals.
    let n = 200_000;
    let mut worst = 0.0f32;
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    let mut dirs: Vec<Vec3> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    dirs.extend([
        Vec3::X,
        -Vec3::X,
        Vec3::Y,
        -Vec3::Y,
        Vec3::Z,
        -Vec3::Z,
        Vec3::ONE.normalize(),
        -Vec3::ONE.normalize(),
    ]);
    for d in dirs {
        worst = worst.max(angle(d, decode_direction(encode_direction(d))));
    }
    eprintln!(
        "largest octahedral direction error: {:.5} degrees",
        worst.to_degrees()
    );
    assert!(worst <= DIRECTION_ERROR_BOUND);
}

proptest! {
    #[test]
    fn coordinate_error_is_bounded(min in -100.0f32..100.0, extent in 1e-3f32..100.0, t in 0.0f32..=1.0) {
        let x = min + t * extent;
        let back = dequantise_coordinate(quantise_coordinate(x, min, extent), min, extent);
        prop_assert!((back - x).abs() <= extent * 2f32.powi(-24) + x.abs() * f32::EPSILON);
    }

    #[test]
    fn direction_error_is_bounded(x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0) {
        let d = Vec3::new(x, y, z);
        prop_assume!(d.length() > 1e-3);
        let d = d.normalize();
        prop_assert!(angle(d, decode_direction(encode_direction(d))) <= DIRECTION_ERROR_BOUND);
    }

    #[test]
    fn rgbe_error_is_bounded(r in 0.0f32..4.0, g in 0.0f32..4.0, b in 0.0f32..4.0, scale in -30i32..30) {
        let rho = Vec3::new(r, g, b) * (scale as f32).exp2();
        let back = decode_rgbe(encode_rgbe(rho).unwrap());
        prop_assert!((back - rho).abs().max_element() <= rho.max_element() / 255.0);
    }
}

#[test]
fn unrepresentable_attenuation_is_an_error() {
    assert!(encode_rgbe(Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
    assert!(encode_rgbe(Vec3::new(-1.0, 0.0, 0.0)).is_err());
    assert!(encode_rgbe(Vec3::splat(1e38)).is_err());
    assert_eq!(decode_rgbe(encode_rgbe(Vec3::ZERO).unwrap()), Vec3::ZERO);
    assert_eq!(decode_rgbe(encode_rgbe(Vec3::ONE).unwrap()), Vec3::ONE);
}
