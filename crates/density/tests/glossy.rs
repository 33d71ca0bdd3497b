//! Glossy surfaces (section 2.10) and the QuadTree (section 2.10.1): the per-vertex list against a brute-force sum of equation 2.1, the QuadTree without summarising against the list, insertion and removal against rebuilding, the summary formula against hand-computed cases, and the degradation of summaries over frames.

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Affine3A, DVec3, Vec3};
use lustre_brdf::models::Phong;
use lustre_brdf::{BoxedBrdf, Brdf, from_model};
use lustre_density::glossy::{
    GlossyMode, GlossyVertex, GlossyVertices, IncidentRay, RayList, UpdateStats, glossy_meshes,
    ray_difference,
};
use lustre_density::quadtree::{
    QuadTree, QuadTreeOptions, Summary, SummaryTree, hemisphere_to_square, square_to_hemisphere,
    summary_degradation,
};
use lustre_density::{
    DensityError, Disc, PrimaryRay, RaySegment, RaySet, RaySetOptions, Twins, diffuse_radiance,
    trace_ray_set, twin_segments,
};
use lustre_geometry::sampling::{Frame, Pcg32, sample_uniform_hemisphere};
use lustre_geometry::{Bvh, MaterialModel, Rgb, Scene, builtin};
use lustre_photon::trace::scene_brdfs;

/// Slack of the disc test (10⁻⁴ of the glosbox's 2 m, as `detp`).
const SLACK: f32 = 2e-4;
/// Radius of the test disc.
const RADIUS: f32 = 0.25;
/// The built-in Cornell boxes' white reflectance (`lustre_geometry::builtin`).
const WHITE: Rgb = Rgb::new(0.885809, 0.698859, 0.666422);

/// A disc on the glossy floor of the glosbox, clear of both boxes.
fn floor_disc() -> Disc {
    Disc {
        centre: Vec3::new(-0.45, -1.0, 0.55),
        normal: Vec3::Y,
        radius: RADIUS,
        mesh: Some(0),
    }
}

/// The glosbox, its BRDFs and one ray set, traced once.
fn shared() -> &'static (Scene, Vec<BoxedBrdf>, RaySet) {
    static SHARED: OnceLock<(Scene, Vec<BoxedBrdf>, RaySet)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let scene = builtin("glosbox").unwrap();
        let bvh = Bvh::build(&scene);
        let rays = trace_ray_set(
            &scene,
            &bvh,
            &RaySetOptions {
                photons: 100_000,
                seed: 3,
                max_segments: 16,
                extension: 0.0,
            },
        )
        .unwrap();
        let brdfs = scene_brdfs(&scene).unwrap();
        (scene, brdfs, rays)
    })
}

/// The glossy floor's BRDF (0.7 Lambert + 0.3 Beckmann α = 0.05).
fn floor_brdf() -> &'static dyn Brdf {
    let (scene, brdfs, _) = shared();
    brdfs[scene.meshes()[0].material as usize].as_ref()
}

/// World view directions from the disc: towards the camera, above, and three oblique ones.
fn views() -> Vec<Vec3> {
    vec![
        Vec3::new(0.45, 1.0, 3.35).normalize(),
        Vec3::Y,
        Vec3::new(0.5, 1.0, 0.0).normalize(),
        Vec3::new(-0.3, 0.4, -1.0).normalize(),
        Vec3::new(1.0, 0.15, 0.2).normalize(),
    ]
}

/// Channel-wise `|a − b| ≤ rel · |b| + abs`.
fn close(a: Rgb, b: Rgb, rel: f32, abs: f32) -> bool {
    (a - b).abs().cmple(b.abs() * rel + Vec3::splat(abs)).all()
}

#[test]
fn hemisphere_map_is_equal_area_and_invertible() {
    let mut rng = Pcg32::new(1, 0);
    for _ in 0..10_000 {
        let u = rng.next_vec2();
        let w = square_to_hemisphere(u);
        assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0, "{w}");
        let back = hemisphere_to_square(w);
        assert!((back - u).abs().max_element() < 2e-4, "{u} → {w} → {back}");
    }
    // Uniform directions on the hemisphere fall evenly in the 16 cells of depth 2: each covers 2π/16 sr.
    let n = 160_000;
    let mut counts = [0u32; 16];
    for _ in 0..n {
        let u = hemisphere_to_square(sample_uniform_hemisphere(rng.next_vec2()));
        let (x, y) = ((u.x * 4.0).min(3.0) as usize, (u.y * 4.0).min(3.0) as usize);
        counts[x + 4 * y] += 1;
    }
    let expected = n as f64 / 16.0;
    let sigma = (expected * (1.0 - 1.0 / 16.0)).sqrt();
    for c in counts {
        assert!(
            (c as f64 - expected).abs() < 5.0 * sigma,
            "{counts:?} (5σ = {})",
            5.0 * sigma
        );
    }
}

#[test]
fn list_matches_brute_force_and_the_diffuse_limit() {
    let (_, _, rays) = shared();
    let disc = floor_disc();
    let vertex = GlossyVertex::build(disc, SLACK, GlossyMode::List, rays.segments()).unwrap();
    assert!(vertex.len() > 1000, "{} rays", vertex.len());
    let frame = Frame::from_normal(disc.normal);
    let brdf = floor_brdf();
    for wo in views() {
        // Equation 2.1 on the disc, straight from the segments, in f64.
        let brute: DVec3 = rays
            .segments()
            .filter(|s| disc.is_crossed_by(s, SLACK))
            .map(|s| {
                (brdf.eval(frame.to_local(-s.direction), frame.to_local(wo)) * s.power).as_dvec3()
            })
            .sum::<DVec3>()
            / (std::f64::consts::PI * (RADIUS as f64).powi(2));
        let got = vertex.radiance(brdf, wo);
        assert!(
            close(got, brute.as_vec3(), 1e-5, 0.0),
            "{got} against {brute}"
        );
    }
    // A Lambertian BRDF gives L = ρ/π E (equation 2.2) with E the DETP irradiance.
    let rho = Rgb::new(0.8, 0.5, 0.2);
    let lambert = from_model(&MaterialModel::Diffuse { reflectance: rho }).unwrap();
    let e: DVec3 = rays
        .segments()
        .filter(|s| disc.is_crossed_by(s, SLACK))
        .map(|s| s.power.as_dvec3())
        .sum::<DVec3>()
        / (std::f64::consts::PI * (RADIUS as f64).powi(2));
    assert!(close(vertex.irradiance(), e.as_vec3(), 1e-5, 0.0));
    for wo in views() {
        let l = vertex.radiance(lambert.as_ref(), wo);
        assert!(
            close(l, diffuse_radiance(rho, e.as_vec3()), 1e-5, 0.0),
            "{l}"
        );
    }
    // Below the tangent plane the radiance is zero.
    assert_eq!(vertex.radiance(brdf, -Vec3::Y), Rgb::ZERO);
}

