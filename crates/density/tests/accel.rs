//! The accelerations of `lustre_density::accel` (sections 1.2.1, 2.6–2.8 and the segment grid) against brute force: the same (disc, segment) crossing pairs and bit-identical sums, on random discs and segments (half-lines, degenerate radii, discs at the bounds, rims and grazing rays) and on a ray set of the subdivided Cornell box; incremental segment grids against rebuilt ones; every structure's invariants.

use std::sync::OnceLock;

use glam::{DVec3, Vec3};
use lustre_density::accel::{InvariantError, scene_discs, scene_slack};
use lustre_density::{
    Acceleration, DensityError, Disc, DiscSet, DiscSetOptions, PreTest, RaySegment, RaySetOptions,
    SegmentGrid, SegmentHit, Twins, segment_meets_box, trace_ray_set, twin_segments,
};
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Aabb, Bvh, Rgb, Scene, builtin};
use proptest::prelude::*;

/// Every acceleration under test, with a few parameter choices each.
fn accelerations() -> Vec<Acceleration> {
    vec![
        Acceleration::BruteForce,
        Acceleration::RayCache { sorted: true },
        Acceleration::RayCache { sorted: false },
        Acceleration::DiscIndex {
            max_per_leaf: 1,
            max_depth: 64,
        },
        Acceleration::DiscIndex {
            max_per_leaf: 4,
            max_depth: 6,
        },
        Acceleration::DiscIndex {
            max_per_leaf: 16,
            max_depth: 0,
        },
        Acceleration::tuned_disc_index(0.05, 0.1),
        Acceleration::SegmentGrid { cell_size: 0.1 },
        Acceleration::SegmentGrid { cell_size: 0.7 },
    ]
}

/// Brute force as `detp` does it: per disc, the ascending indices of the segments crossing it and `Σ φ` in that order from zero.
fn reference(discs: &[Disc], segments: &[RaySegment], slack: f32) -> (Vec<Vec<u32>>, Vec<DVec3>) {
    discs
        .iter()
        .map(|d| {
            let mut ids = Vec::new();
            let mut sum = DVec3::ZERO;
            for (j, s) in segments.iter().enumerate() {
                if d.is_crossed_by(s, slack) {
                    ids.push(j as u32);
                    sum += s.power.as_dvec3();
                }
            }
            (ids, sum)
        })
        .unzip()
}

/// Bits of a vector, so that `-0.0` and `0.0` differ.
fn bits(v: DVec3) -> [u64; 3] {
    v.to_array().map(f64::to_bits)
}

/// Starting values of `out`, so that accumulation is tested on non-zero entries.
fn initial(n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| DVec3::new(i as f64 * 0.37, 1.0 / (i as f64 + 1.0), -(i as f64)))
        .collect()
}

/// Checks one disc set against the reference: crossings equal, `accumulate` bit-identical (with `signs`), every invariant.
fn check_set(
    set: &DiscSet,
    segments: &[RaySegment],
    expected: &(Vec<Vec<u32>>, Vec<DVec3>),
    signs: &[f64],
) -> Result<(), String> {
    let label = format!("{:?}", set.options());
    set.validate().map_err(|e| format!("{label}: {e}"))?;
    let crossings = set.crossings(segments).map_err(|e| e.to_string())?;
    if crossings.len() != expected.0.len() {
        return Err(format!(
            "{label}: {} crossing lists for {} discs",
            crossings.len(),
            expected.0.len()
        ));
    }
    for (i, (got, want)) in crossings.iter().zip(&expected.0).enumerate() {
        if got != want {
            return Err(format!(
                "{label}: disc {i} ({:?}) crossed by {got:?}, brute force {want:?}",
                set.discs()[i]
            ));
        }
    }
    for &sign in signs {
        let mut out = initial(set.len());
        set.accumulate(segments, sign, &mut out)
            .map_err(|e| e.to_string())?;
        for (i, (o, s)) in out.iter().zip(&expected.1).enumerate() {
            let want = initial(set.len())[i] + sign * *s;
            if bits(*o) != bits(want) {
                return Err(format!("{label}: disc {i} sum {o} != {want}"));
            }
        }
    }
    Ok(())
}

/// Builds and checks a disc set for every acceleration × pre-test.
fn check_all(discs: &[Disc], segments: &[RaySegment], slack: f32) -> Result<(), String> {
    let expected = reference(discs, segments, slack);
    for acceleration in accelerations() {
        for pretest in PreTest::ALL {
            let set = DiscSet::new(
                discs.to_vec(),
                DiscSetOptions {
                    slack,
                    acceleration,
                    pretest,
                },
            )
            .map_err(|e| e.to_string())?;
            check_set(&set, segments, &expected, &[1.0, -1.0])?;
        }
    }
    Ok(())
}

/// SplitMix64: a small deterministic generator for the random scenes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform in [a, b).
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn chance(&mut self, p: f32) -> bool {
        self.f() < p
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v.normalize();
            }
        }
    }
    fn point(&mut self, half: f32) -> Vec3 {
        Vec3::new(
            self.range(-half, half),
            self.range(-half, half),
            self.range(-half, half),
        )
    }
}

