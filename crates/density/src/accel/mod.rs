//! Accelerated DETP (sections 1.2.1, 2.6, 2.7, 2.8): the crossings of ray segments with the discs of Density Estimation on the Tangent Plane, found with the ray cache, disc indexing, pre-intersection tests, or a segment grid instead of testing every segment against every disc.
//!
//! Every acceleration returns exactly the (disc, segment) pairs that
//! [`Disc::is_crossed_by`] accepts when tried on all of them: the
//! structures only prune with conservative envelopes (see the `envelope`
//! module: pads of `8e-5` of the coordinates' magnitude, far above the
//! test's `f32` rounding), and every surviving pair still goes through
//! `is_crossed_by`. Each disc's sum `Σ φ_j` is taken over its crossing
//! segments in ascending segment index, starting from zero, in `f64` — the
//! same sum, bit for bit, whatever the acceleration or the thread count.
//!
//! | paper | item |
//! |---|---|
//! | 1.2 DETP, 2.4.1 first frame, 2.4.2 `E += est(NewRays) − est(OldRays)` | [`DiscSet::accumulate`], [`DiscSet::accumulate_net`] (beyond the paper: twins' terms that cancel left out, [`DiscSet::net_crossings`]) |
//! | 1.2.1, 2.6 ray cache, reuse of the point ordering | [`Acceleration::RayCache`], [`DiscSet::validate_ray_cache`], [`ray_cache`] |
//! | 2.7 disc indexing, tables 2.2–2.4 | [`Acceleration::DiscIndex`], [`DiscIndex`], [`Acceleration::tuned_disc_index`] |
//! | 2.8 pre-intersection tests, table 2.5 | [`PreTest`] |
//! | 2.5.2 mobile vertices (beyond the paper: an index over segments) | [`SegmentGrid`], [`DiscSet::accumulate_grid`], [`Acceleration::SegmentGrid`] |
//!
//! Discs that move every frame (the mobile object's vertices, section
//! 2.5.2) keep one [`DiscSet`] whose positions are replaced each frame with
//! [`DiscSet::update_discs`]: the visiting order and the disc index's tree
//! are kept (section 2.6: a rigid mobile stays coherent), only boxes are
//! refitted.

mod crossings;
mod envelope;
mod packed;

pub mod disc_index;
pub mod pretest;
pub mod ray_cache;
pub mod segment_grid;

use glam::DVec3;
use lustre_geometry::{MeshId, Scene};
use rayon::prelude::*;

pub use crossings::Crossings;
pub use disc_index::DiscIndex;
pub use pretest::PreTest;
use ray_cache::RayCache;
pub use segment_grid::SegmentGrid;

use envelope::{Box3, DiscEnvelope, SegmentEnvelope, check_disc, disc_envelope, segment_envelope};
use packed::{PackedLeaves, SegmentLanes};
use pretest::PreTests;

use crate::detp::Disc;
use crate::error::{DensityError, Result};
use crate::ray_set::RaySegment;
use crate::update::Twins;

/// An invariant of an acceleration structure that does not hold (what the `validate` methods report).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{structure}: {message}")]
pub struct InvariantError {
    /// The structure at fault (sections 2.6–2.8, or the segment grid beyond the paper).
    pub structure: &'static str,
    /// What does not hold (sections 2.6–2.8).
    pub message: String,
}

/// How a [`DiscSet`] finds the segments crossing each disc (sections 1.2.1, 2.6, 2.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Acceleration {
    /// Every segment against every disc (section 1.2, figure 2.3), in parallel over discs.
    BruteForce,
    /// The ray cache (sections 1.2.1, 2.6), discs visited in Morton order of their centres when `sorted` (computed once, at build), else in the given order; the order is split in one run per parallel task.
    RayCache {
        /// Visit the discs in a spatially coherent order (section 2.6, "Sort Queries" of table 2.6).
        sorted: bool,
    },
    /// Disc indexing (section 2.7): a hierarchy over the discs' boxes, each segment traversed through it, in parallel over segments.
    DiscIndex {
        /// Largest number of discs in a leaf (section 2.7, table 2.2 b); at least 1.
        max_per_leaf: usize,
        /// Largest depth of the hierarchy (section 2.7: decreased as the radius grows); at most [`disc_index::MAX_DEPTH_LIMIT`].
        max_depth: u32,
    },
    /// A uniform grid over the segments, built for each call, each disc looking at the segments of the cells its box overlaps (beyond the paper).
    SegmentGrid {
        /// Edge of the cubic cells; positive. A grid that would have more cells than four per segment (at least 4 096, at most [`segment_grid::MAX_CELLS`]) doubles its cell edge until it does not.
        cell_size: f32,
    },
}

impl Default for Acceleration {
    /// Disc indexing with leaves of 32 discs: the fastest full estimate of the `detp` bench's leaf sweep at every radius (section 2.7), see [`Acceleration::tuned_disc_index`].
    fn default() -> Self {
        Self::DiscIndex {
            max_per_leaf: 32,
            max_depth: 32,
        }
    }
}

