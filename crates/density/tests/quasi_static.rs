//! The incremental recalculation of section 2 against a full recomputation: after random rigid motions of one or several mobile objects, the updated ray set equals a full trace of the new pose (figure 2.2 against figure 2.1), and the incrementally updated irradiance equals the estimate computed from scratch (equations 2.4–2.15, figure 2.4) up to rounding.

use glam::{Affine3A, DVec3, Quat, Vec3};
use lustre_density::PreTest;
use lustre_density::artifact::ArtifactOptions;
use lustre_density::glossy::GlossyMode;
use lustre_density::quadtree::QuadTreeOptions;
use lustre_density::{
    DensityError, Disc, DiscSet, DiscSetOptions, Estimator, QuasiStatic, QuasiStaticOptions,
    RaySegment, RaySetOptions, SegmentHit, Twins, World, photon_maps, photon_maps_radiance,
    trace_ray_set_in, update_ray_set,
};
use lustre_geometry::animation::{Keyframe, ObjectPath, PathEnd};
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{ObjectId, Rgb, Scene, builtin};
use proptest::prelude::*;

/// The Cornell box with every mesh subdivided to edges of at most `edge` metres.
fn cornell(edge: f32) -> Scene {
    let scene = builtin("cornell").expect("built-in");
    let meshes = scene
        .meshes()
        .iter()
        .map(|m| subdivide(m, edge).expect("subdivides"))
        .collect();
    scene.with_meshes(meshes).expect("valid")
}

fn options(estimator: Estimator) -> QuasiStaticOptions {
    with_artifact(estimator, None)
}

fn with_artifact(estimator: Estimator, artifact: Option<ArtifactOptions>) -> QuasiStaticOptions {
    QuasiStaticOptions {
        artifact,
        glossy_radius: None,
        glossy: None,
        acceleration: None,
        pretest: PreTest::None,
        max_glossy_rays: None,
        rays: RaySetOptions {
            photons: 4_000,
            seed: 3,
            max_segments: 16,
            extension: 0.0,
        },
        estimator,
    }
}

/// A rigid motion on the floor: a translation in x and z and a turn about y, applied after the object's rest transform.
fn motion(rest: Affine3A, dx: f32, dz: f32, degrees: f32) -> Affine3A {
    Affine3A::from_rotation_translation(
        Quat::from_rotation_y(degrees.to_radians()),
        Vec3::new(dx, 0.0, dz),
    ) * rest
}

/// Largest difference between two per-point irradiances, relative to the largest value.
fn relative_difference(a: &[DVec3], b: &[DVec3]) -> f64 {
    let scale = b
        .iter()
        .map(|e| e.max_element())
        .fold(0.0, f64::max)
        .max(1e-30);
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f64::max)
        / scale
}

fn check_frames(estimator: Estimator, objects: &[&str], moves: &[(f32, f32, f32)]) {
    check_frames_with(options(estimator), objects, moves);
}