/// The incident rays of the test disc.
fn disc_rays() -> Vec<IncidentRay> {
    let (_, _, rays) = shared();
    let disc = floor_disc();
    let frame = Frame::from_normal(disc.normal);
    rays.segments()
        .filter(|s| disc.is_crossed_by(s, SLACK))
        .map(|s| IncidentRay::from_segment(&frame, s))
        .collect()
}

#[test]
fn quadtree_without_summarising_matches_the_list() {
    let rays = disc_rays();
    let list = RayList::from_rays(&rays);
    let phong = Phong::new(Rgb::splat(0.2), Rgb::splat(0.6), 80.0).unwrap();
    let frame = Frame::from_normal(Vec3::Y);
    let mut worst_excess: f32 = 0.0;
    for (name, brdf) in [
        ("glossy floor", floor_brdf()),
        ("phong n = 80", &phong as &dyn Brdf),
    ] {
        for capacity in [1, 8, 32] {
            let tree = QuadTree::from_rays(
                QuadTreeOptions {
                    capacity,
                    max_depth: 12,
                },
                &rays,
            )
            .unwrap();
            tree.validate().unwrap();
            assert_eq!(tree.len(), list.len());
            for wo in views().iter().map(|&w| frame.to_local(w)) {
                let exact = list.estimate(brdf, wo);
                // Tolerance zero: per ray, the list's sum up to the order of the f64 summation.
                let zero = tree.estimate(brdf, wo, 0.0);
                assert!(
                    close(zero.value, exact.value, 1e-6, 0.0),
                    "{zero:?} {exact:?}"
                );
                assert_eq!(zero.bound, Rgb::ZERO);
                assert_eq!(zero.evaluations, list.len());
                for tolerance in [0.01f32, 0.05, 0.2] {
                    let e = tree.estimate(brdf, wo, tolerance);
                    let error = (e.value - exact.value).abs();
                    worst_excess =
                        worst_excess.max(((error - e.bound) / exact.value).max_element());
                    assert!(
                        error.cmple(e.bound + exact.value * 1e-4).all(),
                        "{name}, capacity {capacity}, τ {tolerance}: error {error} > bound {}",
                        e.bound
                    );
                    assert!(
                        e.bound.cmple(exact.value * tolerance * 1.0001).all(),
                        "{name}: bound {} above τ × {}",
                        e.bound,
                        exact.value
                    );
                    if wo == frame.to_local(views()[1]) || wo == frame.to_local(views()[0]) {
                        eprintln!(
                            "{name}, wo {wo:.2}, capacity {capacity}, τ = {tolerance}: {} BRDF evaluations against {} (relative error {:.2e}, bound {:.2e})",
                            e.evaluations,
                            exact.evaluations,
                            (error / exact.value).max_element(),
                            (e.bound / exact.value).max_element()
                        );
                    }
                }
            }
        }
    }
    eprintln!("largest (error − bound) / value: {worst_excess:.2e}");
}

/// The direct build (rays partitioned level by level, each leaf sorted) gives the tree that inserting the rays one by one gives, at the default shape and at the depth limit, duplicates included.
#[test]
fn a_built_tree_equals_one_grown_by_insertion() {
    let mut rays = disc_rays();
    rays.extend_from_within(..rays.len() / 3);
    for options in [
        QuadTreeOptions::default(),
        QuadTreeOptions {
            capacity: 1,
            max_depth: 3,
        },
    ] {
        let mut grown = QuadTree::new(options).unwrap();
        for &ray in &rays {
            grown.insert(ray);
        }
        let built = QuadTree::from_rays(options, &rays).unwrap();
        built.validate().unwrap();
        assert_eq!(built, grown, "{options:?}");
    }
}

#[test]
fn insertions_and_removals_equal_a_rebuild() {
    let rays = disc_rays();
    let options = QuadTreeOptions {
        capacity: 3,
        max_depth: 4,
    };
    let mut rng = Pcg32::new(9, 1);
    let mut current: Vec<IncidentRay> = rays[..rays.len() / 2].to_vec();
    let mut tree = QuadTree::from_rays(options, &current).unwrap();
    let mut list = RayList::from_rays(&current);
    let brdf = floor_brdf();
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    for step in 0..3000 {
        let r = rng.next_f32();
        if r < 0.45 || current.is_empty() {
            // Insert a ray (sometimes one already present: the lists are multisets).
            let ray = if r < 0.05 && !current.is_empty() {
                current[(rng.next_u32() as usize) % current.len()]
            } else {
                rays[(rng.next_u32() as usize) % rays.len()]
            };
            tree.insert(ray);
            list.insert(ray);
            current.push(ray);
        } else if r < 0.95 {
            let i = (rng.next_u32() as usize) % current.len();
            let ray = current.swap_remove(i);
            assert!(tree.remove(&ray) && list.remove(&ray));
        } else {
            // Removing a ray that is not there changes nothing.
            let absent = IncidentRay {
                wi: Vec3::Z,
                power: Rgb::splat(-1.0),
            };
            assert!(!tree.remove(&absent) && !list.remove(&absent));
        }
        if step % 100 == 0 {
            tree.validate().unwrap();
        }
    }
    tree.validate().unwrap();
    let rebuilt = QuadTree::from_rays(options, &current).unwrap();
    assert_eq!(
        tree, rebuilt,
        "the shape and sums depend on the multiset alone"
    );
    assert_eq!(list, RayList::from_rays(&current));
    assert_eq!(tree.len(), current.len());
    for tolerance in [0.0, 0.05] {
        assert_eq!(
            tree.estimate(brdf, wo, tolerance),
            rebuilt.estimate(brdf, wo, tolerance)
        );
    }
    assert!(tree.depth() <= 4);
    // Emptying the tree leaves the empty tree.
    for ray in &current {
        assert!(tree.remove(ray));
    }
    assert_eq!(tree, QuadTree::new(options).unwrap());
    assert_eq!(tree.estimate(brdf, wo, 0.0).value, Rgb::ZERO);
}