/// Random discs in [-1, 1]³: some on the box's faces, some sharing a centre, some axis-aligned or with a zero normal; radii by `kind` (0 tiny, 1 small, 2 large, 3 mixed).
fn random_discs(rng: &mut Rng, n: usize, kind: u32) -> Vec<Disc> {
    let mut discs: Vec<Disc> = Vec::with_capacity(n);
    for _ in 0..n {
        let mut centre = rng.point(1.0);
        if rng.chance(0.2) {
            let axis = rng.below(3) as usize;
            centre[axis] = if rng.chance(0.5) { -1.0 } else { 1.0 };
        }
        if !discs.is_empty() && rng.chance(0.05) {
            centre = discs[rng.below(discs.len() as u64) as usize].centre;
        }
        let normal = if rng.chance(0.05) {
            Vec3::ZERO
        } else if rng.chance(0.2) {
            let axis = rng.below(3) as usize;
            let sign = if rng.chance(0.5) { -1.0 } else { 1.0 };
            Vec3::AXES[axis] * sign
        } else {
            rng.unit()
        };
        let tiny = [0.0, 1e-7, 1e-4][rng.below(3) as usize];
        let radius = match kind {
            0 => tiny,
            1 => rng.range(0.02, 0.08),
            2 => rng.range(0.2, 0.6),
            _ => [tiny, 0.05, 0.3, 1.0][rng.below(4) as usize],
        };
        discs.push(Disc {
            centre,
            normal,
            radius,
            mesh: if rng.chance(0.8) {
                Some(rng.below(3) as u32)
            } else {
                None
            },
        });
    }
    discs
}

/// A hit `distance` along a segment, on mesh `mesh`.
fn hit(origin: Vec3, direction: Vec3, distance: f32, mesh: u32) -> SegmentHit {
    SegmentHit {
        triangle: 0,
        mesh,
        mobile: false,
        position: origin + distance * direction,
        normal: -direction,
        distance,
    }
}

/// Random segments: many aimed at a disc (inside, on or just past its rim, sometimes grazing, ending on, just before or past its plane), random ones, ones from far outside, half-lines, and degenerate ones.
fn random_segments(
    rng: &mut Rng,
    discs: &[Disc],
    n: usize,
    scale: f32,
    shift: Vec3,
) -> Vec<RaySegment> {
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let power = Rgb::new(
            10f32.powf(rng.range(-3.0, 3.0)),
            10f32.powf(rng.range(-3.0, 3.0)),
            rng.range(0.0, 1.0),
        );
        let mesh = rng.below(3) as u32;
        let extension = [0.0, 0.0, 0.01, 0.2, -0.01][rng.below(5) as usize];
        let kind = rng.f();
        let mut segment = if kind < 0.45 && !discs.is_empty() {
            let d = discs[rng.below(discs.len() as u64) as usize];
            let n = d.normal.normalize_or(Vec3::Y);
            let (u, v) = n.any_orthonormal_pair();
            let angle = rng.range(0.0, std::f32::consts::TAU);
            let rim = [rng.f(), 1.0, 1.0 - 1e-7, 1.0 + 1e-7, 0.0][rng.below(5) as usize];
            let point = d.centre + d.radius * rim * (angle.cos() * u + angle.sin() * v);
            let mut dir = rng.unit();
            if rng.chance(0.15) {
                // Grazing: almost in the plane.
                dir = (dir - dir.dot(n) * n).normalize_or(u) - 1e-3 * rng.f() * n;
                dir = dir.normalize();
            }
            if dir.dot(n) > 0.0 {
                dir = -dir;
            }
            // From nearby, or from a thousand times farther (f32 rounding of the crossing point grows with |o|).
            let far = if rng.chance(0.2) { 1e3 } else { 1.0 };
            let t = rng.range(0.0, 2.0) * scale * far;
            let origin = point - t * dir;
            let h = match rng.below(6) {
                0 => None,
                1 => Some(t),
                2 => Some(t * (1.0 - 1e-6)),
                3 => Some(t * (1.0 + 1e-6)),
                4 => Some(rng.range(0.0, t)),
                _ => Some(t + rng.range(0.0, 2.0) * scale),
            };
            RaySegment::new(origin, dir, h.map(|h| hit(origin, dir, h, mesh)), power)
        } else if kind < 0.8 {
            let origin = rng.point(1.5) * scale + shift;
            let dir = rng.unit();
            let h = rng.chance(0.7).then(|| rng.range(0.0, 3.0) * scale);
            RaySegment::new(origin, dir, h.map(|h| hit(origin, dir, h, mesh)), power)
        } else if kind < 0.9 {
            let origin = rng.unit() * 5.0 * scale + shift;
            let dir = (rng.point(1.0) * scale + shift - origin).normalize();
            let h = rng.chance(0.5).then(|| rng.range(3.0, 7.0) * scale);
            RaySegment::new(origin, dir, h.map(|h| hit(origin, dir, h, mesh)), power)
        } else {
            let origin = rng.point(1.0) * scale + shift;
            match rng.below(6) {
                0 => RaySegment::new(origin, Vec3::ZERO, None, power),
                1 => RaySegment::new(Vec3::NAN, rng.unit(), None, power),
                2 => RaySegment::new(origin, Vec3::new(f32::INFINITY, 0.0, 0.0), None, power),
                3 => RaySegment::new(
                    origin,
                    rng.unit(),
                    Some(hit(origin, Vec3::X, -0.5, mesh)),
                    power,
                ),
                4 => RaySegment::new(
                    origin,
                    rng.unit(),
                    Some(hit(origin, Vec3::X, f32::NAN, mesh)),
                    power,
                ),
                _ => RaySegment::new(
                    origin,
                    rng.unit(),
                    Some(hit(origin, Vec3::X, 0.0, mesh)),
                    power,
                ),
            }
        };
        segment.extension = extension * scale;
        out.push(segment);
    }
    out
}