fn check_frames_with(options: QuasiStaticOptions, objects: &[&str], moves: &[(f32, f32, f32)]) {
    let scene = cornell(0.25);
    let ids: Vec<ObjectId> = objects
        .iter()
        .map(|n| scene.object_by_name(n).expect("object"))
        .collect();
    let rest: Vec<Affine3A> = ids
        .iter()
        .map(|&o| scene.objects()[o as usize].transform)
        .collect();
    let mut sim = QuasiStatic::new(scene.clone(), &ids, options).expect("first frame");
    // The world a full trace uses: built at the first pose (its ray offset is fixed there), then moved.
    let mut fresh_world = World::new(&scene, &ids).expect("world");
    let mut fresh_scene = scene;
    let mut recalculated = 0;
    for (frame, &(dx, dz, degrees)) in moves.iter().enumerate() {
        let pose: Vec<(ObjectId, Affine3A)> = ids
            .iter()
            .zip(&rest)
            .enumerate()
            .map(|(i, (&o, &r))| {
                let s = if i % 2 == 0 { 1.0 } else { -0.5 };
                (o, motion(r, s * dx, s * dz, s * degrees))
            })
            .collect();
        let stats = sim.set_pose(&pose).expect("frame");
        recalculated += stats.recalculated;
        for &(o, t) in &pose {
            fresh_scene.set_object_transform(o, t).expect("pose");
        }
        fresh_world.move_mobile(&fresh_scene);
        let full =
            trace_ray_set_in(&fresh_scene, &fresh_world, &sim_rays(&options)).expect("trace");
        assert!(
            sim.rays() == &full,
            "frame {frame}: the updated ray set differs from a full trace of the new pose"
        );
        let incremental = sim.point_irradiance();
        let scratch = sim.recompute_point_irradiance();
        let d = relative_difference(&incremental, &scratch);
        assert!(
            d < 1e-9,
            "frame {frame}: incremental and full irradiance differ by {d:e} of the largest value"
        );
    }
    assert!(
        recalculated > 0,
        "the motions changed no ray; the test proves nothing"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn detp_incremental_equals_full(moves in prop::collection::vec((-0.4f32..0.4, -0.4f32..0.4, -90.0f32..90.0), 3)) {
        check_frames(Estimator::Detp { radius: 0.15 }, &["small-box"], &moves);
    }

    #[test]
    fn impact_count_incremental_equals_full(moves in prop::collection::vec((-0.4f32..0.4, -0.4f32..0.4, -90.0f32..90.0), 3)) {
        check_frames(Estimator::ImpactCount, &["small-box"], &moves);
    }

    #[test]
    fn several_mobile_objects(moves in prop::collection::vec((-0.2f32..0.2, -0.2f32..0.2, -45.0f32..45.0), 2)) {
        check_frames(Estimator::Detp { radius: 0.15 }, &["small-box", "large-box"], &moves);
    }
}

/// The ray options a simulation traces with: artifact control sets the concave extension to `max_extension · r`.
fn sim_rays(options: &QuasiStaticOptions) -> RaySetOptions {
    let mut rays = options.rays;
    if let (Some(a), Estimator::Detp { radius }) = (options.artifact, options.estimator) {
        rays.extension = a.max_extension * radius;
    }
    rays
}

#[test]
fn artifact_controlled_detp_incremental_equals_full() {
    let artifact = ArtifactOptions {
        samples_per_axis: 8,
        ..ArtifactOptions::default()
    };
    check_frames_with(
        with_artifact(Estimator::Detp { radius: 0.15 }, Some(artifact)),
        &["small-box"],
        &[(0.3, 0.1, 30.0), (-0.2, 0.2, -10.0)],
    );
}

/// Photon Maps in the loop (section 2.5.2: estimated in full every frame) against the free `photon_maps` and `photon_maps_radiance` on an independently traced ray set of the scene posed at each frame: the loop's kd-tree must hold the frame's impacts, not the first frame's.
#[test]
fn photon_maps_follow_the_motion() {
    let scene = glosbox(0.4);
    let small = scene.object_by_name("small-box").expect("object");
    let rest = scene.objects()[small as usize].transform;
    let k = 20;
    let mut options = options(Estimator::PhotonMaps { k });
    options.glossy = Some(GlossyMode::List);
    let mut sim = QuasiStatic::new(scene.clone(), &[small], options).expect("first frame");
    let eye = scene.camera().position;
    let mut fresh_world = World::new(&scene, &[small]).expect("world");
    let mut fresh_scene = scene;
    let first = sim.irradiance();
    let mut moved_vertices = 0;
    for (frame, (dx, dz, degrees)) in [(0.3, 0.1, 30.0), (-0.2, 0.2, -10.0)]
        .into_iter()
        .enumerate()
    {
        let pose = motion(rest, dx, dz, degrees);
        sim.set_pose(&[(small, pose)]).expect("frame");
        fresh_scene.set_object_transform(small, pose).expect("pose");
        fresh_world.move_mobile(&fresh_scene);
        let rays = trace_ray_set_in(&fresh_scene, &fresh_world, &options.rays).expect("trace");
        let expected = photon_maps(&fresh_scene, &rays, k).expect("photon maps");
        let got = sim.irradiance();
        let (mut worst, mut scale) = (0.0f32, 0.0f32);
        for (a, b) in got.iter().flatten().zip(expected.iter().flatten()) {
            worst = worst.max((*a - *b).abs().max_element());
            scale = scale.max(b.max_element());
        }
        assert!(
            worst <= 1e-5 * scale,
            "frame {frame}: loop and fresh Photon Maps irradiance differ by {worst} (largest {scale})"
        );
        moved_vertices += got
            .iter()
            .flatten()
            .zip(first.iter().flatten())
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * scale)
            .count();
        let expected = photon_maps_radiance(&fresh_scene, &rays, k, eye).expect("radiance");
        let got = sim
            .glossy_radiance(eye)
            .expect("radiance")
            .expect("glossy on");
        let (mut worst, mut scale, mut lit) = (0.0f32, 0.0f32, 0);
        for (a, b) in got.iter().flatten().zip(expected.iter().flatten()) {
            worst = worst.max((*a - *b).abs().max_element());
            scale = scale.max(b.max_element());
            lit += usize::from(a.max_element() > 0.0);
        }
        assert!(lit > 100, "frame {frame}: {lit} lit glossy vertices");
        assert!(
            worst <= 1e-5 * scale,
            "frame {frame}: loop and fresh Photon Maps glossy radiance differ by {worst} (largest {scale})"
        );
    }
    assert!(
        moved_vertices > 100,
        "the motion changed only {moved_vertices} vertices' irradiance; the test proves little"
    );
}