#[test]
fn batched_updates_equal_one_ray_at_a_time() {
    let rays = disc_rays();
    for options in [
        QuadTreeOptions::default(),
        QuadTreeOptions {
            capacity: 2,
            max_depth: 5,
        },
    ] {
        let mut rng = Pcg32::new(17, 3);
        let mut current: Vec<IncidentRay> = rays[..rays.len() / 2].to_vec();
        let mut batched = QuadTree::from_rays(options, &current).unwrap();
        let mut single = batched.clone();
        for frame in 0..40 {
            // Frames from a few rays to most of the tree, so that leaves empty, refill, merge and split.
            let size = 1 + (rng.next_u32() as usize) % if frame % 4 == 0 { 800 } else { 40 };
            let mut old = Vec::new();
            for _ in 0..size.min(current.len()) {
                let i = (rng.next_u32() as usize) % current.len();
                old.push(current.swap_remove(i));
            }
            // Some Old Rays that are not there, and a removed ray inserted again.
            let absent = IncidentRay {
                wi: Vec3::Z,
                power: Rgb::splat(-1.0),
            };
            if frame % 3 == 0 {
                old.push(absent);
            }
            let mut new: Vec<IncidentRay> = (0..size)
                .map(|_| rays[(rng.next_u32() as usize) % rays.len()])
                .collect();
            if let Some(&first) = old.first() {
                new.push(first);
            }
            let mut missing = 0;
            for ray in &old {
                missing += usize::from(!single.remove(ray));
            }
            for &ray in &new {
                single.insert(ray);
            }
            assert_eq!(batched.update(&old, &new), missing, "frame {frame}");
            assert_eq!(missing, usize::from(frame % 3 == 0));
            current.extend(new);
            batched.validate().unwrap();
            assert_eq!(batched, single, "{options:?}, frame {frame}");
        }
        assert_eq!(batched, QuadTree::from_rays(options, &current).unwrap());
        // One batch that empties the tree.
        let all = batched.rays();
        assert_eq!(batched.update(&all, &[]), 0);
        assert_eq!(batched, QuadTree::new(options).unwrap());
    }
}

#[test]
fn vertex_updates_equal_a_rebuild() {
    let (_, _, rays) = shared();
    let (scene, _, _) = shared();
    let bvh = Bvh::build(scene);
    let other = trace_ray_set(
        scene,
        &bvh,
        &RaySetOptions {
            photons: 10_000,
            seed: 99,
            max_segments: 16,
            extension: 0.0,
        },
    )
    .unwrap();
    let all: Vec<RaySegment> = rays.segments().copied().collect();
    let new: Vec<RaySegment> = other.segments().copied().collect();
    // Old Rays: every third segment of the first set.
    let old: Vec<RaySegment> = all.iter().step_by(3).copied().collect();
    let kept: Vec<RaySegment> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 3 != 0)
        .map(|(_, s)| *s)
        .collect();
    let after: Vec<RaySegment> = kept.iter().chain(&new).copied().collect();
    let brdf = floor_brdf();
    for mode in [
        GlossyMode::List,
        GlossyMode::QuadTree {
            options: QuadTreeOptions::default(),
            tolerance: 0.0,
        },
        GlossyMode::QuadTree {
            options: QuadTreeOptions::default(),
            tolerance: 0.05,
        },
    ] {
        let mut vertex = GlossyVertex::build(floor_disc(), SLACK, mode, &all).unwrap();
        let before = vertex.len();
        let stats = vertex.update(&old, &new).unwrap();
        assert_eq!(stats.missing, 0);
        assert_eq!(vertex.len(), before - stats.removed + stats.inserted);
        assert!(stats.removed > 100 && stats.inserted > 100, "{stats:?}");
        let rebuilt = GlossyVertex::build(floor_disc(), SLACK, mode, &after).unwrap();
        assert_eq!(vertex, rebuilt, "{mode:?}");
        for wo in views() {
            assert_eq!(vertex.estimate(brdf, wo), rebuilt.estimate(brdf, wo));
        }
        // Removing the same Old Rays again finds none of them.
        let again = vertex.update(&old, &[]).unwrap();
        assert_eq!(again.missing, stats.removed);
    }
}

fn ray(w: [f32; 3], p: f32) -> IncidentRay {
    IncidentRay {
        wi: Vec3::from(w),
        power: Rgb::splat(p),
    }
}