/// Random discs (of radii `kind`, as [`random_discs`]) and segments for them ([`random_segments`]), scaled by `scale` and moved by `(1, -0.5, 0.25) · offset` away from the origin, where f32 rounding of the crossing test is coarse.
fn random_scene(
    seed: u64,
    n_discs: usize,
    n_segments: usize,
    kind: u32,
    scale: f32,
    offset: f32,
) -> (Vec<Disc>, Vec<RaySegment>) {
    let mut rng = Rng(seed);
    let shift = Vec3::new(offset, -0.5 * offset, 0.25 * offset);
    let discs: Vec<Disc> = random_discs(&mut rng, n_discs, kind)
        .into_iter()
        .map(|d| Disc {
            centre: d.centre * scale + shift,
            radius: d.radius * scale,
            ..d
        })
        .collect();
    let segments = random_segments(&mut rng, &discs, n_segments, scale, shift);
    (discs, segments)
}

/// [`DiscSet::net_crossings`] and [`DiscSet::accumulate_net`] with every acceleration × pre-test against
/// brute force on a random scene whose New Rays are twins of Old Rays (ending shorter, farther, on another
/// mesh or with another extension, NaN included) and random segments, with one Old Ray repeated (no twin by
/// its bits) and a twin of it paired by hand; the number of (disc, twin pair) crossings that cancelled.
fn check_net(
    seed: u64,
    n_discs: usize,
    n_segments: usize,
    kind: u32,
    slack: f32,
    scale: f32,
    offset: f32,
) -> Result<usize, String> {
    let (discs, mut old) = random_scene(seed, n_discs, n_segments, kind, scale, offset);
    let mut rng = Rng(seed ^ 0x9e37_79b9);
    let mut new: Vec<RaySegment> = Vec::new();
    for s in &old {
        if rng.chance(0.6) {
            let mut twin = *s;
            let length = s.hit.map_or(rng.range(0.0, 3.0) * scale, |h| h.distance);
            let distance = length * [0.3, 0.999_999, 1.000_001, 1.7][rng.below(4) as usize];
            twin.hit = (!rng.chance(0.1))
                .then(|| hit(s.origin, s.direction, distance, rng.below(3) as u32));
            twin.extension = [0.0, 0.01, 0.2, f32::NAN][rng.below(4) as usize] * scale;
            new.push(twin);
        }
    }
    new.extend(random_segments(
        &mut rng,
        &discs,
        n_segments / 4,
        scale,
        Vec3::ZERO,
    ));
    old.push(old[0]);
    // A twin of the repeated Old Ray, which its bits cannot pair (two Old Rays share them): paired with the
    // repeat by hand, as an update pairs each re-traced path's segments.
    let mut again = old[0];
    again.hit = Some(hit(again.origin, again.direction, 0.5 * scale, 1));
    new.push(again);
    let (old_twin, new_twin) = twin_segments(&old, &new);
    if old_twin[0].is_some()
        || old_twin[old.len() - 1].is_some()
        || new_twin[new.len() - 1].is_some()
    {
        return Err("a repeated Old Ray has a twin".into());
    }
    let mut twins = Twins {
        old: old_twin,
        new: new_twin,
    };
    twins.old[old.len() - 1] = Some(new.len() as u32 - 1);
    twins.new[new.len() - 1] = Some(old.len() as u32 - 1);
    let (old_twin, new_twin) = (&twins.old, &twins.new);
    // Brute force: each disc's crossings less the twins crossing it both.
    let net = |a: &[RaySegment], b: &[RaySegment], twins: &[Option<u32>]| -> Vec<Vec<u32>> {
        discs
            .iter()
            .map(|d| {
                (0..a.len() as u32)
                    .filter(|&j| d.is_crossed_by(&a[j as usize], slack))
                    .filter(|&j| {
                        twins[j as usize].is_none_or(|k| !d.is_crossed_by(&b[k as usize], slack))
                    })
                    .collect()
            })
            .collect()
    };
    let (want_old, want_new) = (net(&old, &new, old_twin), net(&new, &old, new_twin));
    let cancelled = discs
        .iter()
        .map(|d| {
            (0..old.len())
                .filter(|&j| {
                    old_twin[j].is_some_and(|k| {
                        d.is_crossed_by(&old[j], slack) && d.is_crossed_by(&new[k as usize], slack)
                    })
                })
                .count()
        })
        .sum();
    let sum = |ids: &[u32], segments: &[RaySegment]| {
        ids.iter().fold(DVec3::ZERO, |acc, &j| {
            acc + segments[j as usize].power.as_dvec3()
        })
    };
    let lists = |c: &lustre_density::Crossings| c.iter().map(<[u32]>::to_vec).collect::<Vec<_>>();
    for acceleration in accelerations() {
        for pretest in PreTest::ALL {
            let label = format!("{acceleration:?} {pretest:?}");
            let options = DiscSetOptions {
                slack,
                acceleration,
                pretest,
            };
            let set = DiscSet::new(discs.clone(), options).map_err(|e| e.to_string())?;
            let (a, b) = set
                .net_crossings(&old, &new, &twins)
                .map_err(|e| e.to_string())?;
            if lists(&a) != want_old || lists(&b) != want_new {
                return Err(format!("{label}: net crossings differ from brute force"));
            }
            let mut out = initial(discs.len());
            set.accumulate_net(&old, &new, &twins, &mut out)
                .map_err(|e| e.to_string())?;
            for (i, o) in out.iter().enumerate() {
                let mut want = initial(discs.len())[i];
                want += -1.0 * sum(&want_old[i], &old);
                want += 1.0 * sum(&want_new[i], &new);
                if bits(*o) != bits(want) {
                    return Err(format!("{label}: disc {i} sum {o} != {want}"));
                }
            }
        }
    }
    Ok(cancelled)
}