/// How many of `radiance` are lit (some channel above zero).
fn count_lit<'a>(radiance: impl Iterator<Item = &'a Rgb>) -> usize {
    radiance.filter(|l| l.max_element() > 0.0).count()
}

/// The glosbox with every mesh subdivided to edges of at most `edge` metres.
fn glosbox(edge: f32) -> Scene {
    let s = builtin("glosbox").expect("built-in");
    let meshes = s
        .meshes()
        .iter()
        .map(|m| subdivide(m, edge).expect("subdivides"))
        .collect();
    s.with_meshes(meshes).expect("valid")
}

/// Impact Count's per-triangle impact lists of glossy meshes (section 2.10 with figure 2.4), updated with OldRays and NewRays, give the glossy radiance that lists rebuilt from the frame's ray set give, and that a fresh simulation at the new pose gives.
#[test]
fn impact_count_glossy_lists_follow_the_motion() {
    let scene = glosbox(0.4);
    let small = scene.object_by_name("small-box").expect("object");
    let rest = scene.objects()[small as usize].transform;
    let mut options = options(Estimator::ImpactCount);
    options.glossy = Some(GlossyMode::List);
    let mut sim = QuasiStatic::new(scene.clone(), &[small], options).expect("first frame");
    let eye = scene.camera().position;
    let first = sim
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let mut changed = 0;
    let mut pose = rest;
    for (dx, dz, degrees) in [(-0.3, 0.1, 20.0), (0.2, -0.1, -40.0)] {
        pose = motion(rest, dx, dz, degrees);
        sim.set_pose(&[(small, pose)]).expect("frame");
        let incremental = sim
            .glossy_radiance(eye)
            .expect("radiance")
            .expect("glossy on");
        let scratch = sim
            .recompute_glossy_radiance(eye)
            .expect("radiance")
            .expect("impact count");
        // Sorted lists of the same multiset sum in the same order: bit-identical.
        assert_eq!(incremental, scratch);
        changed += incremental
            .iter()
            .flatten()
            .zip(first.iter().flatten())
            .filter(|(a, b)| a != b)
            .count();
    }
    assert!(
        changed > 50,
        "the motion changed only {changed} glossy vertices"
    );
    let mut moved = scene;
    moved.set_object_transform(small, pose).expect("pose");
    let fresh = QuasiStatic::new(moved, &[small], options).expect("fresh");
    assert!(sim.rays() == fresh.rays(), "the ray sets differ");
    let scratch = fresh
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let incremental = sim
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    assert_eq!(incremental, scratch);
    let lit = count_lit(incremental.iter().flatten());
    let total = incremental.iter().flatten().count();
    assert!(lit > total / 4, "{lit} of {total} glossy vertices lit");
}

