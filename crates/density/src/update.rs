//! PHOTOSIMULATION RECALCULUS (section 2.3, figure 2.2): after the mobile objects move, every ray that hit one of them, or hits one now, is traced again from that ray on; its old path goes to OldRays, the new one to NewRays.

use std::collections::HashMap;

use lustre_geometry::{Ray, Scene};
use rayon::prelude::*;

use crate::error::{DensityError, Result};
use crate::ray_set::{PrimaryRay, RaySegment, RaySet, RaySetOptions, Tracer};
use crate::world::World;

/// The rays a frame's recalculation replaced (section 2.4.2: `O^t = S^{t-1} - S^t`, equation 2.6) and those that replaced them (`N^t = S^t - S^{t-1}`, equation 2.5).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RayUpdate {
    /// OldRays: the segments removed from the ray set.
    pub old: Vec<RaySegment>,
    /// NewRays: the segments added to it.
    pub new: Vec<RaySegment>,
    /// The primary rays with a recalculated path, by index into `RaySet::rays`, ascending.
    pub primaries: Vec<usize>,
    /// The twins of each recalculated path: its re-traced segment before and after (same origin, direction
    /// and power, another end), and any later segments at the same place in both paths with the same
    /// origin, direction and power (a path that bounces where it did, e.g. off a face the motion kept in
    /// its plane, continues as it did).
    pub twins: Twins,
}

/// A frame's twins (beyond the paper): for each Old Ray its twin among the New Rays and for each New Ray its
/// twin among the Old Rays, or `None`; twins have the same origin, direction and power bits and are paired
/// one to one. At every disc both cross they are the same incident ray, so there their two contributions
/// cancel ([`crate::DiscSet::net_crossings`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Twins {
    /// Per Old Ray, the index of its twin among the New Rays.
    pub old: Vec<Option<u32>>,
    /// Per New Ray, the index of its twin among the Old Rays.
    pub new: Vec<Option<u32>>,
}

impl Twins {
    /// The twins found by their bits alone ([`twin_segments`]), for Old and New Rays that do not come from
    /// [`update_ray_set`] (which pairs them as it re-traces).
    pub fn by_bits(old: &[RaySegment], new: &[RaySegment]) -> Self {
        let (old, new) = twin_segments(old, new);
        Self { old, new }
    }

    /// Fails unless the twins are those of `old` and `new`: one entry per ray, each twin naming the other
    /// back, with the same origin, direction and power bits.
    pub fn check(&self, old: &[RaySegment], new: &[RaySegment]) -> Result<()> {
        let fail = |message: String| {
            Err(DensityError::InvalidOption {
                option: "twins",
                message,
            })
        };
        if self.old.len() != old.len() || self.new.len() != new.len() {
            return fail(format!(
                "{} and {} entries for {} Old and {} New Rays",
                self.old.len(),
                self.new.len(),
                old.len(),
                new.len()
            ));
        }
        for (j, &twin) in self.old.iter().enumerate() {
            let Some(k) = twin else { continue };
            match new.get(k as usize) {
                Some(n) if self.new[k as usize] == Some(j as u32) && same_ray(&old[j], n) => {}
                _ => return fail(format!("Old Ray {j} and New Ray {k} are not twins")),
            }
        }
        for (k, &twin) in self.new.iter().enumerate() {
            if twin.is_some_and(|j| self.old.get(j as usize) != Some(&Some(k as u32))) {
                return fail(format!(
                    "New Ray {k} names an Old Ray that does not name it"
                ));
            }
        }
        Ok(())
    }
}

/// Whether two segments have the same origin, direction and power bits.
fn same_ray(a: &RaySegment, b: &RaySegment) -> bool {
    ray_bits(a) == ray_bits(b)
}

/// The bits of a segment's origin, direction and power.
fn ray_bits(s: &RaySegment) -> [u32; 9] {
    let (o, d, p) = (s.origin, s.direction, s.power);
    [o.x, o.y, o.z, d.x, d.y, d.z, p.x, p.y, p.z].map(f32::to_bits)
}

/// Updates a ray set traced with [`crate::trace_ray_set_in`] after the world's mobile objects moved (figure 2.2). `world` must already hold the new pose ([`World::move_mobile`]) and `options` must be those of the first trace, so that the result equals a full trace of the new pose.
pub fn update_ray_set(
    scene: &Scene,
    world: &World,
    rays: &mut RaySet,
    options: &RaySetOptions,
) -> Result<RayUpdate> {
    update_paths(scene, world, rays, options, None)
}

/// [`update_ray_set`] visiting only the primary rays `paths` lists (ascending indices; those past the ray set
/// are ignored): the others must be paths none of whose segments hit the mobile objects before their move or
/// meet them after it, such as those a [`crate::path_cells::PathCells`] region round both poses rules out
/// ([`crate::path_cells::PathCells::paths_meeting`]; beyond the paper: figure 2.2 visits every ray).
pub fn update_ray_set_paths(
    scene: &Scene,
    world: &World,
    rays: &mut RaySet,
    options: &RaySetOptions,
    paths: &[usize],
) -> Result<RayUpdate> {
    update_paths(scene, world, rays, options, Some(paths))
}