#[test]
fn summary_formula_matches_hand_computed_cases() {
    let a = ray([0.0, 0.0, 1.0], 1.0);
    let b = ray([0.6, 0.0, 0.8], 2.0);
    let c = ray([0.0, 0.6, 0.8], 4.0);
    let s = Summary::of(&[a, b]);
    assert_eq!(s.count, 2);
    assert!((s.mean - DVec3::new(0.3, 0.0, 0.9)).length() < 1e-7);
    assert!((s.power - DVec3::splat(3.0)).length() < 1e-12);
    // (R + c/2 − a/2) · 2/(2 + 1 − 1) = (0.3, 0.3, 0.8): the mean of {b, c}.
    let t = s.updated(&[c], &[a]).unwrap();
    assert_eq!(t.count, 2);
    assert!(
        (t.mean - DVec3::new(0.3, 0.3, 0.8)).length() < 1e-7,
        "{t:?}"
    );
    assert!((t.power - DVec3::splat(6.0)).length() < 1e-12);
    // Three copies of a, then b and c: (R + (b + c)/3) · 3/5 = (0.12, 0.12, 0.92).
    let s = Summary::of(&[a, a, a]);
    let t = s.updated(&[b, c], &[]).unwrap();
    assert_eq!(t.count, 5);
    assert!(
        (t.mean - DVec3::new(0.12, 0.12, 0.92)).length() < 1e-7,
        "{t:?}"
    );
    assert!((t.power - DVec3::splat(9.0)).length() < 1e-12);
    // Only removals: {a, b, c} minus c is the mean of {a, b}.
    let t = Summary::of(&[a, b, c]).updated(&[], &[c]).unwrap();
    assert!((t.mean - DVec3::new(0.3, 0.0, 0.9)).length() < 1e-7);
    // Removing everything gives the empty summary; from empty, the mean of the new rays.
    let empty = Summary::of(&[a, b]).updated(&[], &[a, b]).unwrap();
    assert_eq!(empty, Summary::EMPTY);
    assert_eq!(empty.direction(), None);
    let t = empty.updated(&[b, c], &[]).unwrap();
    assert!((t.mean - DVec3::new(0.3, 0.3, 0.8)).length() < 1e-7);
    assert!((t.direction().unwrap() - Vec3::new(0.3, 0.3, 0.8).normalize()).length() < 1e-6);
    // More Old Rays than the summary holds is an error.
    assert!(matches!(
        Summary::of(&[a]).updated(&[], &[a, b]),
        Err(DensityError::InvalidOption { .. })
    ));
    // The formula is the exact mean: summarising the new multiset gives the same (up to rounding).
    let mut rng = Pcg32::new(5, 5);
    let mut random = || {
        ray(
            square_to_hemisphere(rng.next_vec2()).to_array(),
            rng.next_f32(),
        )
    };
    let first: Vec<IncidentRay> = (0..50).map(|_| random()).collect();
    let added: Vec<IncidentRay> = (0..20).map(|_| random()).collect();
    let s = Summary::of(&first).updated(&added, &first[..30]).unwrap();
    let direct = Summary::of(&[&first[30..], &added[..]].concat());
    assert_eq!(s.count, direct.count);
    assert!((s.mean - direct.mean).length() < 1e-12);
    assert!((s.power - direct.power).length() < 1e-9);
}

/// Frames of a drifting distribution: 30 % cosine background, 70 % a `cos^40` lobe about an axis moving from 15° to 65° off the normal; 10 % of the rays are replaced each frame.
fn drifting_frames(frames: usize) -> Vec<Vec<IncidentRay>> {
    let mut rng = Pcg32::new(21, 3);
    let draw = |t: f32, rng: &mut Pcg32| -> IncidentRay {
        let theta = (15.0 + 50.0 * t).to_radians();
        let axis = Vec3::new(theta.sin(), 0.0, theta.cos());
        let u = rng.next_vec2();
        let wi = if rng.next_f32() < 0.3 {
            lustre_geometry::sampling::sample_cosine_hemisphere(u)
        } else {
            let cos = u.x.powf(1.0 / 41.0);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let w = Frame::from_normal(axis)
                .to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
                .normalize();
            if w.z > 0.01 { w } else { axis }
        };
        IncidentRay {
            wi,
            power: Rgb::new(0.5 + rng.next_f32(), 0.5 + rng.next_f32(), 1.0),
        }
    };
    let n = 2000;
    let mut current: Vec<IncidentRay> = (0..n).map(|_| draw(0.0, &mut rng)).collect();
    let mut out = vec![current.clone()];
    for f in 1..frames {
        let t = f as f32 / (frames - 1) as f32;
        for _ in 0..n / 10 {
            let i = (rng.next_u32() as usize) % current.len();
            current.swap_remove(i);
        }
        for _ in 0..n / 10 {
            current.push(draw(t, &mut rng));
        }
        out.push(current.clone());
    }
    out
}

#[test]
fn summaries_degrade_under_drift_within_their_bound() {
    let frames = drifting_frames(41);
    let brdf = Phong::new(Rgb::splat(0.1), Rgb::splat(0.8), 200.0).unwrap();
    let mirror = |deg: f32| {
        let t = deg.to_radians();
        Vec3::new(-t.sin(), 0.0, t.cos())
    };
    let views = [mirror(15.0), mirror(65.0), Vec3::Z, mirror(-40.0)];
    let options = QuadTreeOptions {
        capacity: 8,
        max_depth: 10,
    };
    let mut tree = SummaryTree::from_rays(options, &frames[0]).unwrap();
    let mut worst_ratio: f64 = 0.0;
    let mut incremental = vec![vec![0.0f64; views.len()]; frames.len()];
    let mut rebuilt_err = vec![vec![0.0f64; views.len()]; frames.len()];
    let grey = |c: Rgb| (c.x as f64 + c.y as f64 + c.z as f64) / 3.0;
    for (t, rays) in frames.iter().enumerate() {
        if t > 0 {
            let (old, new) = ray_difference(&frames[t - 1], rays);
            assert_eq!((old.len(), new.len()), (200, 200));
            tree.update(&old, &new).unwrap();
        }
        tree.validate().unwrap();
        // The formula keeps each leaf's mean exact: Σ n R over the leaves is Σ R_i over the rays.
        let sum_means: DVec3 = tree
            .summaries()
            .iter()
            .map(|s| s.mean * s.count as f64)
            .sum();
        let sum_rays: DVec3 = rays.iter().map(|r| r.wi.as_dvec3()).sum();
        assert!((sum_means - sum_rays).length() < 1e-9 * rays.len() as f64);
        assert_eq!(tree.len(), rays.len() as u64);
        let exact = RayList::from_rays(rays);
        let rebuilt = SummaryTree::from_rays(options, rays).unwrap();
        for (k, &wo) in views.iter().enumerate() {
            let e = exact.estimate(&brdf, wo).value;
            let approx = tree.estimate(&brdf, wo).value;
            let bound = tree.error_bound(&brdf, wo, 9);
            let error = (approx - e).abs();
            // The characterisation: the error never exceeds Σ Φ (sup f − inf f) over the frozen cells.
            assert!(
                error.cmple(bound * 1.0001 + e * 1e-6).all(),
                "frame {t}, view {k}: error {error} above bound {bound}"
            );
            worst_ratio = worst_ratio.max((error / bound).max_element() as f64);
            incremental[t][k] = (grey(approx) - grey(e)).abs() / grey(e);
            rebuilt_err[t][k] = (grey(rebuilt.estimate(&brdf, wo).value) - grey(e)).abs() / grey(e);
        }
    }
    let last = frames.len() - 1;
    for k in 0..views.len() {
        eprintln!(
            "view {k}: frame 0 {:.2}%, frame {last} incremental {:.2}% against rebuilt {:.2}%",
            100.0 * incremental[0][k],
            100.0 * incremental[last][k],
            100.0 * rebuilt_err[last][k]
        );
    }
    eprintln!("largest error / bound: {worst_ratio:.3}");
    // The degradation is real: towards the mirror of the final lobe the summaries of cells that were sparse at frame 0 are much worse than both the first frame and a rebuild.
    assert!(incremental[last][1] > 5.0 * incremental[0][1]);
    assert!(incremental[last][1] > 5.0 * rebuilt_err[last][1]);
    assert!(incremental[last][1] > 0.05);
    // summary_degradation reports the same errors.
    let table = summary_degradation(&brdf, &frames, &views, options).unwrap();
    assert_eq!(table.rows.len(), frames.len());
    for (t, row) in table.rows.iter().enumerate() {
        for k in 0..views.len() {
            assert!(
                (row.incremental[k] - incremental[t][k]).abs() < 1e-4,
                "frame {t} view {k}: {} {}",
                row.incremental[k],
                incremental[t][k]
            );
            assert!((row.rebuilt[k] - rebuilt_err[t][k]).abs() < 1e-4);
        }
    }
    let shown: Vec<_> = table
        .rows
        .iter()
        .filter(|r| r.frame % 10 == 0)
        .cloned()
        .collect();
    eprintln!(
        "{}",
        lustre_density::quadtree::DegradationTable {
            rows: shown,
            ..table
        }
    );
}