impl Acceleration {
    /// Disc indexing with the leaf size and depth tuned for discs of `radius` on a mesh of edge `typical_edge` (section 2.7, tables 2.2–2.4): `max_per_leaf = 32` when `r / e < 4`, else 64, and `max_depth = 32`. From the `detp` bench's leaf sweep (`leaf_r…` groups, Cornell box at 0.05 m edges, 100 000 photons; leaves of 1 to 64 discs) with the leaves' discs tested eight at a time (the `packed` module): the fastest leaves were 32 at `r/e` = 0.5, 1 and 2 (64 within 3 %, 16 within 5–9 %); on the `dense_glossy` bench (one thread), its glossy discs (r = 0.213 m on a blob of 0.03 m edges) took 9 % less time with leaves of 64 than of 32, its diffuse discs (0.071 m) 3–7 % less with 32 than with 16 or 64. Before the packed test the optimum was 8–16. It moves far less than the paper's 20 → 1 600 because this index partitions the discs instead of the space (no disc is copied into both children), and no leaf reached depth 32, so the depth limit of section 2.7 is not needed here.
    pub fn tuned_disc_index(radius: f32, typical_edge: f32) -> Self {
        let ratio = radius / typical_edge;
        let max_per_leaf = if ratio < 4.0 { 32 } else { 64 };
        Self::DiscIndex {
            max_per_leaf,
            max_depth: 32,
        }
    }
}

/// Settings of a [`DiscSet`] (sections 1.2.1, 2.6–2.8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscSetOptions {
    /// Slack past a segment's reach passed to [`Disc::is_crossed_by`] (section 1.2: `detp` uses `1e-4` of the scene's size); finite, non-negative.
    pub slack: f32,
    /// How crossing segments are found (sections 1.2.1, 2.6, 2.7).
    pub acceleration: Acceleration,
    /// The pre-intersection test before each ray–disc test (section 2.8).
    pub pretest: PreTest,
}

impl Default for DiscSetOptions {
    fn default() -> Self {
        Self {
            slack: 0.0,
            acceleration: Acceleration::default(),
            pretest: PreTest::None,
        }
    }
}

/// What a disc gathers from its crossing segments, in ascending segment index.
trait Sink: Default + Send {
    /// Takes crossing segment `id`.
    fn add(&mut self, id: u32, segment: &RaySegment);
}

impl Sink for DVec3 {
    #[inline]
    fn add(&mut self, _: u32, segment: &RaySegment) {
        *self += segment.power.as_dvec3();
    }
}

impl Sink for Vec<u32> {
    #[inline]
    fn add(&mut self, id: u32, _: &RaySegment) {
        self.push(id);
    }
}

/// Mean edge length of the triangles of `meshes` (world space), the `typical_edge` of [`Acceleration::tuned_disc_index`] (section 2.7); 1 without a triangle. Meshes the scene does not have are skipped.
pub fn mean_edge(scene: &Scene, meshes: impl IntoIterator<Item = MeshId>) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for m in meshes {
        let Some(mesh) = scene.meshes().get(m as usize) else {
            continue;
        };
        let positions = scene.world_positions(m);
        for idx in &mesh.indices {
            for k in 0..3 {
                let a = positions[idx[k] as usize];
                let b = positions[idx[(k + 1) % 3] as usize];
                sum += a.distance(b) as f64;
                n += 1;
            }
        }
    }
    if n == 0 { 1.0 } else { (sum / n as f64) as f32 }
}

/// The crossings `a` and `b` of a frame's Old and New Rays less, at each disc, the twins that both cross it.
fn cancel_twins(a: &Crossings, b: &Crossings, twins: &Twins) -> (Crossings, Crossings) {
    let keep = |ids: &[u32], twins: &[Option<u32>], other: &[u32]| -> Vec<u32> {
        ids.iter()
            .copied()
            .filter(|&i| twins[i as usize].is_none_or(|t| other.binary_search(&t).is_err()))
            .collect()
    };
    let net = |x: &Crossings, twins: &[Option<u32>], y: &Crossings| {
        Crossings::from_lists(
            x.iter()
                .zip(y.iter())
                .map(|(p, q)| keep(p, twins, q))
                .collect(),
        )
    };
    (net(a, &twins.old, b), net(b, &twins.new, a))
}

/// A disc's sink fed with its crossing segments `ids` (indices into `segments`), in the order given.
fn sink_of<S: Sink>(ids: &[u32], segments: &[RaySegment]) -> S {
    let mut sink = S::default();
    for &j in ids {
        sink.add(j, &segments[j as usize]);
    }
    sink
}

/// Fails when segment indices would not fit in `u32`.
fn check_segment_count(segments: &[RaySegment]) -> Result<()> {
    if u32::try_from(segments.len()).is_err() {
        return Err(DensityError::InvalidOption {
            option: "segments",
            message: format!("{} segments are more than 2^32", segments.len()),
        });
    }
    Ok(())
}