/// A recalculated primary ray: its index, its OldRays and its NewRays.
type Recalculated = (usize, Vec<RaySegment>, Vec<RaySegment>);

/// Primary rays per parallel task of the update.
const PATH_RUN: usize = 1 << 12;

/// [`update_ray_set_paths`], every path when `paths` is `None`.
fn update_paths(
    scene: &Scene,
    world: &World,
    rays: &mut RaySet,
    options: &RaySetOptions,
    paths: Option<&[usize]>,
) -> Result<RayUpdate> {
    let tracer = Tracer::new(
        scene,
        world,
        (options.extension > 0.0).then(|| world.static_scene_bvh(scene)),
        world.epsilon(),
        options,
    )?;
    // Runs of paths in parallel, each visiting its listed paths in order.
    let changed: Vec<Vec<Recalculated>> = rays
        .rays
        .par_chunks_mut(PATH_RUN)
        .enumerate()
        .map(|(run, chunk)| {
            let base = run * PATH_RUN;
            let listed: Box<dyn Iterator<Item = usize>> = match paths {
                Some(paths) => {
                    let a = paths.partition_point(|&i| i < base);
                    let b = paths.partition_point(|&i| i < base + chunk.len());
                    Box::new(paths[a..b].iter().copied())
                }
                None => Box::new(base..base + chunk.len()),
            };
            listed
                .filter_map(|i| recalculate(world, &tracer, i, &mut chunk[i - base]))
                .collect()
        })
        .collect();
    let mut update = RayUpdate::default();
    let mut pairs = Vec::new();
    for (i, old, new) in changed.into_iter().flatten() {
        update.primaries.push(i);
        // The re-traced segment keeps its origin, direction and power; so does every later one while the
        // path bounces where it did (its random numbers are its own).
        for (n, (a, b)) in old.iter().zip(&new).enumerate() {
            if same_ray(a, b) {
                pairs.push((update.old.len() + n, update.new.len() + n));
            }
        }
        update.old.extend(old);
        update.new.extend(new);
    }
    update.twins = Twins {
        old: vec![None; update.old.len()],
        new: vec![None; update.new.len()],
    };
    for (j, k) in pairs {
        update.twins.old[j] = Some(k as u32);
        update.twins.new[k] = Some(j as u32);
    }
    Ok(update)
}

/// Figure 2.2 on primary ray `i`: from its first segment that must be recalculated on, its old path (the
/// OldRays) and the path traced again (the NewRays); `None` when no segment must be.
fn recalculate(
    world: &World,
    tracer: &Tracer,
    i: usize,
    primary: &mut PrimaryRay,
) -> Option<Recalculated> {
    let k = primary
        .segments
        .iter()
        .position(|s| must_recalculate(world, s))?;
    let old = primary.segments.split_off(k);
    let first = old[0];
    let ray = Ray::new(first.origin, first.direction);
    tracer.follow(
        primary.light,
        primary.index,
        k as u32,
        ray,
        first.power,
        &mut primary.segments,
    );
    let new = primary.segments[k..].to_vec();
    Some((i, old, new))
}

/// For each Old Ray its twin among the New Rays, and for each New Ray its twin among the Old Rays: the one
/// segment of the other kind with the same origin, direction and power bits (a re-traced path's first
/// changed segment, which keeps them and only ends elsewhere), where no other Old or New Ray shares them,
/// so that the pairing is one to one (beyond the paper: such a pair crosses the same discs but near its
/// ends, and there its two contributions cancel).
pub fn twin_segments(
    old: &[RaySegment],
    new: &[RaySegment],
) -> (Vec<Option<u32>>, Vec<Option<u32>>) {
    let key = ray_bits;
    // Per key: how many Old and New Rays carry it, and the last of each.
    let mut seen: HashMap<[u32; 9], [(u32, u32); 2]> =
        HashMap::with_capacity(old.len() + new.len());
    for (side, segments) in [old, new].into_iter().enumerate() {
        for (i, s) in segments.iter().enumerate() {
            let entry = &mut seen.entry(key(s)).or_default()[side];
            *entry = (entry.0 + 1, i as u32);
        }
    }
    let twins = |side: usize, segments: &[RaySegment]| {
        segments
            .iter()
            .map(|s| match seen[&key(s)] {
                [(1, o), (1, n)] => Some(if side == 0 { n } else { o }),
                _ => None,
            })
            .collect()
    };
    (twins(0, old), twins(1, new))
}

/// Figure 2.2's test: the ray intersected the mobile object, or intersects it now before its current end. (The artifact-control extension is measured against the static scene only, so it never changes while the ray is kept.)
fn must_recalculate(world: &World, segment: &RaySegment) -> bool {
    if segment.hit.is_some_and(|h| h.mobile) {
        return true;
    }
    world
        .mobile_hit(&Ray::segment(
            segment.origin,
            segment.direction,
            0.0,
            segment.length(),
        ))
        .is_some()
}