/// The glosbox with its small box moved by `offset`, traced with the same photons.
fn glosbox_frame(offset: Vec3, photons: u64) -> Vec<IncidentRay> {
    let mut scene = builtin("glosbox").unwrap();
    let id = scene.object_by_name("small-box").unwrap();
    scene
        .set_object_transform(id, Affine3A::from_translation(offset))
        .unwrap();
    let bvh = Bvh::build(&scene);
    let rays = trace_ray_set(
        &scene,
        &bvh,
        &RaySetOptions {
            photons,
            seed: 17,
            max_segments: 16,
            extension: 0.0,
        },
    )
    .unwrap();
    let disc = floor_disc();
    let frame = Frame::from_normal(disc.normal);
    rays.segments()
        .filter(|s| disc.is_crossed_by(s, SLACK))
        .map(|s| IncidentRay::from_segment(&frame, s))
        .collect()
}

#[test]
fn glosbox_degradation_tables() {
    // The small box rises and slides over the disc in 12 frames, shadowing it; the Old and New Rays are the multiset differences of the disc's rays (equations 2.5, 2.6).
    let photons = 60_000;
    let frames: Vec<Vec<IncidentRay>> = (0..12)
        .map(|k| glosbox_frame(Vec3::new(-0.07, 0.05, 0.0) * k as f32, photons))
        .collect();
    let frame = Frame::from_normal(Vec3::Y);
    // Directions (world, from the disc): the camera, the mirror of the light, the mirror of the small box, the mirror of the back wall.
    let views: Vec<Vec3> = [
        Vec3::new(0.45, 1.0, 3.35),
        Vec3::new(-0.45, 1.99, 0.54),
        Vec3::new(-0.785, 0.3, 0.17),
        Vec3::new(0.0, 0.5, 1.55),
    ]
    .iter()
    .map(|&w| frame.to_local(w.normalize()))
    .collect();
    let options = QuadTreeOptions {
        capacity: 8,
        max_depth: 10,
    };
    let arriving = summary_degradation(floor_brdf(), &frames, &views, options).unwrap();
    // The same frames backwards: the box leaves, light comes back into cells that were in shadow (sparse) at frame 0.
    let backwards: Vec<Vec<IncidentRay>> = frames.iter().rev().cloned().collect();
    let leaving = summary_degradation(floor_brdf(), &backwards, &views, options).unwrap();
    eprintln!(
        "glosbox floor disc r = {RADIUS} at (-0.45, -1, 0.55), {photons} photons per frame, capacity {}, views: camera, mirror of the light, of the small box, of the back wall.\n\nThe small box arrives over the disc (shadowing it):\n\n{arriving}\nThe small box leaves (the same frames backwards):\n\n{leaving}",
        options.capacity
    );
    for table in [&arriving, &leaving] {
        let changed: usize = table.rows.iter().map(|r| r.new + r.old).sum();
        assert!(changed > 500, "the box must change the disc's rays");
        // Frame 0: built from the same rays, both errors agree.
        assert_eq!(table.rows[0].incremental, table.rows[0].rebuilt);
        for row in &table.rows {
            for k in 0..views.len() {
                assert!(row.incremental[k].is_finite() && row.rebuilt[k].is_finite());
                assert!(row.incremental[k] <= row.bound[k] + 1e-6, "{row:?}");
            }
        }
    }
}

#[test]
fn glossy_vertices_of_a_scene() {
    let (scene, brdfs, rays) = shared();
    let meshes = glossy_meshes(scene);
    // The glossy floor and the gold box.
    assert_eq!(meshes, vec![0, 7]);
    let mode = GlossyMode::QuadTree {
        options: QuadTreeOptions::default(),
        tolerance: 0.02,
    };
    let mut vertices = GlossyVertices::build(scene, rays, 0.3, mode, &meshes).unwrap();
    assert_eq!(
        vertices.vertices(0).len(),
        scene.meshes()[0].positions.len()
    );
    assert!(vertices.vertices(1).is_empty());
    let eye = scene.camera().position;
    let l = vertices.radiance(brdfs, eye).unwrap();
    assert_eq!(l.len(), scene.meshes().len());
    assert!(l[1].is_empty());
    for (v, vertex) in vertices.vertices(0).iter().enumerate() {
        let vertex = vertex.as_ref().unwrap();
        assert_eq!(
            l[0][v],
            vertex.radiance(floor_brdf(), eye - vertex.disc().centre)
        );
    }
    // An update with nothing changes nothing; artifact-control areas rescale the radiance.
    let stats = vertices.update(&[], &[]).unwrap();
    assert_eq!(stats.inserted + stats.removed, 0);
    let areas: Vec<Vec<f32>> = scene
        .meshes()
        .iter()
        .map(|m| vec![0.25 * PI * 0.09; m.positions.len()])
        .collect();
    vertices.set_areas(&areas).unwrap();
    let quartered = vertices.radiance(brdfs, eye).unwrap();
    for (a, b) in quartered[0].iter().zip(&l[0]) {
        assert!(close(*a, *b * 4.0, 1e-5, 0.0), "{a} {b}");
    }
}