/// One scene of [`check_net`] with many discs: twins cancel on many of them.
#[test]
fn net_crossings_cancel_twins_as_brute_force_does() {
    let cancelled = check_net(7, 40, 400, 2, 1e-4, 1.0, 0.0).unwrap();
    assert!(cancelled > 50, "only {cancelled} twin crossings cancelled");
}

/// The disc index's normal cones (a leaf whose discs all face one way is skipped by segments travelling along that way) against brute force where the back-face test is closest to its rounding: flat discs that share one normal, crossed by segments within a hair of their plane from either side, and discs on a sphere crossed by segments leaving it along each normal and arriving against it.
#[test]
fn normal_cones_keep_grazing_and_leaving_segments_exact() {
    let mut discs = Vec::new();
    for i in 0..12 {
        for k in 0..12 {
            discs.push(Disc {
                centre: Vec3::new(0.1 * i as f32, 0.0, 0.1 * k as f32),
                normal: Vec3::Y,
                radius: 0.08,
                mesh: Some(1),
            });
        }
    }
    let mut segments = Vec::new();
    for (n, tilt) in [1e-7f32, 1e-6, 1e-5, 1e-3, 1e-1].into_iter().enumerate() {
        for sign in [-1.0f32, 1.0] {
            let direction = Vec3::new(1.0, sign * tilt, 0.37).normalize();
            // Through the plane y = 0 near the middle of the grid, both ways along the direction.
            let through = Vec3::new(0.55, 0.0, 0.5 + 0.013 * n as f32);
            let origin = through - 0.6 * direction;
            segments.push(RaySegment::new(
                origin,
                direction,
                Some(hit(origin, direction, 1.2, 1)),
                Rgb::ONE,
            ));
            segments.push(RaySegment::new(origin, direction, None, Rgb::ONE));
        }
    }
    // Discs on a unit sphere (mesh 2): segments leaving each along its normal, or tilted off it, and arriving against it.
    let mut rng = Rng(7);
    for _ in 0..300 {
        let n = rng.unit();
        let centre = Vec3::new(3.0, 0.0, 0.0) + n;
        discs.push(Disc {
            centre,
            normal: n,
            radius: 0.3,
            mesh: Some(2),
        });
        let tilted = (n + 0.999 * rng.unit()).normalize_or_zero();
        for direction in [n, tilted, -n] {
            if direction == Vec3::ZERO {
                continue;
            }
            let origin = if direction.dot(n) < 0.0 {
                centre - 2.0 * direction
            } else {
                centre
            };
            segments.push(RaySegment::new(
                origin,
                direction,
                Some(hit(origin, direction, 2.0, 2)),
                Rgb::ONE,
            ));
        }
    }
    check_all(&discs, &segments, 1e-4).unwrap();
}