#[test]
fn refused_input_leaves_the_simulation_unchanged() {
    let scene = cornell(0.5);
    let small = scene.object_by_name("small-box").expect("object");
    let floor = scene.object_by_name("floor").expect("object");
    let mut sim =
        QuasiStatic::new(scene, &[small], options(Estimator::ImpactCount)).expect("first frame");
    let before = sim.point_irradiance();
    assert!(
        sim.set_pose(&[(floor, Affine3A::IDENTITY)]).is_err(),
        "a static object cannot move"
    );
    let nan = Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
    assert!(
        sim.set_pose(&[(small, Affine3A::IDENTITY), (small, nan)])
            .is_err()
    );
    assert_eq!(sim.point_irradiance(), before);
    let light = sim.scene().object_by_name("light").expect("light");
    let err = QuasiStatic::new(
        sim.scene().clone(),
        &[light],
        options(Estimator::ImpactCount),
    )
    .unwrap_err();
    assert!(err.to_string().contains("emits light"), "{err}");
    let bad = QuasiStatic::new(
        sim.scene().clone(),
        &[small],
        options(Estimator::Detp { radius: -1.0 }),
    );
    assert!(bad.is_err());
}

/// The glosbox (edges of 0.4 m) with its small box mobile under DETP (r = 0.2) and the QuadTree glossy estimate: the scene, the box, its rest pose and the simulation's first frame.
fn glossy_quadtree_simulation() -> (Scene, ObjectId, Affine3A, QuasiStatic) {
    let scene = glosbox(0.4);
    let small = scene.object_by_name("small-box").expect("object");
    let rest = scene.objects()[small as usize].transform;
    let mut options = options(Estimator::Detp { radius: 0.2 });
    options.glossy = Some(GlossyMode::QuadTree {
        options: QuadTreeOptions::default(),
        tolerance: 0.01,
    });
    let sim = QuasiStatic::new(scene.clone(), &[small], options).expect("first frame");
    (scene, small, rest, sim)
}

/// The glossy radiance towards a resting eye, recomputed each frame only for the vertices whose lists changed, equals the radiance computed for every vertex, bit for bit, also after the eye moves away and back.
#[test]
fn glossy_radiance_of_a_resting_eye_equals_a_full_recomputation() {
    let (scene, small, rest, mut cached) = glossy_quadtree_simulation();
    let mut full = cached.clone();
    let never = Vec3::new(9.0, 9.0, 9.0);
    let eye = scene.camera().position;
    let elsewhere = eye + Vec3::new(0.4, -0.2, 0.3);
    let radiance = |sim: &QuasiStatic, eye: Vec3| {
        sim.glossy_radiance(eye)
            .expect("radiance")
            .expect("glossy on")
    };
    let mut previous = radiance(&cached, eye);
    let (mut kept, mut changed) = (0, 0);
    for (frame, (dx, dz, degrees)) in [(-0.3, 0.1, 20.0), (0.2, -0.1, -40.0), (0.1, 0.2, 10.0)]
        .into_iter()
        .enumerate()
    {
        let pose = [(small, motion(rest, dx, dz, degrees))];
        cached.set_pose(&pose).expect("frame");
        full.set_pose(&pose).expect("frame");
        if frame == 1 {
            // The eye moves away and back: everything is computed again, then kept.
            assert_eq!(radiance(&cached, elsewhere), radiance(&full, elsewhere));
        }
        let got = radiance(&cached, eye);
        // `full`'s cache is never at this eye when asked, so it computes every vertex.
        let expected = radiance(&full, eye);
        radiance(&full, never);
        assert_eq!(got, expected, "frame {frame}");
        for (a, b) in got.iter().flatten().zip(previous.iter().flatten()) {
            if a == b {
                kept += 1;
            } else {
                changed += 1;
            }
        }
        previous = got;
    }
    assert!(
        changed > 50 && kept > 50,
        "{changed} glossy vertices changed and {kept} kept their radiance: the test proves little"
    );
}