/// A bound on the rays the lists may hold: under it the same vertices as without one; below the exact total a typed error with the total; far below it the sampled estimate refuses before the crossings are gathered.
#[test]
fn glossy_vertices_refuse_more_rays_than_allowed() {
    let (scene, _, rays) = shared();
    let meshes = glossy_meshes(scene);
    let free = GlossyVertices::build(scene, rays, 0.3, GlossyMode::List, &meshes).unwrap();
    let total: u64 = meshes
        .iter()
        .flat_map(|&m| free.vertices(m))
        .flatten()
        .map(|v| v.len() as u64)
        .sum();
    assert!(total > 1000, "{total}");
    let bounded =
        GlossyVertices::build_limited(scene, rays, 0.3, GlossyMode::List, &meshes, Some(total))
            .unwrap();
    assert_eq!(bounded, free);
    let just_below =
        GlossyVertices::build_limited(scene, rays, 0.3, GlossyMode::List, &meshes, Some(total - 1));
    match just_below {
        Err(DensityError::TooManyRays { rays, limit }) => {
            assert_eq!(limit, total - 1);
            // Exact, or the sampled estimate when that is already above twice the limit.
            assert!(rays == total || rays > 2 * limit, "{rays} {total}");
        }
        other => panic!("expected TooManyRays, got {other:?}"),
    }
    let far_below = GlossyVertices::build_limited(
        scene,
        rays,
        0.3,
        GlossyMode::List,
        &meshes,
        Some(total / 10),
    );
    match far_below {
        Err(DensityError::TooManyRays { rays, .. }) => {
            // The estimate from one segment in 64: within a fifth of the total here.
            assert!(
                (rays as f64 / total as f64 - 1.0).abs() < 0.2,
                "{rays} {total}"
            );
        }
        other => panic!("expected TooManyRays, got {other:?}"),
    }
}

/// The segments of another trace of `scene` (5,000 photons, seed 9): a frame's New Rays.
fn other_trace(scene: &Scene) -> Vec<RaySegment> {
    let other = trace_ray_set(
        scene,
        &Bvh::build(scene),
        &RaySetOptions {
            photons: 5_000,
            seed: 9,
            max_segments: 16,
            extension: 0.0,
        },
    )
    .unwrap();
    other.segments().copied().collect()
}

/// One frame's Old and New Rays on `eager` (applied at once) and `lazy` (deferred behind `eye`): the rays `lazy` then holds deferred, the vertices behind the eye it applied because they reached the bound on deferred rays, and the changed vertices it did not list. Listed: every changed vertex the eye is not behind, and those that reached the bound.
fn frame(
    eager: &mut GlossyVertices,
    lazy: &mut GlossyVertices,
    eye: Vec3,
    old: &[RaySegment],
    new: &[RaySegment],
) -> (usize, usize, usize) {
    let (_, all) = eager.update_listing(old, new).unwrap();
    let (_, listed) = lazy
        .update_towards(old, new, &Twins::by_bits(old, new), Some(eye))
        .unwrap();
    let behind_eye = |&(m, v): &(u32, u32)| {
        lazy.vertices(m)[v as usize]
            .as_ref()
            .unwrap()
            .faces_away_from(eye)
    };
    assert!(all.iter().all(|id| behind_eye(id) || listed.contains(id)));
    assert!(listed.iter().all(|id| all.contains(id)));
    (
        lazy.deferred_rays(),
        listed.iter().filter(|id| behind_eye(id)).count(),
        all.len() - listed.len(),
    )
}

/// Three frames' Old and New Rays deferred on the vertices facing away from an eye (as their net change: the second frame removes what the first inserted; the third more than many vertices may defer, which they then apply), then applied when an eye on the other side asks, leave the same vertices, store for store, as applying each frame at once; the vertices the eye sees are updated and listed at once, the others are not listed.
#[test]
fn deferred_updates_equal_updates_applied_at_once() {
    let (scene, brdfs, rays) = shared();
    let meshes = glossy_meshes(scene);
    let mode = GlossyMode::QuadTree {
        options: QuadTreeOptions::default(),
        tolerance: 0.01,
    };
    let mut eager = GlossyVertices::build(scene, rays, 0.3, mode, &meshes).unwrap();
    let mut lazy = eager.clone();
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    let new = other_trace(scene);
    let eye = scene.camera().position;
    let centre = scene.bounds().center();
    let behind = centre + (centre - eye);
    // Frame 1 removes some held rays and adds the other trace's; frame 2 removes those again.
    let (first, _, held_back) = frame(&mut eager, &mut lazy, eye, &segments[..20_000], &new);
    assert!(first > 1000 && held_back > 0, "only {first} rays deferred");
    let (second, _, _) = frame(&mut eager, &mut lazy, eye, &new, &[]);
    // Frame 2's Old Rays cancel frame 1's deferred New Rays: the net change shrinks.
    assert!(second < first, "{first} then {second} rays deferred");
    // Towards either eye the radiance is the eager vertices' (deferred ones are applied on a copy).
    for at in [eye, behind] {
        assert_eq!(
            lazy.lobe_radiance(brdfs, at).unwrap(),
            eager.lobe_radiance(brdfs, at).unwrap()
        );
    }
    assert!(lazy != eager, "deferred rays are part of a vertex's state");
    // What the deferral and the back-face culling rest on: a vertex the eye is behind has zero radiance whatever its
    // rays, here estimated from its own rays (the floor's blend and the gold conductor).
    let mut culled = 0;
    for &m in &meshes {
        let brdf = brdfs[scene.meshes()[m as usize].material as usize].as_ref();
        for vertex in eager.vertices(m).iter().flatten() {
            if vertex.faces_away_from(eye) && !vertex.is_empty() {
                let wo = eye - vertex.disc().centre;
                assert_eq!(vertex.estimate(brdf, wo).value, Rgb::ZERO);
                culled += 1;
            }
        }
    }
    assert!(culled > 10, "only {culled} vertices face away from the eye");
    // Frame 3 removes a sixth of the held rays, more than many vertices may defer: those apply it.
    let (_, capped, _) = frame(
        &mut eager,
        &mut lazy,
        eye,
        &segments[20_000..segments.len() / 3],
        &[],
    );
    assert!(capped > 0, "no vertex reached the bound on deferred rays");
    let caught_up = lazy.catch_up(behind).unwrap();
    assert!(!caught_up.is_empty());
    for (m, v) in caught_up {
        let vertex = lazy.vertices(m)[v as usize].as_ref().unwrap();
        assert!(!vertex.faces_away_from(behind));
        assert_eq!(vertex.deferred_rays(), 0);
    }
    // What the eye behind does not see either (vertices seen edge-on from both) is applied vertex by vertex.
    for &m in &meshes {
        for vertex in lazy.vertices_mut(m).iter_mut().flatten() {
            vertex.catch_up().unwrap();
        }
    }
    assert_eq!(lazy.deferred_rays(), 0);
    assert!(
        lazy == eager,
        "the caught-up vertices differ from the eager ones"
    );
}

