//! A segment grid (beyond the paper, for sections 2.4.2 and 2.5.2): a uniform grid over a box in which every ray segment is registered in the cells it passes, kept current by incremental insertion and removal, so that a disc that moves every frame looks only at the segments near it.
//!
//! Registration walks the segment slab by slab along its dominant axis and,
//! within each slab, takes the cells its padded piece spans on the other two
//! axes: a conservative 3D DDA that never misses a cell to rounding. A
//! segment leaving the grid's box is also kept in an *outside* list, which
//! a disc not wholly inside the box scans as well, so a query is exact for
//! any disc. Removal is lazy: a removed segment's slot is marked dead and
//! its registrations are skipped until the grid compacts itself (when dead
//! slots outnumber live ones), so insertion and removal cost only the
//! segment's own cells even in the crowded cells around a light.

use std::collections::HashMap;

use lustre_geometry::Aabb;
use rayon::prelude::*;

use super::InvariantError;
use super::envelope::{
    Box3, DiscEnvelope, SegmentEnvelope, check_disc, disc_envelope, segment_envelope, segment_limit,
};
use crate::detp::Disc;
use crate::error::{DensityError, Result};
use crate::ray_set::RaySegment;

/// Largest number of cells of a segment grid (beyond the paper).
pub const MAX_CELLS: usize = 1 << 21;
/// Segments per parallel task of a bulk build.
const BUILD_CHUNK: usize = 2048;

/// A stored segment.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Slot {
    /// The caller's id.
    id: u32,
    /// The segment.
    segment: RaySegment,
    /// Whether it can cross any disc at all.
    valid: bool,
    /// Its envelope clipped to the grid's box (`None` when it does not enter it or crosses nothing).
    envelope: Option<SegmentEnvelope>,
}

impl Slot {
    /// Whether the segment belongs on the outside list: it may cross a disc outside the grid's box.
    fn outside(&self) -> bool {
        self.valid && self.envelope.is_none_or(|e| e.clipped)
    }
}

/// The segment grid (beyond the paper; sections 2.4.2, 2.5.2): segments by id, each registered in the grid cells it passes.
#[derive(Debug, Clone)]
pub struct SegmentGrid {
    /// The gridded box.
    bounds: Box3,
    /// Cell edge.
    cell: f64,
    /// Cells per axis (beyond the paper).
    dims: [usize; 3],
    /// Slack of the crossing test the segments are registered for.
    slack: f32,
    /// Slot numbers registered in each cell (dead slots included until compaction).
    cells: Vec<Vec<u32>>,
    /// Slots of the segments that leave the box (dead slots included until compaction).
    outside: Vec<u32>,
    /// Every slot, `None` once removed.
    slots: Vec<Option<Slot>>,
    /// The slot of each live id.
    by_id: HashMap<u32, u32>,
    /// Whether ids increase with slot numbers (after a bulk build, a compaction, or insertions in increasing id), so that slot order is id order.
    monotonic: bool,
    /// The id of the last slot.
    last_id: Option<u32>,
}