/// Frames' Old and New Rays deferred on glossy vertices facing away from the eye (applied when an eye in front of them asks) give, bit for bit, the radiance of a simulation that applied every frame's rays at once: towards the resting eye each frame, then from behind, where the deferred vertices are seen.
#[test]
fn deferred_glossy_rays_give_the_radiance_of_rays_applied_at_once() {
    let (scene, small, rest, mut lazy) = glossy_quadtree_simulation();
    // Never asked until the end: no eye, so every frame's rays are applied at once.
    let mut eager = lazy.clone();
    let eye = scene.camera().position;
    let centre = scene.bounds().center();
    let behind = centre + (centre - eye);
    let radiance = |sim: &QuasiStatic, eye: Vec3| {
        sim.glossy_radiance(eye)
            .expect("radiance")
            .expect("glossy on")
    };
    radiance(&lazy, eye);
    let mut deferred = 0;
    for (dx, dz, degrees) in [(-0.3, 0.1, 20.0), (0.2, -0.1, -40.0), (0.1, 0.2, 10.0)] {
        let pose = [(small, motion(rest, dx, dz, degrees))];
        lazy.set_pose(&pose).expect("frame");
        eager.set_pose(&pose).expect("frame");
        deferred = deferred.max(lazy.deferred_glossy_rays());
        radiance(&lazy, eye);
    }
    assert_eq!(eager.deferred_glossy_rays(), 0);
    assert!(
        deferred > 100,
        "only {deferred} rays deferred: the test proves little"
    );
    assert_eq!(radiance(&lazy, eye), radiance(&eager, eye));
    let seen = radiance(&lazy, behind);
    assert_eq!(seen, radiance(&eager, behind));
    assert!(
        lazy.deferred_glossy_rays() < deferred,
        "the eye behind caught up no deferred vertex"
    );
    let lit = count_lit(seen.iter().flatten());
    assert!(lit > 50, "only {lit} glossy vertices lit from behind");
    // And a frame after the eye moved applies the rest as the new eye sees them.
    let pose = [(small, motion(rest, 0.0, 0.0, 0.0))];
    lazy.set_pose(&pose).expect("frame");
    eager.set_pose(&pose).expect("frame");
    assert_eq!(radiance(&lazy, eye), radiance(&eager, eye));
}

/// Glossy vertices (section 2.10): the ray lists of static glossy vertices updated with OldRays and NewRays give the radiance that lists built from scratch at the new pose give.
#[test]
fn glossy_lists_follow_the_motion() {
    let scene = glosbox(0.4);
    let small = scene.object_by_name("small-box").expect("object");
    let mut options = options(Estimator::Detp { radius: 0.2 });
    options.glossy = Some(GlossyMode::List);
    let mut sim = QuasiStatic::new(scene.clone(), &[small], options).expect("first frame");
    let eye = scene.camera().position;
    let pose = [(small, Affine3A::from_translation(Vec3::new(-0.3, 0.0, 0.1)))];
    sim.set_pose(&pose).expect("frame");
    let incremental = sim
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let mut moved = scene;
    moved.set_object_transform(small, pose[0].1).expect("pose");
    let fresh = QuasiStatic::new(moved, &[small], options).expect("fresh");
    assert!(
        sim.rays() == fresh.rays(),
        "the scene bounds changed, so the ray offsets differ"
    );
    let scratch = fresh
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let (mut compared, mut worst) = (0, 0.0f32);
    for (a, b) in incremental.iter().flatten().zip(scratch.iter().flatten()) {
        let scale = b.max_element().max(1e-6);
        worst = worst.max((*a - *b).abs().max_element() / scale);
        compared += 1;
    }
    assert!(compared > 100, "only {compared} glossy vertices");
    assert!(
        worst < 1e-4,
        "incremental and rebuilt glossy radiance differ by {worst}"
    );
    let lit = count_lit(incremental.iter().flatten());
    assert!(
        lit > compared / 2,
        "{lit} of {compared} glossy vertices are lit"
    );
}