/// The scene's glossy vertices, whose crossing rays disc indexing finds, hold exactly the rays that testing every segment against each vertex's disc finds (section 2.10), before and after a frame's Old and New Rays; the lobe radiance is the full radiance less the diffuse part `ρ/π E` on the same disc (the floor's `ρ` is 0.7 · white; the gold box has none).
#[test]
fn glossy_vertices_hold_the_rays_of_a_brute_force_search() {
    let (scene, brdfs, rays) = shared();
    let meshes = glossy_meshes(scene);
    let radius = 0.3;
    let mut vertices =
        GlossyVertices::build(scene, rays, radius, GlossyMode::List, &meshes).unwrap();
    let eye = scene.camera().position;
    // A frame's update: some of the held rays leave, rays of another trace arrive.
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    let old = &segments[..20_000];
    let new = other_trace(scene);
    let stats = vertices.update(old, &new).unwrap();
    let mut expected_stats = UpdateStats::default();
    let full = vertices.radiance(brdfs, eye).unwrap();
    let lobe = vertices.lobe_radiance(brdfs, eye).unwrap();
    let mut held = 0;
    for &m in &meshes {
        let positions = scene.world_positions(m);
        let normals = scene.world_normals(m);
        let rho = scene.materials()[scene.meshes()[m as usize].material as usize]
            .model
            .diffuse_reflectance();
        for (v, vertex) in vertices.vertices(m).iter().enumerate() {
            let vertex = vertex.as_ref().unwrap();
            let disc = Disc {
                centre: positions[v],
                normal: normals[v].normalize(),
                radius,
                mesh: Some(m),
            };
            let mut brute =
                GlossyVertex::build(disc, SLACK, GlossyMode::List, rays.segments()).unwrap();
            expected_stats += brute.update(old, &new).unwrap();
            assert_eq!(vertex.rays(), brute.rays(), "mesh {m} vertex {v}");
            held += vertex.len();
            let diffuse = diffuse_radiance(rho, vertex.irradiance());
            let expected = (full[m as usize][v] - diffuse).max(Rgb::ZERO);
            assert!(
                close(lobe[m as usize][v], expected, 1e-5, 1e-7),
                "mesh {m} vertex {v}: {} against {expected}",
                lobe[m as usize][v]
            );
        }
    }
    assert!(held > 1000, "only {held} rays held");
    assert_eq!(stats, expected_stats);
    assert!(stats.removed > 100 && stats.inserted > 100, "{stats:?}");
    assert_eq!(stats.missing, 0);
    let floor_rho = scene.materials()[scene.meshes()[0].material as usize]
        .model
        .diffuse_reflectance();
    // The blend of 0.7 white Lambert and 0.3 Beckmann; the gold conductor has no diffuse part.
    assert!(close(floor_rho, 0.7 * WHITE, 1e-6, 0.0), "{floor_rho}");
    let gold = scene.materials()[scene.meshes()[7].material as usize]
        .model
        .diffuse_reflectance();
    assert_eq!(gold, Rgb::ZERO);
}

#[test]
fn invalid_options_are_errors() {
    let (scene, _, rays) = shared();
    let bad_options = [
        QuadTreeOptions {
            capacity: 0,
            max_depth: 4,
        },
        QuadTreeOptions {
            capacity: 4,
            max_depth: 99,
        },
    ];
    for options in bad_options {
        assert!(QuadTree::new(options).is_err());
        assert!(SummaryTree::from_rays(options, &[]).is_err());
        assert!(
            GlossyVertex::build(
                floor_disc(),
                SLACK,
                GlossyMode::Summarised(options),
                rays.segments()
            )
            .is_err()
        );
    }
    let tolerance = GlossyMode::QuadTree {
        options: QuadTreeOptions::default(),
        tolerance: f32::NAN,
    };
    assert!(GlossyVertex::build(floor_disc(), SLACK, tolerance, rays.segments()).is_err());
    for radius in [0.0, -1.0, f32::NAN] {
        let disc = Disc {
            radius,
            ..floor_disc()
        };
        assert!(GlossyVertex::build(disc, SLACK, GlossyMode::List, rays.segments()).is_err());
        assert!(GlossyVertices::build(scene, rays, radius, GlossyMode::List, &[0]).is_err());
    }
    let tilted = Disc {
        normal: Vec3::new(0.0, 2.0, 0.0),
        ..floor_disc()
    };
    assert!(GlossyVertex::build(tilted, SLACK, GlossyMode::List, rays.segments()).is_err());
    assert!(GlossyVertex::build(floor_disc(), -1.0, GlossyMode::List, rays.segments()).is_err());
    assert!(GlossyVertices::build(scene, rays, 0.2, GlossyMode::List, &[99]).is_err());
    let mut v =
        GlossyVertex::build(floor_disc(), SLACK, GlossyMode::List, rays.segments()).unwrap();
    assert!(v.set_area(0.0).is_err() && v.set_area(f32::INFINITY).is_err());
    // A summarised vertex cannot lose more rays than a summary holds, and stays unchanged.
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    let mut s = GlossyVertex::build(
        floor_disc(),
        SLACK,
        GlossyMode::Summarised(QuadTreeOptions::default()),
        &segments[..0],
    )
    .unwrap();
    let before = s.clone();
    assert!(s.update(&segments, &[]).is_err());
    assert_eq!(s, before);
    assert!(s.rays().is_none());
}