/// The case CI's random search found: a disc of radius `1e-7` seen from about two units away, where `is_crossed_by`'s rounded crossing point lies within the radius while the exact path passes outside the disc's box; the box test grows by the segment's share of the rounding and keeps it.
#[test]
fn a_tiny_disc_seen_from_far_keeps_its_crossing() {
    let disc = Disc {
        centre: Vec3::new(-0.000_485_363_74, 0.000_407_929_68, 0.000_737_381_4),
        normal: Vec3::new(-0.801_723_96, 0.576_348_8, 0.158_306_18),
        radius: 1e-7,
        mesh: Some(2),
    };
    let (origin, direction) = (
        Vec3::new(-1.074_967_5, 0.859_213_4, 1.361_177_4),
        Vec3::new(0.555_389_4, -0.443_908_27, -0.703_198_4),
    );
    let mut segment = RaySegment::new(
        origin,
        direction,
        Some(hit(origin, direction, 1.934_648_2, 2)),
        Rgb::ONE,
    );
    segment.extension = 2e-4;
    assert!(disc.is_crossed_by(&segment, 0.0));
    let (lo, hi) = disc.bounds(0.0);
    assert!(segment_meets_box(&segment, 0.0, lo, hi));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// A segment that crosses a disc meets the disc's box (the prefilter of the mobile discs' estimate), at any scale and far from the origin.
    #[test]
    fn a_crossing_segment_meets_the_disc_box(
        seed in any::<u64>(),
        kind in 0u32..4,
        slack in prop::sample::select(vec![0.0f32, 1e-4, 0.01]),
        scale in prop::sample::select(vec![1.0f32, 1e-3, 50.0]),
        offset in prop::sample::select(vec![0.0f32, 100.0, -3000.0]),
    ) {
        let (discs, segments) = random_scene(seed, 20, 400, kind, scale, offset);
        let mut crossings = 0;
        for d in &discs {
            let (lo, hi) = d.bounds(slack);
            for s in &segments {
                if d.is_crossed_by(s, slack) {
                    crossings += 1;
                    prop_assert!(segment_meets_box(s, slack, lo, hi), "{d:?} {s:?}");
                }
            }
        }
        // Half the segments are aimed at discs: the property is not vacuous.
        prop_assert!(discs.is_empty() || crossings > 0);
    }

    /// Every acceleration × pre-test finds the brute-force pairs and sums on random discs and segments.
    #[test]
    fn random_scenes_match_brute_force(
        seed in any::<u64>(),
        n_discs in 0usize..40,
        n_segments in 0usize..160,
        kind in 0u32..4,
        slack in prop::sample::select(vec![0.0f32, 1e-4, 0.01]),
        scale in prop::sample::select(vec![1.0f32, 1e-3, 50.0]),
        offset in prop::sample::select(vec![0.0f32, 100.0, -3000.0]),
    ) {
        let (discs, segments) = random_scene(seed, n_discs, n_segments, kind, scale, offset);
        let slack = slack * scale;
        prop_assert_eq!(check_all(&discs, &segments, slack), Ok(()));
        // The ray cache's hierarchy after every query.
        let set = DiscSet::new(discs.clone(), DiscSetOptions {
            slack,
            acceleration: Acceleration::RayCache { sorted: true },
            pretest: PreTest::None,
        }).unwrap();
        prop_assert!(set.validate_ray_cache(&segments).is_ok());
    }

    /// A frame's net crossings (twins, the Old and New Rays with the same origin, direction and power, left
    /// out of the discs they both cross) and sums, with every acceleration × pre-test, against brute force.
    #[test]
    fn net_crossings_match_brute_force(
        seed in any::<u64>(),
        n_discs in 0usize..40,
        n_segments in 1usize..120,
        kind in 0u32..4,
        slack in prop::sample::select(vec![0.0f32, 1e-4, 0.01]),
        scale in prop::sample::select(vec![1.0f32, 1e-3, 50.0]),
        offset in prop::sample::select(vec![0.0f32, 100.0, -3000.0]),
    ) {
        let checked = check_net(seed, n_discs, n_segments, kind, slack * scale, scale, offset);
        prop_assert_eq!(checked.map(|_| ()), Ok(()));
    }

    /// A segment grid over random bounds (often smaller than the discs' region) gives the brute-force pairs and sums, before and after removing and re-inserting segments.
    #[test]
    fn random_grids_match_brute_force(
        seed in any::<u64>(),
        n_discs in 0usize..30,
        n_segments in 0usize..120,
        half in 0.3f32..1.6,
        cell in 0.05f32..1.0,
        pretest in prop::sample::select(PreTest::ALL.to_vec()),
    ) {
        let mut rng = Rng(seed);
        let discs = random_discs(&mut rng, n_discs, 3);
        let segments = random_segments(&mut rng, &discs, n_segments, 1.0, Vec3::ZERO);
        let slack = 1e-4;
        let bounds = Aabb { min: Vec3::splat(-half), max: Vec3::splat(half * 0.9) };
        let mut grid = SegmentGrid::from_segments(bounds, cell, slack, &segments).unwrap();
        prop_assert_eq!(grid.validate(), Ok(()));
        let set = DiscSet::new(discs.clone(), DiscSetOptions {
            slack,
            acceleration: Acceleration::BruteForce,
            pretest,
        }).unwrap();
        let expected = reference(&discs, &segments, slack);
        let by_id: Vec<Vec<u32>> = set.crossings_grid(&grid).unwrap().iter().map(<[u32]>::to_vec).collect();
        prop_assert_eq!(&by_id, &expected.0);
        // Remove every third segment, then put it back: the same answer.
        for j in (0..segments.len()).step_by(3) {
            prop_assert!(grid.remove(j as u32));
        }
        prop_assert_eq!(grid.validate(), Ok(()));
        for j in (0..segments.len()).step_by(3) {
            grid.insert(j as u32, &segments[j]);
        }
        prop_assert_eq!(grid.validate(), Ok(()));
        let mut out = initial(discs.len());
        set.accumulate_grid(&grid, -1.0, &mut out).unwrap();
        for (i, o) in out.iter().enumerate() {
            prop_assert_eq!(bits(*o), bits(initial(discs.len())[i] - expected.1[i]));
        }
    }
}