/// The first frame through every acceleration and pre-test (sections 2.6–2.8) equals the plain every-segment-at-every-vertex DETP of `detp` on the same ray set, vertex by vertex.
#[test]
fn every_acceleration_gives_the_plain_detp() {
    use lustre_density::{Acceleration, detp};
    let scene = cornell(0.25);
    let radius = 0.15;
    let plain = {
        let sim = QuasiStatic::new(scene.clone(), &[], options(Estimator::Detp { radius }))
            .expect("first frame");
        detp(sim.scene(), sim.rays(), radius).expect("detp")
    };
    for (acceleration, pretest) in [
        (Acceleration::BruteForce, PreTest::None),
        (
            Acceleration::RayCache { sorted: true },
            PreTest::MollerTrumbore,
        ),
        (Acceleration::RayCache { sorted: false }, PreTest::Badouel),
        (
            Acceleration::DiscIndex {
                max_per_leaf: 4,
                max_depth: 24,
            },
            PreTest::Plucker,
        ),
        (Acceleration::SegmentGrid { cell_size: 0.2 }, PreTest::None),
    ] {
        let mut o = options(Estimator::Detp { radius });
        o.acceleration = Some(acceleration);
        o.pretest = pretest;
        let sim = QuasiStatic::new(scene.clone(), &[], o).expect("first frame");
        let e = sim.irradiance();
        let mut worst = 0.0f32;
        for (a, b) in e.iter().flatten().zip(plain.iter().flatten()) {
            worst = worst.max((*a - *b).abs().max_element() / b.max_element().max(1e-3));
        }
        assert!(
            worst < 1e-5,
            "{acceleration:?} + {pretest:?}: differs from plain DETP by {worst}"
        );
    }
}