impl SegmentGrid {
    /// An empty grid of cubic cells of edge `cell_size` over `bounds`, for crossing tests with `slack` (beyond the paper). Fails on a non-finite or empty box, a cell size that is not positive and finite, more than [`MAX_CELLS`] cells, or a slack that is negative or not finite.
    pub fn new(bounds: Aabb, cell_size: f32, slack: f32) -> Result<Self> {
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(DensityError::InvalidOption {
                option: "bounds",
                message: format!("{bounds:?} is not a finite non-empty box"),
            });
        }
        let bounds = Box3 {
            min: bounds.min.as_dvec3(),
            max: bounds.max.as_dvec3(),
        };
        Self::with_box(bounds, cell_size as f64, slack)
    }

    /// [`SegmentGrid::new`] on an `f64` box.
    pub(crate) fn with_box(bounds: Box3, cell: f64, slack: f32) -> Result<Self> {
        if !(cell > 0.0 && cell.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "cell_size",
                message: format!("{cell} is not a positive finite cell size"),
            });
        }
        if !(slack >= 0.0 && slack.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "slack",
                message: format!("{slack} is not a finite non-negative slack"),
            });
        }
        let extent = bounds.max - bounds.min;
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as usize).max(1));
        let total = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .filter(|&t| t <= MAX_CELLS);
        let Some(total) = total else {
            return Err(DensityError::InvalidOption {
                option: "cell_size",
                message: format!("{cell} gives {dims:?} cells over the box, more than {MAX_CELLS}"),
            });
        };
        Ok(Self {
            bounds,
            cell,
            dims,
            slack,
            cells: vec![Vec::new(); total],
            outside: Vec::new(),
            slots: Vec::new(),
            by_id: HashMap::new(),
            monotonic: true,
            last_id: None,
        })
    }

    /// A grid holding `segments`, segment `j` under id `j`, registered in parallel (beyond the paper).
    pub fn from_segments(
        bounds: Aabb,
        cell_size: f32,
        slack: f32,
        segments: &[RaySegment],
    ) -> Result<Self> {
        let mut grid = Self::new(bounds, cell_size, slack)?;
        grid.fill(
            segments
                .iter()
                .enumerate()
                .map(|(j, s)| (j as u32, *s))
                .collect(),
        );
        Ok(grid)
    }

    /// Registers the given segments (ids distinct, not in the grid) in parallel.
    pub(crate) fn fill(&mut self, entries: Vec<(u32, RaySegment)>) {
        let base = self.slots.len() as u32;
        let prepared: Vec<(Vec<Slot>, Vec<u32>, Vec<u32>)> = entries
            .par_chunks(BUILD_CHUNK)
            .map(|chunk| {
                let mut slots = Vec::with_capacity(chunk.len());
                let mut cells = Vec::new();
                let mut counts = Vec::with_capacity(chunk.len());
                for &(id, segment) in chunk {
                    let slot = self.slot(id, segment);
                    let before = cells.len();
                    if let Some(e) = &slot.envelope {
                        self.cells_of(e, |c| cells.push(c as u32));
                    }
                    counts.push((cells.len() - before) as u32);
                    slots.push(slot);
                }
                (slots, cells, counts)
            })
            .collect();
        let mut number = base;
        for (slots, cells, counts) in prepared {
            let mut at = 0usize;
            for (slot, count) in slots.into_iter().zip(counts) {
                for &c in &cells[at..at + count as usize] {
                    self.cells[c as usize].push(number);
                }
                at += count as usize;
                if slot.outside() {
                    self.outside.push(number);
                }
                self.note_id(slot.id);
                self.by_id.insert(slot.id, number);
                self.slots.push(Some(slot));
                number += 1;
            }
        }
    }

    /// A slot for a segment.
    fn slot(&self, id: u32, segment: RaySegment) -> Slot {
        Slot {
            id,
            segment,
            valid: segment_limit(&segment, self.slack).is_some(),
            envelope: segment_envelope(&segment, self.slack, &self.bounds),
        }
    }

    /// The cell coordinate of `x` along `axis`, clamped to the grid.
    #[inline]
    fn coord(&self, axis: usize, x: f64) -> usize {
        let c = ((x - self.bounds.min[axis]) / self.cell).floor();
        (c as i64).clamp(0, self.dims[axis] as i64 - 1) as usize
    }

    /// The linear index of cell `(i, j, k)`.
    #[inline]
    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Calls `f` with every cell the padded segment passes (each once): slab by slab along the dominant axis, the cells spanned by the padded piece within the slab.
    fn cells_of(&self, e: &SegmentEnvelope, mut f: impl FnMut(usize)) {
        let d = e.direction.abs();
        let a = if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        };
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let p0 = e.origin + e.t_lo * e.direction;
        let p1 = e.origin + e.t_hi * e.direction;
        let pad = e.pad;
        let i0 = self.coord(a, p0[a].min(p1[a]) - pad);
        let i1 = self.coord(a, p0[a].max(p1[a]) + pad);
        for i in i0..=i1 {
            let lo = if i == 0 {
                f64::NEG_INFINITY
            } else {
                self.bounds.min[a] + i as f64 * self.cell - pad
            };
            let hi = if i + 1 == self.dims[a] {
                f64::INFINITY
            } else {
                self.bounds.min[a] + (i + 1) as f64 * self.cell + pad
            };
            let ta = (lo - e.origin[a]) * e.inv_direction[a];
            let tb = (hi - e.origin[a]) * e.inv_direction[a];
            let t0 = ta.min(tb).max(e.t_lo);
            let t1 = ta.max(tb).min(e.t_hi);
            if !(t0 <= t1) {
                continue;
            }
            let q0 = e.origin + t0 * e.direction;
            let q1 = e.origin + t1 * e.direction;
            let (j0, j1) = (
                self.coord(b, q0[b].min(q1[b]) - pad),
                self.coord(b, q0[b].max(q1[b]) + pad),
            );
            let (k0, k1) = (
                self.coord(c, q0[c].min(q1[c]) - pad),
                self.coord(c, q0[c].max(q1[c]) + pad),
            );
            for j in j0..=j1 {
                for k in k0..=k1 {
                    let mut cell = [0; 3];
                    cell[a] = i;
                    cell[b] = j;
                    cell[c] = k;
                    f(self.index(cell));
                }
            }
        }
    }

    /// Adds a segment under `id`, replacing the segment that had that id (beyond the paper: a NewRays segment, section 2.4.2).
    pub fn insert(&mut self, id: u32, segment: &RaySegment) {
        self.remove(id);
        let slot = self.slot(id, *segment);
        let number = self.slots.len() as u32;
        if let Some(e) = &slot.envelope {
            let mut cells = Vec::new();
            self.cells_of(e, |c| cells.push(c));
            for c in cells {
                self.cells[c].push(number);
            }
        }
        if slot.outside() {
            self.outside.push(number);
        }
        self.note_id(id);
        self.by_id.insert(id, number);
        self.slots.push(Some(slot));
    }

    /// Records that the next slot gets `id`.
    fn note_id(&mut self, id: u32) {
        if self.last_id.is_some_and(|last| last >= id) {
            self.monotonic = false;
        }
        self.last_id = Some(id);
    }

    /// Removes the segment of `id` (an OldRays segment, section 2.4.2); `false` when there was none.
    pub fn remove(&mut self, id: u32) -> bool {
        let Some(number) = self.by_id.remove(&id) else {
            return false;
        };
        self.slots[number as usize] = None;
        if self.slots.len() - self.by_id.len() > self.by_id.len().max(1024) {
            self.compact();
        }
        true
    }

    /// Drops every dead slot and registration, renumbering the live segments in id order (beyond the paper).
    pub fn compact(&mut self) {
        let mut live: Vec<(u32, RaySegment)> = self
            .slots
            .iter()
            .flatten()
            .map(|s| (s.id, s.segment))
            .collect();
        live.sort_unstable_by_key(|&(id, _)| id);
        for cell in &mut self.cells {
            cell.clear();
        }
        self.outside.clear();
        self.slots.clear();
        self.by_id.clear();
        self.monotonic = true;
        self.last_id = None;
        self.fill(live);
    }

    /// Number of live segments: the current ray set `S^t` (section 2.4.2).
    pub fn len(&self) -> usize {
        self.by_id.len()
    }

    /// Whether the grid holds no segment (section 2.4.2).
    pub fn is_empty(&self) -> bool {
        self.by_id.is_empty()
    }

    /// The segment of `id`, if any (section 2.3: a ray of the ray set).
    pub fn get(&self, id: u32) -> Option<&RaySegment> {
        let number = *self.by_id.get(&id)?;
        self.slots[number as usize].as_ref().map(|s| &s.segment)
    }

    /// Every live segment with its id, in id order (section 2.4.2: the ray set `S^t`).
    pub fn segments(&self) -> Vec<(u32, RaySegment)> {
        let mut v: Vec<(u32, RaySegment)> = self
            .slots
            .iter()
            .flatten()
            .map(|s| (s.id, s.segment))
            .collect();
        v.sort_unstable_by_key(|&(id, _)| id);
        v
    }

    /// The slack the segments are registered for (section 1.2, the crossing test).
    pub fn slack(&self) -> f32 {
        self.slack
    }

    /// Cells per axis (beyond the paper).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Total registrations (live and dead) in the cells (beyond the paper).
    pub fn registrations(&self) -> usize {
        self.cells.iter().map(Vec::len).sum()
    }

    /// Fills `out` with the `(id, slot)` of every live segment that may cross the disc of envelope `disc` (`None`: every live segment), sorted by id without repeats; `scratch` is working space.
    pub(crate) fn candidates(
        &self,
        disc: Option<&DiscEnvelope>,
        scratch: &mut Vec<u32>,
        out: &mut Vec<(u32, u32)>,
    ) {
        out.clear();
        scratch.clear();
        match disc {
            None => scratch.extend(
                self.slots
                    .iter()
                    .enumerate()
                    .filter_map(|(n, s)| s.as_ref().filter(|s| s.valid).map(|_| n as u32)),
            ),
            Some(disc) => {
                let b = &disc.bounds;
                let lo = [0, 1, 2].map(|a| self.coord(a, b.min[a]));
                let hi = [0, 1, 2].map(|a| self.coord(a, b.max[a]));
                for k in lo[2]..=hi[2] {
                    for j in lo[1]..=hi[1] {
                        for i in lo[0]..=hi[0] {
                            scratch.extend_from_slice(&self.cells[self.index([i, j, k])]);
                        }
                    }
                }
                if !self.bounds.contains_box(b) {
                    scratch.extend_from_slice(&self.outside);
                }
                scratch.sort_unstable();
                scratch.dedup();
            }
        }
        out.extend(
            scratch
                .iter()
                .filter_map(|&n| self.slots[n as usize].as_ref().map(|s| (s.id, n))),
        );
        if !self.monotonic {
            out.sort_unstable();
        }
    }

    /// Calls `f(slot)` once for every live slot registered in a cell that the disc box overlaps (and on the outside list when the box leaves the grid), in no particular order; `stamps` and `epoch` are the caller's per-thread mailbox, so that no list is sorted.
    pub(crate) fn for_each_unique_slot(
        &self,
        disc: &DiscEnvelope,
        stamps: &mut Vec<u32>,
        epoch: &mut u32,
        mut f: impl FnMut(u32),
    ) {
        if stamps.len() < self.slots.len() {
            stamps.resize(self.slots.len(), 0);
        }
        *epoch = epoch.wrapping_add(1);
        if *epoch == 0 {
            stamps.fill(0);
            *epoch = 1;
        }
        let e = *epoch;
        let mut visit = |n: u32| {
            let stamp = &mut stamps[n as usize];
            if *stamp != e {
                *stamp = e;
                if self.slots[n as usize].is_some() {
                    f(n);
                }
            }
        };
        let b = &disc.bounds;
        let lo = [0, 1, 2].map(|a| self.coord(a, b.min[a]));
        let hi = [0, 1, 2].map(|a| self.coord(a, b.max[a]));
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    for &n in &self.cells[self.index([i, j, k])] {
                        visit(n);
                    }
                }
            }
        }
        if !self.bounds.contains_box(b) {
            for &n in &self.outside {
                visit(n);
            }
        }
    }

    /// The id of a live slot.
    #[inline]
    pub(crate) fn slot_id(&self, slot: u32) -> u32 {
        self.slots[slot as usize]
            .as_ref()
            .map_or(u32::MAX, |s| s.id)
    }

    /// The stored envelope and segment of a live slot.
    #[inline]
    pub(crate) fn slot_data(&self, slot: u32) -> (Option<&SegmentEnvelope>, &RaySegment) {
        let s = self.slots[slot as usize]
            .as_ref()
            .expect("candidates returns live slots");
        (s.envelope.as_ref(), &s.segment)
    }

    /// Calls `f(id, segment)` for every live segment that may cross `disc` (a superset of those that do, each once, in id order) (beyond the paper: a moving disc looks only at nearby segments, section 2.5.2).
    pub fn for_each_candidate(&self, disc: &Disc, mut f: impl FnMut(u32, &RaySegment)) {
        let envelope = if check_disc(disc).is_some() {
            None
        } else {
            match disc_envelope(disc) {
                Some(e) => Some(e),
                None => return,
            }
        };
        let (mut scratch, mut out) = (Vec::new(), Vec::new());
        self.candidates(envelope.as_ref(), &mut scratch, &mut out);
        for (id, n) in out {
            f(id, self.slot_data(n).1);
        }
    }

    /// Checks the grid (beyond the paper): ids and slots agree, every live segment is registered in exactly the cells its envelope passes (once each) and on the outside list exactly when it leaves the box, no registration names a slot that does not exist.
    pub fn validate(&self) -> std::result::Result<(), InvariantError> {
        let fail = |message: String| InvariantError {
            structure: "segment grid",
            message,
        };
        for (&id, &n) in &self.by_id {
            match self.slots.get(n as usize) {
                Some(Some(s)) if s.id == id => {}
                _ => return Err(fail(format!("id {id} maps to slot {n}, which is not its"))),
            }
        }
        let live = self.slots.iter().flatten().count();
        if live != self.by_id.len() {
            return Err(fail(format!(
                "{live} live slots for {} ids",
                self.by_id.len()
            )));
        }
        let mut registered: HashMap<u32, Vec<usize>> = HashMap::new();
        for (c, cell) in self.cells.iter().enumerate() {
            for &n in cell {
                match self.slots.get(n as usize) {
                    None => return Err(fail(format!("cell {c} names slot {n}, past the slots"))),
                    Some(None) => {}
                    Some(Some(_)) => registered.entry(n).or_default().push(c),
                }
            }
        }
        let mut outside: Vec<u32> = self
            .outside
            .iter()
            .copied()
            .filter(|&n| matches!(self.slots.get(n as usize), Some(Some(_))))
            .collect();
        outside.sort_unstable();
        let mut expected_outside = Vec::new();
        for (n, slot) in self.slots.iter().enumerate() {
            let Some(slot) = slot else { continue };
            let mut expected = Vec::new();
            if let Some(e) = &slot.envelope {
                self.cells_of(e, |c| expected.push(c));
            }
            expected.sort_unstable();
            let mut got = registered.remove(&(n as u32)).unwrap_or_default();
            got.sort_unstable();
            if got != expected {
                return Err(fail(format!(
                    "segment {} is in {} cells, expected {}",
                    slot.id,
                    got.len(),
                    expected.len()
                )));
            }
            if slot.outside() {
                expected_outside.push(n as u32);
            }
        }
        if outside != expected_outside {
            return Err(fail(format!(
                "{} live segments on the outside list, expected {}",
                outside.len(),
                expected_outside.len()
            )));
        }
        Ok(())
    }
}