/// The envelopes' unit normals, zero for a disc without an envelope (the disc index's normal cones).
fn normals(envelopes: &[Option<DiscEnvelope>]) -> Vec<DVec3> {
    envelopes
        .iter()
        .map(|e| e.map_or(DVec3::ZERO, |e| e.normal))
        .collect()
}

/// Segments per parallel task of disc indexing.
const SEGMENT_CHUNK: usize = 1024;
/// Parallel runs of the ray cache per rayon thread.
const RUNS_PER_THREAD: usize = 4;
/// Fewest discs in a ray cache run.
const MIN_RUN: usize = 64;

/// A fixed set of DETP discs with its acceleration structures (sections 1.2, 2.6–2.8): the visiting order, the disc index and the pre-test triangles are built once here and reused by every call.
#[derive(Debug, Clone)]
pub struct DiscSet {
    /// The discs.
    discs: Vec<Disc>,
    /// Their envelopes (`None`: a disc nothing crosses).
    envelopes: Vec<Option<DiscEnvelope>>,
    /// Their boxes (the envelopes' boxes).
    boxes: Vec<Option<Box3>>,
    /// The settings.
    options: DiscSetOptions,
    /// Box of every envelope: segments are clipped to it.
    bounds: Box3,
    /// Largest envelope reach.
    max_reach: f64,
    /// Visiting order of the ray cache (section 2.6).
    order: Vec<u32>,
    /// The box the order's Morton codes were computed in, while the discs have not moved since (`None` once they have, or unsorted).
    order_bounds: Option<Box3>,
    /// The disc index (section 2.7), with [`Acceleration::DiscIndex`].
    index: Option<DiscIndex>,
    /// The index's leaves packed for the branch-free test, without a pre-test (beyond the paper).
    packed: Option<PackedLeaves>,
    /// The pre-test triangles (section 2.8).
    pretests: PreTests,
}

/// The envelopes, boxes, bounds, largest reach and largest absolute coordinate of a list of discs.
type Prepared = (Vec<Option<DiscEnvelope>>, Vec<Option<Box3>>, Box3, f64, f64);