/// The Cornell box with every mesh subdivided to edges of at most 0.1 (6 499 vertices), and its ray set (1 500 photons), with artifact-control extensions on some segments.
fn cornell() -> &'static (Scene, Vec<RaySegment>) {
    static SHARED: OnceLock<(Scene, Vec<RaySegment>)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let scene = builtin("cornell").unwrap();
        let meshes = scene
            .meshes()
            .iter()
            .map(|m| subdivide(m, 0.1).unwrap())
            .collect();
        let scene = scene.with_meshes(meshes).unwrap();
        let bvh = Bvh::build(&scene);
        let rays = trace_ray_set(
            &scene,
            &bvh,
            &RaySetOptions {
                photons: 1_500,
                seed: 11,
                max_segments: 8,
                extension: 0.0,
            },
        )
        .unwrap();
        let mut segments: Vec<RaySegment> = rays.segments().copied().collect();
        for s in segments.iter_mut().step_by(7) {
            s.extension = 0.05;
        }
        (scene, segments)
    })
}

/// Every acceleration × pre-test on the Cornell box's ray set, discs of radius 0.05 and 0.15 at every vertex: the same crossings, and bit-identical sums (checked once per acceleration, as every pre-test feeds the same summation).
#[test]
fn cornell_matches_brute_force() {
    let (scene, segments) = cornell();
    let slack = scene_slack(scene);
    assert!(
        segments.iter().any(|s| s.hit.is_none()),
        "half-lines present"
    );
    for radius in [0.05, 0.15] {
        let (discs, _) = scene_discs(scene, radius);
        assert!(discs.len() > 1000);
        let expected = reference(&discs, segments, slack);
        let pairs: usize = expected.0.iter().map(Vec::len).sum();
        assert!(pairs > 5_000, "{pairs} crossings");
        for acceleration in accelerations() {
            for pretest in PreTest::ALL {
                let set = DiscSet::new(
                    discs.clone(),
                    DiscSetOptions {
                        slack,
                        acceleration,
                        pretest,
                    },
                )
                .unwrap();
                let signs: &[f64] = if pretest == PreTest::Plucker {
                    &[-1.0]
                } else {
                    &[]
                };
                assert_eq!(check_set(&set, segments, &expected, signs), Ok(()));
            }
        }
    }
}

/// The same sums as the `detp` estimator, mesh by mesh, once divided by `π r²`.
#[test]
fn cornell_matches_detp() {
    let (scene, segments) = cornell();
    let radius = 0.1;
    let rays = lustre_density::RaySet {
        rays: vec![lustre_density::PrimaryRay {
            light: 0,
            index: 0,
            segments: segments
                .iter()
                .map(|s| RaySegment {
                    extension: 0.0,
                    ..*s
                })
                .collect(),
        }],
        emitted_per_light: vec![1],
    };
    let plain: Vec<RaySegment> = rays.segments().copied().collect();
    let e = lustre_density::detp(scene, &rays, radius).unwrap();
    let (discs, starts) = scene_discs(scene, radius);
    let set = DiscSet::new(
        discs,
        DiscSetOptions {
            slack: scene_slack(scene),
            acceleration: Acceleration::RayCache { sorted: true },
            pretest: PreTest::MollerTrumbore,
        },
    )
    .unwrap();
    let mut out = vec![DVec3::ZERO; set.len()];
    set.accumulate(&plain, 1.0, &mut out).unwrap();
    let area = std::f64::consts::PI * (radius as f64).powi(2);
    for (m, mesh) in e.iter().enumerate() {
        for (v, value) in mesh.iter().enumerate() {
            let ours = (out[starts[m] + v] / area).as_vec3();
            assert_eq!(ours, *value, "mesh {m} vertex {v}");
        }
    }
}

/// The ray cache's hierarchy stays valid after every query on the Cornell box, and sorting the queries builds fewer spheres (section 2.6).
#[test]
fn cornell_ray_cache_hierarchy() {
    let (scene, segments) = cornell();
    let (discs, starts) = scene_discs(scene, 0.05);
    // The floor and the two boxes: enough queries, quick to validate.
    let mut picked = Vec::new();
    for m in 0..starts.len() - 1 {
        if m % 3 == 0 {
            picked.extend_from_slice(&discs[starts[m]..starts[m + 1]]);
        }
    }
    let mut built = Vec::new();
    for sorted in [true, false] {
        let set = DiscSet::new(
            picked.clone(),
            DiscSetOptions {
                slack: scene_slack(scene),
                acceleration: Acceleration::RayCache { sorted },
                pretest: PreTest::None,
            },
        )
        .unwrap();
        let (spheres, queries) = set.validate_ray_cache(segments).unwrap();
        assert_eq!(queries as usize, picked.len());
        built.push(spheres);
    }
    assert!(
        built[0] <= built[1],
        "sorted {} vs unsorted {}",
        built[0],
        built[1]
    );
}