/// An Old Ray and a New Ray with the same direction and power (a re-traced path's first segment, ending elsewhere) cancel at every disc both cross: the updated stores equal, store for store, those built from scratch on the ray set after the frame, with far fewer insertions and removals than the rays crossing the discs, and a vertex only such pairs cross is not listed as changed.
#[test]
fn twin_old_and_new_rays_cancel_before_the_store() {
    let (scene, _, rays) = shared();
    let meshes = glossy_meshes(scene);
    let segments: Vec<RaySegment> = rays.segments().copied().collect();
    // Old: 6,000 held segments that end on a surface; New: each of the first 4,000 again, ending halfway
    // (its twin), and 1,000 segments of another trace.
    let old: Vec<RaySegment> = segments
        .iter()
        .filter(|s| s.hit.is_some())
        .take(6_000)
        .copied()
        .collect();
    let mut new: Vec<RaySegment> = old[..4_000]
        .iter()
        .map(|s| {
            let mut twin = *s;
            let hit = twin.hit.as_mut().unwrap();
            hit.distance *= 0.5;
            hit.position = s.origin + s.direction * hit.distance;
            twin
        })
        .collect();
    new.extend_from_slice(&other_trace(scene)[..1_000]);
    let (old_twin, new_twin) = twin_segments(&old, &new);
    assert!(
        old_twin[..4_000]
            .iter()
            .enumerate()
            .all(|(i, t)| *t == Some(i as u32))
    );
    assert!(
        new_twin[..4_000]
            .iter()
            .enumerate()
            .all(|(i, t)| *t == Some(i as u32))
    );
    assert!(old_twin[4_000..].iter().all(Option::is_none));
    // A key two New Rays share has no twin: the pairing stays one to one.
    let doubled = [new[0], new[0]];
    assert_eq!(
        twin_segments(&old[..1], &doubled),
        (vec![None], vec![None, None])
    );
    // The ray set after a frame: every segment less the Old Rays, with `added`.
    let after = |added: &[&[RaySegment]]| RaySet {
        rays: vec![PrimaryRay {
            light: 0,
            index: 0,
            segments: segments
                .iter()
                .filter(|s| s.hit.is_none())
                .chain(segments.iter().filter(|s| s.hit.is_some()).skip(6_000))
                .chain(added.iter().copied().flatten())
                .copied()
                .collect(),
        }],
        emitted_per_light: rays.emitted_per_light.clone(),
    };
    for mode in [
        GlossyMode::List,
        GlossyMode::QuadTree {
            options: QuadTreeOptions::default(),
            tolerance: 0.01,
        },
    ] {
        let built = GlossyVertices::build(scene, rays, 0.3, mode, &meshes).unwrap();
        // What every vertex's own test sees of a frame: its crossings, the twins (by index) crossing it
        // both, the vertices crossed and those crossed by such twins alone.
        let seen = |old: &[RaySegment], new: &[RaySegment]| {
            let (mut crossing, mut twins, mut touched, mut untouched) = (0, 0, 0, 0);
            for &m in &meshes {
                for v in built.vertices(m).iter().flatten() {
                    let n = old
                        .iter()
                        .chain(new)
                        .filter(|s| v.incident(s).is_some())
                        .count();
                    let both = (0..4_000)
                        .filter(|&i| v.incident(&old[i]).is_some() && v.incident(&new[i]).is_some())
                        .count();
                    crossing += n;
                    twins += both;
                    touched += usize::from(n > 0);
                    untouched += usize::from(n > 0 && n == 2 * both);
                }
            }
            (crossing, twins, touched, untouched)
        };
        let mut updated = built.clone();
        let (stats, listed) = updated.update_listing(&old, &new).unwrap();
        let rebuilt = GlossyVertices::build(scene, &after(&[&new]), 0.3, mode, &meshes).unwrap();
        assert!(
            updated == rebuilt,
            "{mode:?}: the updated stores differ from the rebuilt ones"
        );
        let (crossing, twins, touched, untouched) = seen(&old, &new);
        assert!(
            twins > 200,
            "{mode:?}: only {twins} twins cross a disc both"
        );
        assert_eq!(stats.missing, 0);
        assert_eq!(
            stats.removed + stats.inserted,
            crossing - 2 * twins,
            "{mode:?}"
        );
        assert_eq!(listed.len(), touched - untouched, "{mode:?}");
        // One pair whose ends both lie beyond every disc it crosses moves back: no vertex changes.
        let vertices = || meshes.iter().flat_map(|&m| built.vertices(m)).flatten();
        let i = (0..4_000)
            .find(|&i| {
                vertices().any(|v| v.incident(&old[i]).is_some())
                    && vertices()
                        .all(|v| v.incident(&old[i]).is_some() == v.incident(&new[i]).is_some())
            })
            .expect("a twin crossing the same discs");
        let (stats, listed) = updated.update_listing(&new[i..=i], &old[i..=i]).unwrap();
        assert_eq!(stats, UpdateStats::default(), "{mode:?}");
        assert!(listed.is_empty(), "{mode:?}: {listed:?}");
        let mut moved = new.clone();
        moved[i] = old[i];
        let rebuilt = GlossyVertices::build(scene, &after(&[&moved]), 0.3, mode, &meshes).unwrap();
        assert!(
            updated == rebuilt,
            "{mode:?}: the stores differ after the second frame"
        );
    }
}