/// Glossy vertices with a glossy disc radius of their own (section 2.10) under artifact control, the gold box mobile: after two frames, the static glossy floor's lists updated with OldRays and NewRays and the gold box's rebuilt lists and reachable areas give the radiance a fresh simulation at the final pose gives; the glossy radius changes the estimate.
#[test]
fn glossy_radius_lists_follow_the_motion_under_artifact_control() {
    let scene = glosbox(0.4);
    let small = scene.object_by_name("small-box").expect("object");
    let gold = scene.object_by_name("large-box").expect("object");
    let mut options = with_artifact(
        Estimator::Detp { radius: 0.15 },
        Some(ArtifactOptions {
            samples_per_axis: 8,
            ..ArtifactOptions::default()
        }),
    );
    options.glossy = Some(GlossyMode::List);
    options.glossy_radius = Some(0.35);
    let mobile = [small, gold];
    let mut sim = QuasiStatic::new(scene.clone(), &mobile, options).expect("first frame");
    let eye = scene.camera().position;
    let rest = |o| scene.objects()[o as usize].transform;
    let poses = [
        [
            (small, motion(rest(small), -0.2, 0.1, 15.0)),
            (gold, motion(rest(gold), 0.1, 0.05, -10.0)),
        ],
        [
            (small, motion(rest(small), 0.1, -0.1, -20.0)),
            (gold, motion(rest(gold), 0.15, 0.1, 25.0)),
        ],
    ];
    for pose in &poses {
        sim.set_pose(pose).expect("frame");
    }
    let incremental = sim
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let mut moved = scene.clone();
    for &(o, t) in &poses[1] {
        moved.set_object_transform(o, t).expect("pose");
    }
    let fresh = QuasiStatic::new(moved.clone(), &mobile, options).expect("fresh");
    assert!(sim.rays() == fresh.rays(), "the ray sets differ");
    let scratch = fresh
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let (mut compared, mut worst) = (0, 0.0f32);
    for (a, b) in incremental.iter().flatten().zip(scratch.iter().flatten()) {
        let scale = b.max_element().max(1e-6);
        worst = worst.max((*a - *b).abs().max_element() / scale);
        compared += usize::from(b.max_element() > 0.0);
    }
    let gold_mesh = moved.objects()[gold as usize].meshes[0] as usize;
    assert!(
        count_lit(incremental[gold_mesh].iter()) > 20,
        "the gold box is not lit"
    );
    assert!(compared > 100, "only {compared} lit glossy vertices");
    assert!(
        worst < 1e-4,
        "incremental and rebuilt glossy radiance differ by {worst}"
    );
    // One radius for both parts gives another estimate.
    options.glossy_radius = None;
    let single = QuasiStatic::new(moved, &mobile, options)
        .expect("single radius")
        .glossy_radiance(eye)
        .expect("radiance")
        .expect("glossy on");
    let differ = single
        .iter()
        .flatten()
        .zip(scratch.iter().flatten())
        .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * b.max_element())
        .count();
    assert!(
        differ > compared / 2,
        "the glossy radius changed only {differ} of {compared}"
    );
}

/// The path cells over the reach of the mobile object's path (beyond the paper: a finer grid than one over the whole scene): frames along the small box's path, then two off it (the cells are rebuilt over the whole scene), each give the ray set a full trace of the pose gives and the irradiance a recomputation over it gives.
#[test]
fn frames_along_a_path_and_off_it_match_full_traces() {
    let rest_scene = cornell(0.25);
    let small = rest_scene.object_by_name("small-box").expect("object");
    let positions =
        &rest_scene.meshes()[rest_scene.objects()[small as usize].meshes[0] as usize].positions;
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let pivot = 0.5 * (lo + hi);
    let keys = (0..=4)
        .map(|k| {
            let s = k as f32 / 4.0;
            Keyframe::new(
                s,
                pivot + Vec3::new(-0.15 * s, 0.0, 0.1 * s),
                Quat::from_rotation_y(0.6 * s),
            )
        })
        .collect();
    let path = ObjectPath::new(keys, PathEnd::Clamp)
        .and_then(|p| p.with_pivot(pivot))
        .expect("path");
    let scene = rest_scene
        .with_mobile("small-box", path.clone())
        .expect("mobile");
    let options = options(Estimator::Detp { radius: 0.15 });
    let mut sim = QuasiStatic::new(scene.clone(), &[small], options).expect("first frame");
    let mut poses = path.frames(5);
    // Off the path, twice (the cells are rebuilt over the whole scene once).
    poses.push(Affine3A::from_translation(Vec3::new(-0.6, 0.0, 0.0)) * poses[2]);
    poses.push(Affine3A::from_translation(Vec3::new(-0.7, 0.0, 0.3)) * poses[2]);
    let mut fresh_world = World::new(&scene, &[small]).expect("world");
    let mut fresh_scene = scene;
    for (frame, &pose) in poses.iter().enumerate().skip(1) {
        sim.set_pose(&[(small, pose)]).expect("frame");
        fresh_scene.set_object_transform(small, pose).expect("pose");
        fresh_world.move_mobile(&fresh_scene);
        let full = trace_ray_set_in(&fresh_scene, &fresh_world, &options.rays).expect("full trace");
        assert!(
            sim.rays() == &full,
            "frame {frame}: the updated ray set differs from a full trace"
        );
        let difference =
            relative_difference(&sim.point_irradiance(), &sim.recompute_point_irradiance());
        assert!(
            difference < 1e-9,
            "frame {frame}: incremental irradiance off by {difference}"
        );
    }
}