/// Incremental insertion, removal and replacement give the same grid answers as a grid built from the final segments, before and after compaction; the sums match brute force over the segments in id order, also for discs outside the grid.
#[test]
fn grid_incremental_matches_rebuild() {
    let (scene, segments) = cornell();
    let slack = scene_slack(scene);
    let (discs, _) = scene_discs(scene, 0.1);
    let b = scene.bounds();
    let n = segments.len();
    // Ids 0..n are the segments; the grid covers only part of the box for the second run, so many discs are outside it.
    for bounds in [
        Aabb {
            min: b.min - 0.01,
            max: b.max + 0.01,
        },
        Aabb {
            min: b.min + 0.4,
            max: b.max - 0.7,
        },
    ] {
        let mut grid = SegmentGrid::new(bounds, 0.25, slack).unwrap();
        let mut current: Vec<Option<RaySegment>> = vec![None; n + 100];
        for j in 0..n / 2 {
            grid.insert(j as u32, &segments[j]);
            current[j] = Some(segments[j]);
        }
        for j in (0..n / 2).step_by(3) {
            assert!(grid.remove(j as u32));
            current[j] = None;
        }
        assert!(!grid.remove((n + 50) as u32));
        for j in n / 2..n {
            grid.insert(j as u32, &segments[j]);
            current[j] = Some(segments[j]);
        }
        // Replace some ids by other segments (a changed ray keeps its slot).
        for j in (1..n / 2).step_by(5) {
            let other = segments[(j * 7919) % n];
            grid.insert(j as u32, &other);
            current[j] = Some(other);
        }
        grid.validate().unwrap();
        let live: Vec<(u32, RaySegment)> = current
            .iter()
            .enumerate()
            .filter_map(|(j, s)| s.map(|s| (j as u32, s)))
            .collect();
        assert_eq!(grid.segments(), live);
        let mut fresh = SegmentGrid::new(bounds, 0.25, slack).unwrap();
        for (id, s) in &live {
            fresh.insert(*id, s);
        }
        fresh.validate().unwrap();
        let candidates = |g: &SegmentGrid| -> Vec<Vec<u32>> {
            discs
                .iter()
                .step_by(5)
                .map(|d| {
                    let mut ids = Vec::new();
                    g.for_each_candidate(d, |id, _| ids.push(id));
                    ids
                })
                .collect()
        };
        let expected_candidates = candidates(&fresh);
        assert_eq!(candidates(&grid), expected_candidates);
        grid.compact();
        grid.validate().unwrap();
        assert_eq!(grid.registrations(), fresh.registrations());
        assert_eq!(candidates(&grid), expected_candidates);
        // Sums in id order against brute force over the live segments in id order.
        let ordered: Vec<RaySegment> = live.iter().map(|&(_, s)| s).collect();
        let expected = reference(&discs, &ordered, slack);
        for pretest in [PreTest::None, PreTest::Plucker] {
            let set = DiscSet::new(
                discs.clone(),
                DiscSetOptions {
                    slack,
                    acceleration: Acceleration::BruteForce,
                    pretest,
                },
            )
            .unwrap();
            let by_id = set.crossings_grid(&grid).unwrap();
            for (got, want) in by_id.iter().zip(&expected.0) {
                let want: Vec<u32> = want.iter().map(|&k| live[k as usize].0).collect();
                assert_eq!(got, &want);
            }
            let mut out = vec![DVec3::ZERO; discs.len()];
            set.accumulate_grid(&grid, 1.0, &mut out).unwrap();
            for (o, s) in out.iter().zip(&expected.1) {
                assert_eq!(bits(*o), bits(*s));
            }
        }
    }
}

/// Discs that move every frame (section 2.5.2): `update_discs` keeps the order and the tree, and every acceleration still matches brute force on the moved discs.
#[test]
fn moving_discs_match_brute_force() {
    let (scene, segments) = cornell();
    let slack = scene_slack(scene);
    let (discs, starts) = scene_discs(scene, 0.08);
    // The last mesh (a box) is the mobile object.
    let m = starts.len() - 2;
    let mobile: Vec<Disc> = discs[starts[m]..starts[m + 1]].to_vec();
    let centre = mobile.iter().map(|d| d.centre).sum::<Vec3>() / mobile.len() as f32;
    for acceleration in accelerations() {
        let mut set = DiscSet::new(
            mobile.clone(),
            DiscSetOptions {
                slack,
                acceleration,
                pretest: PreTest::Badouel,
            },
        )
        .unwrap();
        let order = set.order().to_vec();
        for frame in 1..4 {
            let rotation = glam::Quat::from_rotation_y(0.3 * frame as f32);
            let shift = Vec3::new(0.05 * frame as f32, 0.0, -0.04 * frame as f32);
            let moved: Vec<Disc> = mobile
                .iter()
                .map(|d| Disc {
                    centre: rotation * (d.centre - centre) + centre + shift,
                    normal: (rotation * d.normal).normalize_or_zero(),
                    ..*d
                })
                .collect();
            set.update_discs(&moved).unwrap();
            assert_eq!(set.order(), &order[..], "order reused");
            let expected = reference(&moved, segments, slack);
            assert_eq!(check_set(&set, segments, &expected, &[-1.0]), Ok(()));
        }
    }
}