impl DiscSet {
    /// Builds the set and its structures (sections 2.6–2.8). Fails on a disc with a non-finite centre, a negative or non-finite radius, or a normal neither zero nor unit; on a negative or non-finite slack; on `max_per_leaf = 0`, `max_depth` above [`disc_index::MAX_DEPTH_LIMIT`], or a cell size that is not positive and finite.
    pub fn new(discs: Vec<Disc>, options: DiscSetOptions) -> Result<Self> {
        if !(options.slack >= 0.0 && options.slack.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "slack",
                message: format!("{} is not a finite non-negative slack", options.slack),
            });
        }
        match options.acceleration {
            Acceleration::DiscIndex {
                max_per_leaf,
                max_depth,
            } => {
                if max_per_leaf == 0 {
                    return Err(DensityError::InvalidOption {
                        option: "max_per_leaf",
                        message: "must be at least 1".into(),
                    });
                }
                if max_depth > disc_index::MAX_DEPTH_LIMIT {
                    return Err(DensityError::InvalidOption {
                        option: "max_depth",
                        message: format!(
                            "{max_depth} is more than {}",
                            disc_index::MAX_DEPTH_LIMIT
                        ),
                    });
                }
            }
            Acceleration::SegmentGrid { cell_size } => {
                if !(cell_size > 0.0 && cell_size.is_finite()) {
                    return Err(DensityError::InvalidOption {
                        option: "cell_size",
                        message: format!("{cell_size} is not a positive finite cell size"),
                    });
                }
            }
            Acceleration::BruteForce | Acceleration::RayCache { .. } => {}
        }
        let (envelopes, boxes, bounds, max_reach, near_limit) = Self::prepare(&discs)?;
        let order = match options.acceleration {
            Acceleration::RayCache { sorted } => {
                let centres: Vec<_> = envelopes.iter().map(|e| e.map(|e| e.centre)).collect();
                ray_cache::visiting_order(&centres, &bounds, sorted)
            }
            _ => Vec::new(),
        };
        let index = match options.acceleration {
            Acceleration::DiscIndex {
                max_per_leaf,
                max_depth,
            } => Some(DiscIndex::build(
                &boxes,
                &normals(&envelopes),
                max_per_leaf,
                max_depth,
            )),
            _ => None,
        };
        let order_bounds = matches!(
            options.acceleration,
            Acceleration::RayCache { sorted: true }
        )
        .then_some(bounds);
        let pretests = PreTests::new(options.pretest, &envelopes, near_limit);
        let mut set = Self {
            discs,
            envelopes,
            boxes,
            options,
            bounds,
            max_reach,
            order,
            order_bounds,
            index,
            packed: None,
            pretests,
        };
        set.pack();
        Ok(set)
    }

    /// Packs the disc index's leaves when the ray–disc test runs without a pre-test (section 2.8's tests stay one disc at a time).
    fn pack(&mut self) {
        self.packed = match (&self.index, self.options.pretest) {
            (Some(index), PreTest::None) => Some(PackedLeaves::new(
                &self.discs,
                index.items(),
                index.leaves(),
            )),
            _ => None,
        };
    }

    /// Checks the discs and computes their envelopes.
    fn prepare(discs: &[Disc]) -> Result<Prepared> {
        if u32::try_from(discs.len()).is_err() {
            return Err(DensityError::InvalidOption {
                option: "discs",
                message: format!("{} discs are more than 2^32", discs.len()),
            });
        }
        for (i, d) in discs.iter().enumerate() {
            if let Some(message) = check_disc(d) {
                return Err(DensityError::InvalidOption {
                    option: "discs",
                    message: format!("disc {i}: {message}"),
                });
            }
        }
        let envelopes: Vec<Option<DiscEnvelope>> = discs.iter().map(disc_envelope).collect();
        let boxes: Vec<Option<Box3>> = envelopes.iter().map(|e| e.map(|e| e.bounds)).collect();
        let bounds = boxes
            .iter()
            .flatten()
            .copied()
            .fold(Box3::EMPTY, Box3::union);
        let max_reach = envelopes
            .iter()
            .flatten()
            .map(|e| e.reach)
            .fold(0.0, f64::max);
        let near_limit = bounds.max_abs();
        Ok((envelopes, boxes, bounds, max_reach, near_limit))
    }

    /// Replaces the discs by moved ones, same count (section 2.5.2: the mobile object's vertices each frame), keeping the visiting order (section 2.6: computed once, reused) and the disc index's tree (boxes refitted). Fails as [`DiscSet::new`] does on a bad disc, or when the count differs.
    pub fn update_discs(&mut self, discs: &[Disc]) -> Result<()> {
        if discs.len() != self.discs.len() {
            return Err(DensityError::InvalidOption {
                option: "discs",
                message: format!(
                    "{} discs given to replace {}",
                    discs.len(),
                    self.discs.len()
                ),
            });
        }
        let (envelopes, boxes, bounds, max_reach, near_limit) = Self::prepare(discs)?;
        let same_support = envelopes
            .iter()
            .zip(&self.envelopes)
            .all(|(a, b)| a.is_some() == b.is_some());
        self.discs.copy_from_slice(discs);
        self.envelopes = envelopes;
        self.boxes = boxes;
        self.bounds = bounds;
        self.max_reach = max_reach;
        if !same_support {
            // A disc gained or lost its normal: the order and tree must list exactly the crossable discs.
            if let Acceleration::RayCache { sorted } = self.options.acceleration {
                let centres: Vec<_> = self.envelopes.iter().map(|e| e.map(|e| e.centre)).collect();
                self.order = ray_cache::visiting_order(&centres, &self.bounds, sorted);
                self.order_bounds = sorted.then_some(self.bounds);
            }
            if let Acceleration::DiscIndex {
                max_per_leaf,
                max_depth,
            } = self.options.acceleration
            {
                self.index = Some(DiscIndex::build(
                    &self.boxes,
                    &normals(&self.envelopes),
                    max_per_leaf,
                    max_depth,
                ));
            }
        } else {
            self.order_bounds = None;
            if let Some(index) = &mut self.index {
                index.refit(&self.boxes, &normals(&self.envelopes));
            }
        }
        self.pretests = PreTests::new(self.options.pretest, &self.envelopes, near_limit);
        self.pack();
        Ok(())
    }

    /// The discs (section 1.2: one per vertex).
    pub fn discs(&self) -> &[Disc] {
        &self.discs
    }

    /// Number of discs (section 1.2).
    pub fn len(&self) -> usize {
        self.discs.len()
    }

    /// Whether the set has no disc (section 1.2).
    pub fn is_empty(&self) -> bool {
        self.discs.is_empty()
    }

    /// The settings (sections 2.6–2.8).
    pub fn options(&self) -> DiscSetOptions {
        self.options
    }

    /// The ray cache's visiting order (section 2.6), empty for other accelerations; discs nothing can cross are left out.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The disc index (section 2.7), with [`Acceleration::DiscIndex`].
    pub fn disc_index(&self) -> Option<&DiscIndex> {
        self.index.as_ref()
    }

    /// `out[i] += sign · Σ φ_j` over the segments `j` crossing disc `i`, summed in `f64` in ascending `j` (section 2.4.2: `sign = 1` for NewRays or a first frame, `-1` for OldRays; equation 2.8: contributions are additive). Divide by `π r²` for the irradiance. Fails when `out` does not have one entry per disc.
    pub fn accumulate(&self, segments: &[RaySegment], sign: f64, out: &mut [DVec3]) -> Result<()> {
        self.check_out(out.len())?;
        let sums: Vec<DVec3> = self.gather(segments)?;
        for (o, s) in out.iter_mut().zip(sums) {
            *o += sign * s;
        }
        Ok(())
    }

    /// Per disc, the ascending indices of the segments crossing it (section 1.2: the rays intersecting the disc).
    pub fn crossings(&self, segments: &[RaySegment]) -> Result<Crossings> {
        if let (Acceleration::DiscIndex { .. }, Some(index)) =
            (self.options.acceleration, &self.index)
        {
            check_segment_count(segments)?;
            return Ok(self.indexed_crossings(index, segments));
        }
        self.gather(segments).map(Crossings::from_lists)
    }

    /// [`DiscSet::crossings`] of a frame's Old and New Rays, less the `twins` at each disc they both cross,
    /// where their two contributions cancel (beyond the paper: section 2.4.2's
    /// `est(NewRays) − est(OldRays)` without the terms that cancel). With disc indexing each twin pair is
    /// traversed once, only beyond the nearer of its two ends (a disc one of them crosses and the other
    /// does not lies there), its two ends tested together, and the segments of either kind that cross a
    /// disc their twin does not are exactly those `is_crossed_by` accepts. Fails when `twins` are not those
    /// of `old` and `new` ([`Twins::check`]).
    pub fn net_crossings(
        &self,
        old: &[RaySegment],
        new: &[RaySegment],
        twins: &Twins,
    ) -> Result<(Crossings, Crossings)> {
        check_segment_count(old)?;
        check_segment_count(new)?;
        twins.check(old, new)?;
        if let (Acceleration::DiscIndex { .. }, Some(index), Some(packed)) =
            (self.options.acceleration, &self.index, &self.packed)
        {
            return Ok(self.indexed_net_crossings(index, packed, old, new, &twins.old));
        }
        let (a, b) = (self.crossings(old)?, self.crossings(new)?);
        Ok(cancel_twins(&a, &b, twins))
    }

    /// `out[i] += sign · Σ φ_j` over [`DiscSet::net_crossings`]: the Old Rays' sum with `sign = −1`, then the New Rays' with `+1`, each in ascending segment index from zero in `f64` (section 2.4.2, equation 2.4, `E(x, t) = E(x, t−1) + E(x; N^t) − E(x; O^t)`, without the twins' terms that cancel). Fails when `out` does not have one entry per disc, or as [`DiscSet::net_crossings`] does.
    pub fn accumulate_net(
        &self,
        old: &[RaySegment],
        new: &[RaySegment],
        twins: &Twins,
        out: &mut [DVec3],
    ) -> Result<()> {
        self.check_out(out.len())?;
        let (a, b) = self.net_crossings(old, new, twins)?;
        out.par_iter_mut().enumerate().for_each(|(i, o)| {
            *o += -1.0 * sink_of::<DVec3>(&a[i], old);
            *o += 1.0 * sink_of::<DVec3>(&b[i], new);
        });
        Ok(())
    }

    /// [`DiscSet::accumulate`] over the live segments of a [`SegmentGrid`] (ids in place of indices: sums in ascending id), each disc looking only at the grid cells its box overlaps (beyond the paper; section 2.5.2, the mobile object's discs against all segments). Fails when `out` does not have one entry per disc, or the grid was built for a smaller slack.
    pub fn accumulate_grid(&self, grid: &SegmentGrid, sign: f64, out: &mut [DVec3]) -> Result<()> {
        self.check_out(out.len())?;
        self.check_grid(grid)?;
        let sums: Vec<DVec3> = self.gridded(grid);
        for (o, s) in out.iter_mut().zip(sums) {
            *o += sign * s;
        }
        Ok(())
    }

    /// [`DiscSet::crossings`] over the live segments of a [`SegmentGrid`], by id (beyond the paper; section 2.5.2).
    pub fn crossings_grid(&self, grid: &SegmentGrid) -> Result<Crossings> {
        self.check_grid(grid)?;
        Ok(Crossings::from_lists(self.gridded(grid)))
    }

    /// Fails unless `len` is the number of discs.
    fn check_out(&self, len: usize) -> Result<()> {
        if len != self.discs.len() {
            return Err(DensityError::InvalidOption {
                option: "out",
                message: format!("{len} entries for {} discs", self.discs.len()),
            });
        }
        Ok(())
    }

    /// Fails unless the grid's segments were registered for at least this set's slack.
    fn check_grid(&self, grid: &SegmentGrid) -> Result<()> {
        if !(grid.slack() >= self.options.slack) {
            return Err(DensityError::InvalidOption {
                option: "grid",
                message: format!(
                    "registered for slack {}, less than the disc set's {}",
                    grid.slack(),
                    self.options.slack
                ),
            });
        }
        Ok(())
    }

    /// Whether segment `s` (with envelope `e`, when known) crosses disc `i` (section 2.8): with a pre-test, the ray–disc test's own back-face check first (the same `f32` expression, so exact), then the pre-test may reject, then [`Disc::is_crossed_by`] decides.
    #[inline]
    fn crosses(&self, i: usize, e: Option<&SegmentEnvelope>, s: &RaySegment) -> bool {
        let disc = &self.discs[i];
        if let Some(e) = e {
            if self.pretests.kind() != PreTest::None {
                if !(s.direction.dot(disc.normal) < 0.0) {
                    return false;
                }
                if self.pretests.rejects(i, e) {
                    return false;
                }
            }
        }
        disc.is_crossed_by(s, self.options.slack)
    }

    /// Every segment's envelope within the set's bounds.
    fn segment_envelopes(&self, segments: &[RaySegment]) -> Vec<Option<SegmentEnvelope>> {
        segments
            .par_iter()
            .map(|s| segment_envelope(s, self.options.slack, &self.bounds))
            .collect()
    }

    /// What every disc gathers from its crossing segments, with the chosen acceleration.
    fn gather<S: Sink>(&self, segments: &[RaySegment]) -> Result<Vec<S>> {
        check_segment_count(segments)?;
        Ok(match self.options.acceleration {
            Acceleration::BruteForce => self.brute_force(segments),
            Acceleration::RayCache { .. } => self.cached(segments),
            Acceleration::DiscIndex { .. } => self.indexed(segments),
            Acceleration::SegmentGrid { cell_size } => {
                let mut cell = cell_size as f64;
                let extent = (self.bounds.max - self.bounds.min).max(DVec3::ZERO);
                let cap = (4 * segments.len()).clamp(1 << 12, segment_grid::MAX_CELLS) as f64;
                while (extent / cell).ceil().max(DVec3::ONE).element_product() > cap {
                    cell *= 2.0;
                }
                let bounds = if self.bounds.is_empty() {
                    Box3 {
                        min: DVec3::ZERO,
                        max: DVec3::ZERO,
                    }
                } else {
                    self.bounds
                };
                let mut grid = SegmentGrid::with_box(bounds, cell, self.options.slack)?;
                grid.fill(
                    segments
                        .iter()
                        .enumerate()
                        .map(|(j, s)| (j as u32, *s))
                        .collect(),
                );
                self.gridded(&grid)
            }
        })
    }

    /// Every segment against every disc (section 1.2, figure 2.3).
    fn brute_force<S: Sink>(&self, segments: &[RaySegment]) -> Vec<S> {
        let envelopes =
            (self.pretests.kind() != PreTest::None).then(|| self.segment_envelopes(segments));
        (0..self.discs.len())
            .into_par_iter()
            .map(|i| {
                let mut sink = S::default();
                if self.envelopes[i].is_none() {
                    return sink;
                }
                for (j, s) in segments.iter().enumerate() {
                    let e = match &envelopes {
                        Some(v) => match &v[j] {
                            Some(e) => Some(e),
                            None => continue,
                        },
                        None => None,
                    };
                    if self.crosses(i, e, s) {
                        sink.add(j as u32, s);
                    }
                }
                sink
            })
            .collect()
    }

    /// The ray cache (sections 1.2.1, 2.6): the visiting order split into runs, one cache per run.
    fn cached<S: Sink>(&self, segments: &[RaySegment]) -> Vec<S> {
        let envelopes = self.segment_envelopes(segments);
        let runs = (rayon::current_num_threads() * RUNS_PER_THREAD).max(1);
        let run = self.order.len().div_ceil(runs).max(MIN_RUN);
        let results: Vec<Vec<S>> = self
            .order
            .par_chunks(run)
            .map(|run| {
                let mut cache = RayCache::new(&envelopes, &self.bounds, self.max_reach);
                run.iter()
                    .map(|&i| {
                        let i = i as usize;
                        let mut sink = S::default();
                        let Some(d) = &self.envelopes[i] else {
                            return sink;
                        };
                        for &j in cache.query(d.centre, d.reach) {
                            let s = &segments[j as usize];
                            if self.crosses(i, envelopes[j as usize].as_ref(), s) {
                                sink.add(j, s);
                            }
                        }
                        sink
                    })
                    .collect()
            })
            .collect();
        let mut out: Vec<S> = (0..self.discs.len()).map(|_| S::default()).collect();
        for (&i, sink) in self.order.iter().zip(results.into_iter().flatten()) {
            out[i as usize] = sink;
        }
        out
    }

    /// Disc indexing (section 2.7): the crossings, then each disc's sink fed in segment order.
    fn indexed<S: Sink>(&self, segments: &[RaySegment]) -> Vec<S> {
        let Some(index) = &self.index else {
            return self.brute_force(segments);
        };
        let crossings = self.indexed_crossings(index, segments);
        (0..self.discs.len())
            .into_par_iter()
            .map(|i| sink_of(&crossings[i], segments))
            .collect()
    }

    /// Disc indexing (section 2.7): each segment through the index in parallel, then the pairs bucketed by disc in segment order.
    fn indexed_crossings(&self, index: &DiscIndex, segments: &[RaySegment]) -> Crossings {
        let envelopes = self.segment_envelopes(segments);
        let pairs = self.indexed_pairs(index, segments, &envelopes, |_| true);
        Crossings::from_pairs(self.discs.len(), &pairs)
    }

    /// Disc indexing (section 2.7): the `(disc, segment)` pairs of the segments `keep` accepts (by index) and
    /// the discs they cross, each segment through the index in parallel, chunk by chunk in segment order.
    fn indexed_pairs(
        &self,
        index: &DiscIndex,
        segments: &[RaySegment],
        envelopes: &[Option<SegmentEnvelope>],
        keep: impl Fn(usize) -> bool + Sync,
    ) -> Vec<Vec<(u32, u32)>> {
        envelopes
            .par_chunks(SEGMENT_CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut pairs = Vec::new();
                for (k, e) in chunk.iter().enumerate() {
                    let j = c * SEGMENT_CHUNK + k;
                    let Some(e) = e.as_ref().filter(|_| keep(j)) else {
                        continue;
                    };
                    let s = &segments[j];
                    if let Some(packed) = &self.packed {
                        let lanes = SegmentLanes::new(s, self.options.slack);
                        index.for_each_leaf(e, |first, count| {
                            packed.for_each_crossed(first, count, &lanes, |i| {
                                pairs.push((i, j as u32));
                            });
                        });
                    } else {
                        index.for_each_candidate(e, |i| {
                            if self.crosses(i as usize, Some(e), s) {
                                pairs.push((i, j as u32));
                            }
                        });
                    }
                }
                pairs
            })
            .collect()
    }

    /// [`DiscSet::net_crossings`] by disc indexing: every Old Ray in parallel, a twin pair's two ends tested
    /// together on the part of the pair beyond the nearer end, then the New Rays without a twin.
    fn indexed_net_crossings(
        &self,
        index: &DiscIndex,
        packed: &PackedLeaves,
        old: &[RaySegment],
        new: &[RaySegment],
        old_twin: &[Option<u32>],
    ) -> (Crossings, Crossings) {
        let slack = self.options.slack;
        let (old_env, new_env) = (self.segment_envelopes(old), self.segment_envelopes(new));
        // A pair is traversed together when both ends have an envelope, through the one reaching farther
        // (same origin and direction, so it holds the other's every candidate); otherwise each on its own.
        let joint: Vec<Option<u32>> = old_twin
            .iter()
            .enumerate()
            .map(|(j, t)| t.filter(|&k| old_env[j].is_some() && new_env[k as usize].is_some()))
            .collect();
        let mut paired = vec![false; new.len()];
        for &k in joint.iter().flatten() {
            paired[k as usize] = true;
        }
        type Pairs = (Vec<(u32, u32)>, Vec<(u32, u32)>);
        let from_old: Vec<Pairs> = old_env
            .par_chunks(SEGMENT_CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                for (n, e) in chunk.iter().enumerate() {
                    let Some(e) = e else { continue };
                    let j = c * SEGMENT_CHUNK + n;
                    let lanes = SegmentLanes::new(&old[j], slack);
                    match joint[j] {
                        Some(k) => {
                            let twin = SegmentLanes::new(&new[k as usize], slack);
                            let mut far = match &new_env[k as usize] {
                                Some(f) if f.t_hi > e.t_hi => *f,
                                _ => *e,
                            };
                            // A disc only one of them crosses lies beyond the nearer end: only
                            // that part of the segment is traversed.
                            let ends = (lanes.nearest_limit(), twin.nearest_limit());
                            if !(ends.0.is_nan() || ends.1.is_nan()) {
                                far.t_lo = far.t_lo.max(f64::from(ends.0.min(ends.1)));
                            }
                            index.for_each_leaf(&far, |first, count| {
                                packed.for_each_crossed_by_one(
                                    first,
                                    count,
                                    &lanes,
                                    &twin,
                                    |i| a.push((i, j as u32)),
                                    |i| b.push((i, k)),
                                );
                            });
                        }
                        None => index.for_each_leaf(e, |first, count| {
                            packed
                                .for_each_crossed(first, count, &lanes, |i| a.push((i, j as u32)));
                        }),
                    }
                }
                (a, b)
            })
            .collect();
        let from_new = self.indexed_pairs(index, new, &new_env, |k| !paired[k]);
        let (old_pairs, mut new_pairs): (Vec<_>, Vec<_>) = from_old.into_iter().unzip();
        new_pairs.extend(from_new);
        let mut b = Crossings::from_pairs(self.discs.len(), &new_pairs);
        // The twins' New Rays came in their Old Rays' order.
        b.sort_each();
        (Crossings::from_pairs(self.discs.len(), &old_pairs), b)
    }

    /// Each disc against the segments of the grid cells its box overlaps (beyond the paper), in parallel over discs: each candidate tested once (a per-thread mailbox), the crossing ones then summed in id order.
    fn gridded<S: Sink>(&self, grid: &SegmentGrid) -> Vec<S> {
        (0..self.discs.len())
            .into_par_iter()
            .map_init(
                || (Vec::new(), 0u32, Vec::new()),
                |(stamps, epoch, hits), i| {
                    let mut sink = S::default();
                    let Some(d) = &self.envelopes[i] else {
                        return sink;
                    };
                    hits.clear();
                    grid.for_each_unique_slot(d, stamps, epoch, |slot| {
                        let (e, s) = grid.slot_data(slot);
                        if self.crosses(i, e, s) {
                            hits.push((grid.slot_id(slot), slot));
                        }
                    });
                    hits.sort_unstable();
                    for &(id, slot) in hits.iter() {
                        sink.add(id, grid.slot_data(slot).1);
                    }
                    sink
                },
            )
            .collect()
    }

    /// Runs one ray cache over the whole visiting order (section 2.6), checking after every query that the hierarchy's invariants hold and that the queried list holds every segment crossing the disc; returns the spheres built and the queries made (the cache misses of table 2.6). Fails unless the acceleration is [`Acceleration::RayCache`].
    pub fn validate_ray_cache(
        &self,
        segments: &[RaySegment],
    ) -> std::result::Result<(u64, u64), InvariantError> {
        let fail = |message: String| InvariantError {
            structure: "ray cache",
            message,
        };
        if !matches!(self.options.acceleration, Acceleration::RayCache { .. }) {
            return Err(fail("the disc set has no ray cache".into()));
        }
        let envelopes = self.segment_envelopes(segments);
        let mut cache = RayCache::new(&envelopes, &self.bounds, self.max_reach);
        for &i in &self.order {
            let Some(d) = &self.envelopes[i as usize] else {
                return Err(fail(format!("order lists disc {i}, which nothing crosses")));
            };
            let ids = cache.query(d.centre, d.reach).to_vec();
            cache.validate()?;
            for (j, s) in segments.iter().enumerate() {
                if self.discs[i as usize].is_crossed_by(s, self.options.slack)
                    && ids.binary_search(&(j as u32)).is_err()
                {
                    return Err(fail(format!(
                        "disc {i}: crossing segment {j} not in the cache"
                    )));
                }
            }
        }
        Ok((cache.spheres_built(), cache.queries()))
    }

    /// Checks every structure of the set (sections 2.6–2.8): envelopes match the discs, the visiting order is a permutation of the crossable discs (Morton-sorted when asked), the disc index's invariants, the pre-test triangles.
    pub fn validate(&self) -> std::result::Result<(), InvariantError> {
        let fail = |message: String| InvariantError {
            structure: "disc set",
            message,
        };
        for (i, d) in self.discs.iter().enumerate() {
            if disc_envelope(d) != self.envelopes[i] {
                return Err(fail(format!("disc {i}: stale envelope")));
            }
            if let Some(e) = &self.envelopes[i] {
                if !self.bounds.contains_box(&e.bounds) {
                    return Err(fail(format!("disc {i}: box outside the set's bounds")));
                }
            }
        }
        if let Acceleration::RayCache { .. } = self.options.acceleration {
            let mut seen = vec![false; self.discs.len()];
            for &i in &self.order {
                match seen.get_mut(i as usize) {
                    Some(s) if !*s && self.envelopes[i as usize].is_some() => *s = true,
                    _ => return Err(fail(format!("order lists disc {i} wrongly"))),
                }
            }
            let expected = self.envelopes.iter().flatten().count();
            if self.order.len() != expected {
                return Err(fail(format!(
                    "order lists {} discs, expected {expected}",
                    self.order.len()
                )));
            }
            if let Some(bounds) = self.order_bounds {
                let codes: Vec<u64> = self
                    .order
                    .iter()
                    .map(|&i| {
                        ray_cache::morton(
                            self.envelopes[i as usize].map_or(DVec3::ZERO, |e| e.centre),
                            &bounds,
                        )
                    })
                    .collect();
                if codes.windows(2).any(|w| w[0] > w[1]) {
                    return Err(fail("order is not Morton-sorted".into()));
                }
            }
        }
        if let Some(index) = &self.index {
            index.validate(&self.boxes, &normals(&self.envelopes))?;
        }
        self.pretests
            .validate(&self.envelopes)
            .map_err(|m| InvariantError {
                structure: "pre-tests",
                message: m,
            })
    }
}