/// A frame's [`lustre_density::RayUpdate::twins`], paired as the update re-traces each path, against the
/// twins found by their bits alone (the same here: no two re-traced segments share their bits).
#[test]
fn an_update_pairs_each_retraced_path_with_its_twin() {
    let scene = cornell(0.25);
    let small = scene.object_by_name("small-box").expect("object");
    let mut options = sim_rays(&options(Estimator::Detp { radius: 0.15 }));
    options.photons = 20_000;
    let mut world = World::new(&scene, &[small]).expect("world");
    let mut rays = trace_ray_set_in(&scene, &world, &options).expect("trace");
    let mut moved = scene.clone();
    let rest = scene.objects()[small as usize].transform;
    moved
        .set_object_transform(small, motion(rest, 0.2, -0.1, 25.0))
        .expect("pose");
    world.move_mobile(&moved);
    let update = update_ray_set(&moved, &world, &mut rays, &options).expect("update");
    assert_eq!(
        update.twins,
        Twins::by_bits(&update.old, &update.new),
        "the update's twins differ from those their bits give"
    );
    update.twins.check(&update.old, &update.new).expect("twins");
    let paired = update.twins.old.iter().flatten().count();
    // At least each path's re-traced segment, and here more (tails that bounce where they did).
    assert!(
        paired > update.primaries.len() && update.primaries.len() > 100,
        "{paired} twins for {} re-traced paths",
        update.primaries.len()
    );
}

/// Twins that are not those of the Old and New Rays are refused with an error, not a panic: wrong lengths, an
/// index past the rays, a pair that does not name itself back, a pair whose bits differ.
#[test]
fn net_crossings_refuse_twins_of_other_rays() {
    let ray = |x: f32, length: f32| {
        let origin = Vec3::new(x, 0.5, 0.0);
        let direction = Vec3::NEG_Y;
        RaySegment::new(
            origin,
            direction,
            Some(SegmentHit {
                triangle: 0,
                mesh: 0,
                mobile: false,
                position: origin + length * direction,
                normal: Vec3::Y,
                distance: length,
            }),
            Rgb::ONE,
        )
    };
    let old = [ray(0.0, 0.5), ray(1.0, 0.5)];
    let new = [ray(0.0, 0.2), ray(1.0, 0.7)];
    let discs = vec![Disc {
        centre: Vec3::ZERO,
        normal: Vec3::Y,
        radius: 0.1,
        mesh: Some(0),
    }];
    let set = DiscSet::new(discs, DiscSetOptions::default()).expect("discs");
    let good = Twins::by_bits(&old, &new);
    assert_eq!(good.old, vec![Some(0), Some(1)]);
    let (a, b) = set.net_crossings(&old, &new, &good).expect("good twins");
    // The disc at the origin: the Old Ray reaching it has a twin ending short of it.
    assert_eq!((&a[0], &b[0]), (&[0u32][..], &[][..]));
    let bad = [
        Twins {
            old: vec![Some(0)],
            new: good.new.clone(),
        },
        Twins {
            old: vec![Some(0), Some(7)],
            new: vec![Some(0), Some(1)],
        },
        Twins {
            old: vec![Some(0), None],
            new: vec![Some(0), Some(1)],
        },
        Twins {
            old: vec![Some(1), Some(0)],
            new: vec![Some(1), Some(0)],
        },
    ];
    for twins in &bad {
        assert!(
            matches!(
                set.net_crossings(&old, &new, twins),
                Err(DensityError::InvalidOption {
                    option: "twins",
                    ..
                })
            ),
            "{twins:?} accepted"
        );
        let mut out = vec![DVec3::ZERO];
        assert!(set.accumulate_net(&old, &new, twins, &mut out).is_err());
        assert_eq!(out, vec![DVec3::ZERO], "a refused update changed the sums");
    }
}