/// Bad parameters are typed errors, never panics.
#[test]
fn invalid_options_are_errors() {
    let disc = Disc {
        centre: Vec3::ZERO,
        normal: Vec3::Y,
        radius: 0.1,
        mesh: None,
    };
    let options = DiscSetOptions::default();
    let bad = |discs: Vec<Disc>, options: DiscSetOptions| {
        matches!(
            DiscSet::new(discs, options),
            Err(DensityError::InvalidOption { .. })
        )
    };
    assert!(bad(
        vec![disc],
        DiscSetOptions {
            slack: -1.0,
            ..options
        }
    ));
    assert!(bad(
        vec![disc],
        DiscSetOptions {
            slack: f32::NAN,
            ..options
        }
    ));
    assert!(bad(
        vec![Disc {
            radius: f32::NAN,
            ..disc
        }],
        options
    ));
    assert!(bad(
        vec![Disc {
            radius: -0.1,
            ..disc
        }],
        options
    ));
    assert!(bad(
        vec![Disc {
            centre: Vec3::INFINITY,
            ..disc
        }],
        options
    ));
    assert!(bad(
        vec![Disc {
            normal: Vec3::splat(2.0),
            ..disc
        }],
        options
    ));
    for acceleration in [
        Acceleration::DiscIndex {
            max_per_leaf: 0,
            max_depth: 4,
        },
        Acceleration::DiscIndex {
            max_per_leaf: 4,
            max_depth: 1000,
        },
        Acceleration::SegmentGrid { cell_size: 0.0 },
        Acceleration::SegmentGrid {
            cell_size: f32::INFINITY,
        },
    ] {
        assert!(bad(
            vec![disc],
            DiscSetOptions {
                acceleration,
                ..options
            }
        ));
    }
    let mut set = DiscSet::new(vec![disc], options).unwrap();
    assert!(set.accumulate(&[], 1.0, &mut []).is_err());
    assert!(set.update_discs(&[disc, disc]).is_err());
    let unit = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    assert!(SegmentGrid::new(unit, 0.0, 0.0).is_err());
    assert!(SegmentGrid::new(unit, 1e-4, 0.0).is_err(), "too many cells");
    assert!(SegmentGrid::new(Aabb::EMPTY, 0.1, 0.0).is_err());
    assert!(SegmentGrid::new(unit, 0.1, -1.0).is_err());
    let grid = SegmentGrid::new(unit, 0.1, 0.0).unwrap();
    let strict = DiscSet::new(
        vec![disc],
        DiscSetOptions {
            slack: 0.5,
            ..options
        },
    )
    .unwrap();
    let mut out = vec![DVec3::ZERO];
    assert!(strict.accumulate_grid(&grid, 1.0, &mut out).is_err());
    let cached = DiscSet::new(
        vec![disc],
        DiscSetOptions {
            acceleration: Acceleration::RayCache { sorted: true },
            ..options
        },
    )
    .unwrap();
    assert!(cached.validate_ray_cache(&[]).is_ok());
    let brute = DiscSet::new(
        vec![disc],
        DiscSetOptions {
            acceleration: Acceleration::BruteForce,
            ..options
        },
    )
    .unwrap();
    assert!(matches!(
        brute.validate_ray_cache(&[]),
        Err(InvariantError { .. })
    ));
}

/// The disc index honours its leaf size and depth on the Cornell box, and the tuned rule gives larger leaves for larger discs (section 2.7).
#[test]
fn disc_index_shape() {
    let (scene, _) = cornell();
    let (discs, _) = scene_discs(scene, 0.05);
    for (leaf, depth) in [(1, 64), (8, 40), (4, 3)] {
        let set = DiscSet::new(
            discs.clone(),
            DiscSetOptions {
                acceleration: Acceleration::DiscIndex {
                    max_per_leaf: leaf,
                    max_depth: depth,
                },
                ..DiscSetOptions::default()
            },
        )
        .unwrap();
        set.validate().unwrap();
        let index = set.disc_index().unwrap();
        assert!(index.depth() <= depth);
        assert!(index.leaf_count() >= discs.len().div_ceil(leaf).min(1 << depth.min(30)) / 2);
    }
    let leaf = |r| match Acceleration::tuned_disc_index(r, 0.05) {
        Acceleration::DiscIndex { max_per_leaf, .. } => max_per_leaf,
        _ => unreachable!(),
    };
    assert!(leaf(0.025) <= leaf(0.05) && leaf(0.05) <= leaf(0.1));
    assert!(matches!(
        Acceleration::tuned_disc_index(f32::NAN, 0.0),
        Acceleration::DiscIndex { .. }
    ));
}
