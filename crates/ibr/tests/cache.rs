//! The radiance-map cache: round trip, and refusal of damaged, stale and foreign files.

mod support;

use lustre_ibr::{IbrError, QuadtreeSettings, ReflectorMaps, SamplingSettings, cache};
use support::Room;

fn maps(room: &Room) -> Vec<ReflectorMaps> {
    let sampling = SamplingSettings {
        planar_resolution: (2, 1),
        arc_step_degrees: 60.0,
        map_resolution: (12, 10),
        ..Default::default()
    };
    vec![
        ReflectorMaps::capture(
            &room.floor,
            &sampling,
            &QuadtreeSettings::default(),
            &|o, d| room.trace(o, d),
            &mut |_, _| {},
        )
        .unwrap(),
    ]
}

fn bad_cache(r: lustre_ibr::Result<Vec<ReflectorMaps>>) -> String {
    match r {
        Err(IbrError::BadCache { reason, .. }) => reason,
        other => panic!("expected a bad cache, got {other:?}"),
    }
}

#[test]
fn the_cache_round_trips_and_refuses_bad_files() {
    let room = Room::cornell();
    let maps = maps(&room);
    let dir = std::env::temp_dir().join(format!("lustre-ibr-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("maps.ibr");
    cache::write(&path, 42, maps.iter()).unwrap();
    // Nothing but the file itself: no temporary left behind.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let back = cache::read(&path, 42, &QuadtreeSettings::default()).unwrap();
    assert_eq!(back, maps);

    assert!(bad_cache(cache::read(&path, 43, &QuadtreeSettings::default())).contains("key"));

    let bytes = std::fs::read(&path).unwrap();
    let mut flipped = bytes.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x10;
    std::fs::write(&path, &flipped).unwrap();
    assert!(bad_cache(cache::read(&path, 42, &QuadtreeSettings::default())).contains("checksum"));

    std::fs::write(&path, &bytes[..bytes.len() / 3]).unwrap();
    bad_cache(cache::read(&path, 42, &QuadtreeSettings::default()));

    let mut version = bytes.clone();
    version[8] = 99;
    std::fs::write(&path, &version).unwrap();
    assert!(bad_cache(cache::read(&path, 42, &QuadtreeSettings::default())).contains("version"));

    std::fs::write(&path, b"not a cache at all, just text").unwrap();
    assert!(
        bad_cache(cache::read(&path, 42, &QuadtreeSettings::default())).contains("not a Lustre")
    );

    assert!(matches!(
        cache::read(&dir.join("missing.ibr"), 42, &QuadtreeSettings::default()),
        Err(IbrError::Io { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}