/// One disc per vertex of every mesh of a scene, on its tangent plane, as [`detp`](crate::detp) makes them (section 1.2), flattened mesh by mesh; a vertex without a usable normal gets a zero normal (nothing crosses it). Also returns where each mesh's discs start.
pub fn scene_discs(scene: &Scene, radius: f32) -> (Vec<Disc>, Vec<usize>) {
    let mut discs = Vec::new();
    let mut starts = Vec::with_capacity(scene.meshes().len() + 1);
    for m in 0..scene.meshes().len() {
        starts.push(discs.len());
        let positions = scene.world_positions(m as MeshId);
        let normals = scene.world_normals(m as MeshId);
        discs.extend(
            positions
                .iter()
                .zip(&normals)
                .map(|(&centre, &normal)| Disc {
                    centre,
                    normal: normal.normalize_or_zero(),
                    radius,
                    mesh: Some(m as MeshId),
                }),
        );
    }
    starts.push(discs.len());
    (discs, starts)
}

/// The slack [`detp`](crate::detp) gives [`Disc::is_crossed_by`] in a scene: `1e-4` of its largest extent (section 1.2).
pub fn scene_slack(scene: &Scene) -> f32 {
    let scale = scene.bounds().extent().max_element();
    if scale.is_finite() && scale > 0.0 {
        scale * 1e-4
    } else {
        1e-4
    }
}
