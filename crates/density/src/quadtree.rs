//! The QuadTree of section 2.10.1 over the hemisphere of incoming directions of a glossy vertex, in its two modes.
//!
//! **Directions to the square.** A local direction (`z ≥ 0`) is mapped to the
//! unit square by the inverse of an equal-area map: Shirley & Chiu's
//! concentric map from the square to the unit disc, lifted to the hemisphere
//! by `z = 1 − ρ²` (Lambert's azimuthal projection). A cell of area `a` then
//! covers the solid angle `2π a`, and the four children of the root are the
//! four quarter hemispheres.
//!
//! **Shape.** A node is split into four children exactly when it holds more
//! than `capacity` rays and is shallower than `max_depth`; leaves keep their
//! rays sorted by [`IncidentRay::key`]. The shape and every stored sum are
//! therefore functions of the multiset of rays alone: any sequence of
//! insertions and removals gives the tree that [`QuadTree::from_rays`] builds
//! from scratch, bit for bit. A tree is stored as two arrays, its nodes in
//! preorder and its rays leaf after leaf, updated in place.
//!
//! **Without summarising** ([`QuadTree`]): every node stores its ray count,
//! its total power `Φ_N` and the bounding box of its rays' square
//! coordinates. The estimate `Σ_j f_r(ω_j, ωo) φ_j` descends from the root;
//! at an inner node it samples the BRDF on the node's bounding box (a 3 × 3
//! grid, plus the mirror direction of `ωo` when it falls inside), giving
//! per channel `f_lo ≤ f_hi` (only for nodes holding more rays than the
//! test's 10 evaluations). When `f_hi − f_lo ≤ τ (f_hi + f_lo)` (relative
//! half-range at most the tolerance `τ`) the node is taken as a whole,
//! `Φ_N (f_lo + f_hi)/2`, with error at most `Φ_N (f_hi − f_lo)/2 ≤ τ Φ_N (f_lo + f_hi)/2`;
//! otherwise the estimate descends, and leaves are summed ray by ray. The
//! returned bound is the sum of the accepted nodes' `Φ_N (f_hi − f_lo)/2`, and
//! the relative error is at most `τ`. Both hold when the BRDF over a node's
//! box stays within the range of its samples: true when the box is small
//! against the BRDF's lobes (the samples bracket a monotone variation, and
//! mirror sample catches a specular peak), not guaranteed for a narrow
//! feature that falls between samples of a large box. So a node whose box,
//! grown by its own size on every side, holds the mirror direction of `ωo` is
//! never taken whole: without that rule the glosbox floor's α = 0.05 lobe,
//! peaking just outside a node, put an error 20 times the bound into one
//! test case. With it, in the tests (glosbox floor, a Phong lobe), the error
//! never exceeds the bound by more than 10⁻⁷ of the value. With `τ = 0` no node is taken whole and the
//! estimate is the per-ray sum (up to the order of the `f64` summation).
//! Measured on 1983 rays of a glosbox floor disc (capacity 8, BRDF
//! evaluations against 1983 for the list): away from the glossy lobes 116
//! (relative error 10⁻⁷); looking down the lobe of the light 1304, 847 and
//! 714 at `τ` = 0.01, 0.05, 0.2 (errors 1.3·10⁻⁴, 4.3·10⁻³, 8.6·10⁻³).
//!
//! **With summarising** ([`SummaryTree`], section 2.10.1, which the paper did
//! not implement): the tree of the first frame is frozen and each leaf's `n`
//! rays become one [`Summary`], the mean direction `R = Σ R_i / n`, the count
//! `n` and the total power. A frame with `n_n` New Rays `N_i` and `n_o` Old
//! Rays `O_i` in a leaf updates it with the paper's
//! `R_new = (R + Σ N_i / n − Σ O_i / n) · n / (n + n_n − n_o)`, which keeps `R`
//! the exact mean of the leaf's current rays. The estimate is
//! `Σ_leaves f_r(R̂, ωo) Φ_leaf`, `R̂ = R / |R|`; its error is at most
//! `Σ_leaves Φ_leaf (sup f_r − inf f_r)` over the leaf's cell, which
//! [`SummaryTree::error_bound`] samples. Since the mean stays exact, removals
//! lose nothing; what is lost is the shape: the estimate degrades, as the
//! paper predicts for directions far from the means, when New Rays arrive in
//! cells that were sparse, hence large, in the frozen first-frame tree, which
//! a rebuild would split. The degradation stays within that bound, and can
//! be watched at run time by comparing [`SummaryTree::error_bound`] with the
//! estimate (to rebuild the summaries from the current ray set when it grows);
//! [`summary_degradation`] measures it against the exact per-ray sum.

use std::fmt;

use glam::{DVec3, Vec2, Vec3};
use lustre_brdf::Brdf;
use lustre_geometry::Rgb;
use lustre_geometry::sampling::sample_concentric_disk;

use crate::error::{DensityError, Result};
use crate::glossy::{Estimate, IncidentRay, RayKey, RayList, key_order, ray_difference};

/// Deepest tree allowed: cells of `2⁻²⁰` of the square's side.
pub const MAX_DEPTH: u32 = 20;

/// Samples per axis of the BRDF on a node's box (section 2.10.1 acceleration rule).
const GRID: usize = 3;

/// Samples are kept this far inside the square so that none falls on the horizon, where reflection-only BRDFs are zero.
const INSET: f32 = 1e-3;

/// The equal-area map from the unit square to the hemisphere `z ≥ 0` (section 2.10.1 QuadTree domain): Shirley–Chiu concentric disc, lifted by `z = 1 − ρ²`; a cell of area `a` covers the solid angle `2π a`.
pub fn square_to_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u.clamp(Vec2::ZERO, Vec2::ONE));
    let r2 = d.length_squared().min(1.0);
    let s = (2.0 - r2).sqrt();
    Vec3::new(d.x * s, d.y * s, 1.0 - r2)
}

/// The inverse of [`square_to_hemisphere`] (section 2.10.1 QuadTree domain); directions below the horizon are clamped to it.
pub fn hemisphere_to_square(w: Vec3) -> Vec2 {
    let w = w.normalize_or_zero();
    let xy = Vec2::new(w.x, w.y);
    let len = xy.length();
    if !(len > 0.0) {
        return Vec2::splat(0.5);
    }
    let rho = (1.0 - w.z.clamp(0.0, 1.0)).sqrt();
    let d = xy * (rho / len);
    let o = if d.x.abs() >= d.y.abs() {
        let ox = rho.copysign(d.x);
        Vec2::new(ox, ox * (d.y / d.x).atan() / std::f32::consts::FRAC_PI_4)
    } else {
        let oy = rho.copysign(d.y);
        Vec2::new(oy * (d.x / d.y).atan() / std::f32::consts::FRAC_PI_4, oy)
    };
    ((o + Vec2::ONE) * 0.5).clamp(Vec2::ZERO, Vec2::ONE)
}

/// Shape of a QuadTree (section 2.10.1): a node with more than `capacity` rays is split, down to `max_depth`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QuadTreeOptions {
    /// Most rays a leaf keeps before it splits (a summarised leaf's rays at the first frame), at least 1.
    pub capacity: usize,
    /// Deepest level, at most [`MAX_DEPTH`].
    pub max_depth: u32,
}

impl Default for QuadTreeOptions {
    fn default() -> Self {
        Self {
            capacity: 8,
            max_depth: 12,
        }
    }
}

impl QuadTreeOptions {
    /// Checks `capacity ≥ 1` and `max_depth ≤ MAX_DEPTH`.
    pub fn validate(&self) -> Result<()> {
        if self.capacity == 0 {
            return Err(DensityError::InvalidOption {
                option: "capacity",
                message: "a QuadTree leaf holds at least one ray".into(),
            });
        }
        if self.max_depth > MAX_DEPTH {
            return Err(DensityError::InvalidOption {
                option: "max_depth",
                message: format!("{} is deeper than {MAX_DEPTH}", self.max_depth),
            });
        }
        Ok(())
    }
}

/// A cell of the square: level and integer coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Cell {
    depth: u32,
    x: u32,
    y: u32,
}

impl Cell {
    const ROOT: Self = Self {
        depth: 0,
        x: 0,
        y: 0,
    };

    /// Child `i` (`bit x + 2 bit y`).
    fn child(self, i: usize) -> Self {
        Self {
            depth: self.depth + 1,
            x: 2 * self.x + (i as u32 & 1),
            y: 2 * self.y + (i as u32 >> 1),
        }
    }

    /// Which child holds `uv` (exact: scaling by a power of two does not round).
    fn child_of(self, uv: Vec2) -> usize {
        let n = 1u64 << (self.depth + 1);
        let ix = ((uv.x as f64 * n as f64) as u64).min(n - 1);
        let iy = ((uv.y as f64 * n as f64) as u64).min(n - 1);
        let bx = ix.saturating_sub(2 * self.x as u64).min(1) as usize;
        let by = iy.saturating_sub(2 * self.y as u64).min(1) as usize;
        bx + 2 * by
    }

    /// [`Cell::child_of`] for the point whose [`deepest_cell`] is `deepest`: the same child, read from the point's bits at this level.
    fn child_toward(self, deepest: (u32, u32)) -> usize {
        let shift = MAX_DEPTH - 1 - self.depth;
        (((deepest.0 >> shift) & 1) + 2 * ((deepest.1 >> shift) & 1)) as usize
    }

    /// Corners of the cell in the square.
    fn bounds(self) -> (Vec2, Vec2) {
        let s = 1.0 / (1u64 << self.depth) as f32;
        let lo = Vec2::new(self.x as f32, self.y as f32) * s;
        (lo, lo + Vec2::splat(s))
    }

    /// Whether `uv` belongs to the cell, by the same descent [`Cell::child_of`] makes.
    fn contains(self, uv: Vec2) -> bool {
        let mut c = Self::ROOT;
        while c.depth < self.depth {
            c = c.child(c.child_of(uv));
        }
        c == self
    }
}

/// The integer coordinates of the cell of depth [`MAX_DEPTH`] that holds `uv` (in the unit square). Shifted right by `MAX_DEPTH − d`, they are the cell of depth `d` that [`Cell::child_of`]'s descent reaches: `uv` is scaled by a power of two exactly, the floor of a floor divided by a power of two is the floor of the point scaled by it, and the side `1` is clamped into the last cell as there.
fn deepest_cell(uv: Vec2) -> (u32, u32) {
    let n = 1u64 << MAX_DEPTH;
    let at = |x: f32| ((x as f64 * n as f64) as u64).min(n - 1) as u32;
    (at(uv.x), at(uv.y))
}

/// A ray in the tree with its square coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    ray: IncidentRay,
    uv: Vec2,
}

impl Entry {
    fn new(ray: IncidentRay) -> Self {
        Self {
            ray,
            uv: hemisphere_to_square(ray.wi),
        }
    }

    fn key(&self) -> RayKey {
        self.ray.key()
    }
}

/// A node of a [`QuadTree`]: ray count, total power, bounding box of its rays' square coordinates, and how many nodes its subtree has (one: a leaf). A tree keeps its nodes in preorder in one array (each inner node followed by its four children's subtrees, in child order) and its rays in another, leaf after leaf in that order, each leaf's by key, so that a subtree's rays are one run of it, found by adding the counts of the subtrees before it.
///
/// Why two arrays per tree rather than boxed children and a vector per leaf (the layout until 2026-12-08): a frame's update touches a few leaves of each of thousands of trees, and in the boxed tree every level of every descent and every leaf was a cache miss of its own, one after the other, and every split or merge an allocation. Here a tree is two runs of memory that the update first reads in order ([`QuadTree::touch`]), that the estimate reads in order, and that splits and merges edit in place; a ray costs fewer bytes. Measured (BENCHMARKS.md, dense glossy): updates of cold trees in 0.58 of the time, the glossy radiance of the dense glossy bench in about three quarters, its peak memory 14 % lower, and its whole frame update within the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    power: DVec3,
    lo: Vec2,
    hi: Vec2,
    count: u32,
    size: u32,
}

impl Node {
    /// A leaf over `entries`, its sums in their order.
    fn leaf(entries: &[Entry]) -> Self {
        let (mut power, mut lo, mut hi) = (DVec3::ZERO, Vec2::INFINITY, Vec2::NEG_INFINITY);
        for e in entries {
            power += e.ray.power.as_dvec3();
            lo = lo.min(e.uv);
            hi = hi.max(e.uv);
        }
        Self {
            power,
            lo,
            hi,
            count: entries.len() as u32,
            size: 1,
        }
    }

    /// Whether the node is a leaf.
    fn is_leaf(&self) -> bool {
        self.size == 1
    }
}

/// The preorder indices of the four children of the inner node at `i`.
#[inline]
fn children(nodes: &[Node], i: usize) -> [usize; 4] {
    let c0 = i + 1;
    let c1 = c0 + nodes[c0].size as usize;
    let c2 = c1 + nodes[c1].size as usize;
    [c0, c1, c2, c2 + nodes[c2].size as usize]
}

/// Where the rays of an inner node's four children start, given where the node's rays start and each child's ray count.
fn child_starts(start: usize, counts: [usize; 4]) -> [usize; 4] {
    let mut at = start;
    counts.map(|n| {
        let s = at;
        at += n;
        s
    })
}

/// Sets the inner node at `at` from its four children, which follow it in `nodes`: counts, powers and boxes added in child order.
fn close_inner(nodes: &mut [Node], at: usize) {
    let (mut count, mut power, mut lo, mut hi) =
        (0, DVec3::ZERO, Vec2::INFINITY, Vec2::NEG_INFINITY);
    let mut size = 1;
    for c in children(nodes, at) {
        let n = &nodes[c];
        count += n.count;
        power += n.power;
        lo = lo.min(n.lo);
        hi = hi.max(n.hi);
        size += n.size;
    }
    nodes[at] = Node {
        power,
        lo,
        hi,
        count,
        size,
    };
}

/// Appends to `nodes` and `rays` the subtree of `cell` over `entries` (in any order), by the canonical shape rule: a leaf while it holds at most `capacity` rays or lies at `max_depth`, else four children by quadrant; each leaf's rays in key order. The rays are partitioned among the children level by level through `scratch` (as long as `entries`) and copied once, into the leaf's run of `rays`, sorted there.
fn build(
    entries: &mut [Entry],
    scratch: &mut [Entry],
    cell: Cell,
    options: &QuadTreeOptions,
    nodes: &mut Vec<Node>,
    rays: &mut Vec<Entry>,
) {
    if entries.len() <= options.capacity || cell.depth >= options.max_depth {
        // Stable: rays with equal keys keep their order, as in a sorted leaf split.
        entries.sort_by(|a, b| key_order(&a.ray, &b.ray));
        rays.extend_from_slice(entries);
        nodes.push(Node::leaf(entries));
        return;
    }
    let mut counts = [0usize; 4];
    for e in entries.iter() {
        counts[cell.child_of(e.uv)] += 1;
    }
    let mut next = [
        0,
        counts[0],
        counts[0] + counts[1],
        counts[0] + counts[1] + counts[2],
    ];
    for e in entries.iter() {
        let i = cell.child_of(e.uv);
        scratch[next[i]] = *e;
        next[i] += 1;
    }
    let at = nodes.len();
    nodes.push(Node::leaf(&[]));
    // Each child's rays are now a run of `scratch`; `entries` is their scratch.
    let (mut own, mut spare) = (scratch, entries);
    for (i, n) in counts.into_iter().enumerate() {
        let (mine, rest) = std::mem::take(&mut own).split_at_mut(n);
        let (mine_spare, rest_spare) = std::mem::take(&mut spare).split_at_mut(n);
        (own, spare) = (rest, rest_spare);
        build(mine, mine_spare, cell.child(i), options, nodes, rays);
    }
    close_inner(nodes, at);
}

/// Per thread, the buffers of [`QuadTree::update`], reused from tree to tree.
#[derive(Default)]
struct Scratch {
    /// Per ray of the tree before the update: removed by it.
    removed: Vec<bool>,
    /// Per node before the update: an Old or New Ray descended through it.
    touched: Vec<bool>,
    /// Per node before the update: its ray count after it (touched nodes only; per leaf, first the rays inserted minus those removed).
    count: Vec<i64>,
    /// The New Rays: where each goes in the ray array before the update (before the ray there), its leaf, the ray.
    inserted: Vec<(u32, u32, Entry)>,
    /// The rays from the first one the update changes to the end, before it.
    tail: Vec<Entry>,
    /// A leaf to split: its rays, their partition buffer, and the subtree built.
    split: Vec<Entry>,
    spare: Vec<Entry>,
    nodes: Vec<Node>,
    rays: Vec<Entry>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default();
}

/// Whether the mirror direction of `wo` (a glossy lobe's peak) maps into the box of the square grown by its own size on every side: such a node is never taken as a whole, since a narrow peak just outside its samples can still reach into it.
fn near_peak(wo: Vec3, lo: Vec2, hi: Vec2) -> bool {
    if !(wo.z > 0.0) {
        return false;
    }
    let m = hemisphere_to_square(Vec3::new(-wo.x, -wo.y, wo.z));
    let pad = hi - lo;
    m.cmpge(lo - pad).all() && m.cmple(hi + pad).all()
}

/// Sampled range of a BRDF over a box of the square (the acceleration rule of section 2.10.1 in this module's docs): a `GRID × GRID` grid, the mirror direction of `wo` when inside, and `extra` points; returns the per-channel minimum, maximum and the number of evaluations, or `None` if a value is not finite.
fn sampled_range(
    brdf: &dyn Brdf,
    wo: Vec3,
    lo: Vec2,
    hi: Vec2,
    grid: usize,
    extra: &[Vec3],
) -> Option<(DVec3, DVec3, usize)> {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut evaluations = 0;
    let mut add = |w: Vec3| -> bool {
        let f = brdf.eval(w, wo);
        evaluations += 1;
        if !f.is_finite() {
            return false;
        }
        min = min.min(f.as_dvec3());
        max = max.max(f.as_dvec3());
        true
    };
    let steps = grid.max(2) - 1;
    for j in 0..=steps {
        for i in 0..=steps {
            let t = Vec2::new(i as f32, j as f32) / steps as f32;
            let u = (lo + (hi - lo) * t).clamp(Vec2::splat(INSET), Vec2::splat(1.0 - INSET));
            if !add(square_to_hemisphere(u)) {
                return None;
            }
        }
    }
    if wo.z > 0.0 {
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        let m = hemisphere_to_square(mirror);
        if m.cmpge(lo).all() && m.cmple(hi).all() && !add(mirror) {
            return None;
        }
    }
    for &w in extra {
        if !add(w) {
            return None;
        }
    }
    Some((min, max, evaluations))
}

/// The QuadTree "without summarizing" of section 2.10.1: every ray kept, exact insertion and removal, and a faster estimate (rule and bound in the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadTree {
    options: QuadTreeOptions,
    /// The nodes in preorder, the root first ([`Node`]).
    nodes: Vec<Node>,
    /// The rays, leaf after leaf in preorder, each leaf's by key.
    rays: Vec<Entry>,
}

impl QuadTree {
    /// An empty tree; fails on invalid options.
    pub fn new(options: QuadTreeOptions) -> Result<Self> {
        Self::from_rays(options, &[])
    }

    /// The tree of a set of rays, built from scratch (section 2.10.1); fails on invalid options or more than `u32::MAX` rays.
    pub fn from_rays(options: QuadTreeOptions, rays: &[IncidentRay]) -> Result<Self> {
        options.validate()?;
        check_size(rays.len())?;
        let mut entries: Vec<Entry> = rays.iter().map(|&r| Entry::new(r)).collect();
        let mut scratch = entries.clone();
        let (mut nodes, mut sorted) = (Vec::new(), Vec::with_capacity(entries.len()));
        build(
            &mut entries,
            &mut scratch,
            Cell::ROOT,
            &options,
            &mut nodes,
            &mut sorted,
        );
        Ok(Self {
            options,
            nodes,
            rays: sorted,
        })
    }

    /// The tree's shape options.
    pub fn options(&self) -> QuadTreeOptions {
        self.options
    }

    /// Adds a New Ray (section 2.10.1, "rays can be added").
    pub fn insert(&mut self, ray: IncidentRay) {
        self.update(&[], &[ray]);
    }

    /// Removes one copy of an Old Ray (section 2.10.1, "and removed"); `false` when it is not in the tree.
    pub fn remove(&mut self, ray: &IncidentRay) -> bool {
        self.update(std::slice::from_ref(ray), &[]) == 0
    }

    /// Reads a word of every cache line of the tree, in order, before the descents: the reads do not wait on one another and the hardware prefetcher streams the lines in, where the descents would wait for one line after another (an update of a cold tree in about 0.6 of the time without, BENCHMARKS.md).
    fn touch(&self) {
        let mut seen = 0u32;
        for n in &self.nodes {
            seen ^= n.size;
        }
        for e in self.rays.iter().step_by(2) {
            seen ^= e.ray.wi.x.to_bits();
        }
        std::hint::black_box(seen);
    }

    /// The leaf that a ray at `uv` belongs to and where its rays start, marking the nodes on the way as touched.
    fn descend(&self, uv: Vec2, touched: &mut [bool]) -> (usize, usize) {
        let deepest = deepest_cell(uv);
        let (mut i, mut start, mut cell) = (0, 0, Cell::ROOT);
        loop {
            touched[i] = true;
            if self.nodes[i].is_leaf() {
                return (i, start);
            }
            let k = cell.child_toward(deepest);
            i += 1;
            for _ in 0..k {
                start += self.nodes[i].count as usize;
                i += self.nodes[i].size as usize;
            }
            cell = cell.child(k);
        }
    }

    /// A frame's update (section 2.10.1): removes one copy of each Old Ray, then inserts the New Rays, and returns how many Old Rays were not in the tree. The tree equals the one [`QuadTree::remove`] and [`QuadTree::insert`] make one ray at a time and the one [`QuadTree::from_rays`] builds, bit for bit. Each ray first finds its leaf; the ray array is then rewritten from the first change on, and only the touched nodes are restored, each to the shape its new count asks for (a leaf that a removal empties below the capacity and an insertion refills is not merged and split again).
    pub fn update(&mut self, old: &[IncidentRay], new: &[IncidentRay]) -> usize {
        if old.is_empty() && new.is_empty() {
            return 0;
        }
        SCRATCH.with_borrow_mut(|s| {
            self.touch();
            let n = self.nodes.len();
            s.removed.clear();
            s.removed.resize(self.rays.len(), false);
            s.touched.clear();
            s.touched.resize(n, false);
            s.count.clear();
            s.count.resize(n, 0);
            s.inserted.clear();
            let mut missing = 0;
            for ray in old {
                let e = Entry::new(*ray);
                let (leaf, start) = self.descend(e.uv, &mut s.touched);
                let end = start + self.nodes[leaf].count as usize;
                let key = e.key();
                let first = start + self.rays[start..end].partition_point(|r| r.key() < key);
                let copy = (first..end)
                    .take_while(|&k| self.rays[k].key() == key)
                    .find(|&k| !s.removed[k]);
                match copy {
                    Some(k) => {
                        s.removed[k] = true;
                        s.count[leaf] -= 1;
                    }
                    None => missing += 1,
                }
            }
            for ray in new {
                let e = Entry::new(*ray);
                let (leaf, start) = self.descend(e.uv, &mut s.touched);
                let end = start + self.nodes[leaf].count as usize;
                let key = e.key();
                // After the rays with its key, as one insertion at a time puts it.
                let at = start + self.rays[start..end].partition_point(|r| r.key() <= key);
                s.count[leaf] += 1;
                s.inserted.push((at as u32, leaf as u32, e));
            }
            // By place, then leaf (an empty leaf's place is the next leaf's), then key; stable, so that equal New Rays keep their order (they are the same ray).
            s.inserted.sort_by(|a, b| {
                (a.0, a.1)
                    .cmp(&(b.0, b.1))
                    .then_with(|| key_order(&a.2.ray, &b.2.ray))
            });
            // Children follow their parent in preorder, so backwards each count is ready before its parent's.
            for i in (0..n).rev() {
                if s.touched[i] {
                    let node = &self.nodes[i];
                    s.count[i] = if node.is_leaf() {
                        node.count as i64 + s.count[i]
                    } else {
                        children(&self.nodes, i)
                            .iter()
                            .map(|&c| self.count_after(s, c) as i64)
                            .sum()
                    };
                }
            }
            self.splice_rays(s);
            self.restore(0, Cell::ROOT, 0, s);
            missing
        })
    }

    /// A node's ray count after the update (its index from before it).
    fn count_after(&self, s: &Scratch, i: usize) -> usize {
        if s.touched[i] {
            s.count[i] as usize
        } else {
            self.nodes[i].count as usize
        }
    }

    /// Rewrites the ray array from the first ray the update removes or inserts before: the removed rays left out, the New Rays put in their places.
    fn splice_rays(&mut self, s: &mut Scratch) {
        let first_removed = s.removed.iter().position(|&r| r);
        let first_inserted = s.inserted.first().map(|&(at, _, _)| at as usize);
        let Some(first) = first_removed.into_iter().chain(first_inserted).min() else {
            return;
        };
        s.tail.clear();
        s.tail.extend_from_slice(&self.rays[first..]);
        self.rays.truncate(first);
        let mut inserted = s.inserted.iter().peekable();
        for (k, e) in (first..).zip(&s.tail) {
            while let Some(&(_, _, new)) = inserted.next_if(|&&(at, _, _)| at as usize == k) {
                self.rays.push(new);
            }
            if !s.removed[k] {
                self.rays.push(*e);
            }
        }
        self.rays.extend(inserted.map(|&(_, _, new)| new));
    }

    /// Restores the touched subtree at `i` (an index from before the update; its cell and where its rays start after it) with the update's rays: counts, sums and the canonical shape. Children are restored last first, so that a subtree whose node count changes moves only nodes already restored, and the indices from before the update still hold for what is left to do.
    fn restore(&mut self, i: usize, cell: Cell, start: usize, s: &mut Scratch) {
        if !s.touched[i] {
            return;
        }
        let count = s.count[i] as usize;
        let node = self.nodes[i];
        let end = start + count;
        if count <= self.options.capacity || cell.depth >= self.options.max_depth {
            if !node.is_leaf() {
                // An inner node with few enough rays becomes one leaf: its leaves' runs, sorted together.
                self.rays[start..end].sort_by(|a, b| key_order(&a.ray, &b.ray));
                self.nodes
                    .splice(i..i + node.size as usize, [Node::leaf(&[])]);
            }
            self.nodes[i] = Node::leaf(&self.rays[start..end]);
        } else if node.is_leaf() {
            // A leaf with too many rays becomes the subtree that [`build`] makes of them.
            s.split.clear();
            s.split.extend_from_slice(&self.rays[start..end]);
            s.spare.clear();
            s.spare.extend_from_slice(&s.split);
            s.nodes.clear();
            s.rays.clear();
            build(
                &mut s.split,
                &mut s.spare,
                cell,
                &self.options,
                &mut s.nodes,
                &mut s.rays,
            );
            self.rays[start..end].copy_from_slice(&s.rays);
            self.nodes.splice(i..i + 1, s.nodes.iter().copied());
        } else {
            let kids = children(&self.nodes, i);
            let starts = child_starts(start, kids.map(|c| self.count_after(s, c)));
            for k in (0..4).rev() {
                self.restore(kids[k], cell.child(k), starts[k], s);
            }
            close_inner(&mut self.nodes, i);
        }
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.nodes[0].count as usize
    }

    /// Whether the tree holds no ray.
    pub fn is_empty(&self) -> bool {
        self.nodes[0].count == 0
    }

    /// Total power of the rays.
    pub fn power(&self) -> Rgb {
        self.nodes[0].power.as_vec3()
    }

    /// Every ray, leaf by leaf.
    pub fn rays(&self) -> Vec<IncidentRay> {
        self.rays.iter().map(|e| e.ray).collect()
    }

    /// Number of leaves.
    pub fn leaves(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Depth of the deepest leaf.
    pub fn depth(&self) -> u32 {
        fn below(nodes: &[Node], i: usize) -> u32 {
            if nodes[i].is_leaf() {
                return 0;
            }
            let deepest = children(nodes, i).map(|c| below(nodes, c));
            1 + deepest.into_iter().max().unwrap_or(0)
        }
        below(&self.nodes, 0)
    }

    /// `Σ_j f_r(ω_j, ωo) φ_j` (equation 2.1 before the division by the disc area), `wo` local; a node is evaluated as a whole when the BRDF's sampled relative half-range over its rays' box is at most `tolerance`, with the error bound of the module docs; `tolerance = 0` (or not positive) sums ray by ray.
    pub fn estimate(&self, brdf: &dyn Brdf, wo: Vec3, tolerance: f32) -> Estimate {
        let mut acc = Accumulator::default();
        self.visit(0, 0, brdf, wo, tolerance as f64, &mut acc);
        Estimate {
            value: acc.value.as_vec3(),
            bound: acc.bound.as_vec3(),
            evaluations: acc.evaluations,
        }
    }

    /// Adds the part of the estimate of the node at `i` (its rays from `start`): as a whole when the test of the module docs accepts it, else its children or its rays.
    fn visit(
        &self,
        i: usize,
        start: usize,
        brdf: &dyn Brdf,
        wo: Vec3,
        tolerance: f64,
        acc: &mut Accumulator,
    ) {
        let node = &self.nodes[i];
        if node.count == 0 {
            return;
        }
        if node.is_leaf() {
            let entries = &self.rays[start..start + node.count as usize];
            for e in entries {
                acc.value += e.ray.term(brdf, wo).as_dvec3();
            }
            acc.evaluations += entries.len();
            return;
        }
        // A node with no more rays than the samples the test costs is summed ray by ray.
        if tolerance > 0.0
            && node.count as usize > GRID * GRID + 1
            && !near_peak(wo, node.lo, node.hi)
        {
            if let Some((lo, hi, n)) = sampled_range(brdf, wo, node.lo, node.hi, GRID, &[]) {
                acc.evaluations += n;
                if (hi - lo).cmple((hi + lo) * tolerance).all() {
                    acc.value += node.power * (hi + lo) * 0.5;
                    acc.bound += node.power * (hi - lo) * 0.5;
                    return;
                }
            }
        }
        let kids = children(&self.nodes, i);
        let starts = child_starts(start, kids.map(|c| self.nodes[c].count as usize));
        for (c, at) in kids.into_iter().zip(starts) {
            self.visit(c, at, brdf, wo, tolerance, acc);
        }
    }

    /// Checks the invariants: the nodes in preorder with their subtrees' sizes, stored counts, powers and boxes equal to their recomputation, the canonical shape rule, sorted leaves, every ray in the cell its direction maps to, every ray in a leaf.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let end = self.check(0, Cell::ROOT, 0)?;
        if end != self.nodes.len() {
            return Err(format!(
                "{} nodes stored, {end} in the tree",
                self.nodes.len()
            ));
        }
        if self.nodes[0].count as usize != self.rays.len() {
            return Err(format!(
                "{} rays stored, {} in the tree",
                self.rays.len(),
                self.nodes[0].count
            ));
        }
        Ok(())
    }

    /// Checks the subtree at `i` of `cell`, whose rays start at `start`; returns the index after it.
    fn check(&self, i: usize, cell: Cell, start: usize) -> std::result::Result<usize, String> {
        let node = *self
            .nodes
            .get(i)
            .ok_or_else(|| format!("cell {cell:?}: node {i} missing"))?;
        let should_split =
            node.count as usize > self.options.capacity && cell.depth < self.options.max_depth;
        let recomputed = if node.is_leaf() {
            let entries = self
                .rays
                .get(start..start + node.count as usize)
                .ok_or_else(|| format!("cell {cell:?}: rays past the end"))?;
            if should_split {
                return Err(format!(
                    "cell {cell:?}: leaf with {} rays should be split",
                    node.count
                ));
            }
            if entries.windows(2).any(|w| w[0].key() > w[1].key()) {
                return Err(format!("cell {cell:?}: rays not sorted by key"));
            }
            for e in entries {
                if e.uv != hemisphere_to_square(e.ray.wi) || !cell.contains(e.uv) {
                    return Err(format!(
                        "cell {cell:?}: ray {:?} at {} does not belong here",
                        e.ray, e.uv
                    ));
                }
            }
            Node::leaf(entries)
        } else {
            if !should_split {
                return Err(format!(
                    "cell {cell:?}: inner node with {} rays should be a leaf",
                    node.count
                ));
            }
            let mut sub = vec![node];
            let (mut next, mut at) = (i + 1, start);
            for k in 0..4 {
                let end = self.check(next, cell.child(k), at)?;
                at += self.nodes[next].count as usize;
                sub.extend_from_slice(&self.nodes[next..end]);
                next = end;
            }
            close_inner(&mut sub, 0);
            sub[0]
        };
        if recomputed.count != node.count || recomputed.power != node.power {
            return Err(format!(
                "cell {cell:?}: stored count {} and power {} differ from the recomputed {} and {}",
                node.count, node.power, recomputed.count, recomputed.power
            ));
        }
        if recomputed.lo != node.lo || recomputed.hi != node.hi {
            return Err(format!("cell {cell:?}: stale bounding box"));
        }
        if recomputed.size != node.size {
            return Err(format!(
                "cell {cell:?}: a subtree of {} nodes stored as {}",
                recomputed.size, node.size
            ));
        }
        Ok(i + node.size as usize)
    }
}

/// Fails when a tree would hold more rays than its `u32` counts can.
fn check_size(rays: usize) -> Result<()> {
    if u32::try_from(rays).is_err() {
        return Err(DensityError::InvalidOption {
            option: "rays",
            message: format!("{rays} rays are more than a QuadTree holds"),
        });
    }
    Ok(())
}

#[derive(Default)]
struct Accumulator {
    value: DVec3,
    bound: DVec3,
    evaluations: usize,
}

/// One summarised ray of section 2.10.1: the mean `R = Σ R_i / n` of `n` unit directions, `n`, and the total power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// The mean direction `R` (not normalised), local frame.
    pub mean: DVec3,
    /// The number `n` of rays it stands for.
    pub count: u64,
    /// Their total power.
    pub power: DVec3,
}

impl Summary {
    /// The summary of no ray.
    pub const EMPTY: Self = Self {
        mean: DVec3::ZERO,
        count: 0,
        power: DVec3::ZERO,
    };

    /// The summary of a set of rays (section 2.10.1): `R = Σ R_i / n`.
    pub fn of(rays: &[IncidentRay]) -> Self {
        if rays.is_empty() {
            return Self::EMPTY;
        }
        let n = rays.len() as u64;
        Self {
            mean: rays.iter().map(|r| r.wi.as_dvec3()).sum::<DVec3>() / n as f64,
            count: n,
            power: rays.iter().map(|r| r.power.as_dvec3()).sum(),
        }
    }

    /// The direction the summary is evaluated in, `R / |R|`; `None` when empty.
    pub fn direction(&self) -> Option<Vec3> {
        (self.count > 0)
            .then(|| self.mean.normalize_or_zero().as_vec3())
            .filter(|d| *d != Vec3::ZERO)
    }

    /// One frame's update (section 2.10.1): `R_new = (R + Σ N_i / n − Σ O_i / n) · n / (n + n_n − n_o)`, count `n + n_n − n_o`, power plus the new minus the old. With `n = 0` it is `(Σ N_i − Σ O_i) / (n_n − n_o)`, the formula multiplied through by `n`; a summary left with no ray is [`Summary::EMPTY`]. Fails when `n_o > n + n_n`.
    pub fn updated(&self, new: &[IncidentRay], old: &[IncidentRay]) -> Result<Self> {
        let (n, nn, no) = (self.count, new.len() as u64, old.len() as u64);
        let Some(total) = (n + nn).checked_sub(no) else {
            return Err(DensityError::InvalidOption {
                option: "old",
                message: format!("{no} Old Rays leave a summary of {n} rays given {nn} New Rays"),
            });
        };
        if total == 0 {
            return Ok(Self::EMPTY);
        }
        let sum_new: DVec3 = new.iter().map(|r| r.wi.as_dvec3()).sum();
        let sum_old: DVec3 = old.iter().map(|r| r.wi.as_dvec3()).sum();
        let mean = if n == 0 {
            (sum_new - sum_old) / total as f64
        } else {
            let nf = n as f64;
            (self.mean + sum_new / nf - sum_old / nf) * (nf / total as f64)
        };
        let power = self.power + new.iter().map(|r| r.power.as_dvec3()).sum::<DVec3>()
            - old.iter().map(|r| r.power.as_dvec3()).sum::<DVec3>();
        Ok(Self {
            mean,
            count: total,
            power,
        })
    }
}

#[derive(Debug, Clone, PartialEq)]
enum SNode {
    Leaf(Summary),
    Inner(Box<[SNode; 4]>),
}

impl SNode {
    /// The summaries of the leaves of `tree` below its node at `i` (its rays from `start`), in the same shape.
    fn from_tree(tree: &QuadTree, i: usize, start: usize) -> Self {
        let node = &tree.nodes[i];
        if node.is_leaf() {
            let rays: Vec<IncidentRay> = tree.rays[start..start + node.count as usize]
                .iter()
                .map(|e| e.ray)
                .collect();
            return Self::Leaf(Summary::of(&rays));
        }
        let kids = children(&tree.nodes, i);
        let starts = child_starts(start, kids.map(|c| tree.nodes[c].count as usize));
        Self::Inner(Box::new(
            [0, 1, 2, 3].map(|k| Self::from_tree(tree, kids[k], starts[k])),
        ))
    }

    fn update(&mut self, cell: Cell, old: Vec<Entry>, new: Vec<Entry>) -> Result<()> {
        if old.is_empty() && new.is_empty() {
            return Ok(());
        }
        match self {
            Self::Leaf(s) => {
                let old: Vec<IncidentRay> = old.iter().map(|e| e.ray).collect();
                let new: Vec<IncidentRay> = new.iter().map(|e| e.ray).collect();
                *s = s.updated(&new, &old)?;
                Ok(())
            }
            Self::Inner(children) => {
                let mut olds: [Vec<Entry>; 4] = Default::default();
                let mut news: [Vec<Entry>; 4] = Default::default();
                for e in old {
                    olds[cell.child_of(e.uv)].push(e);
                }
                for e in new {
                    news[cell.child_of(e.uv)].push(e);
                }
                for (i, (o, n)) in olds.into_iter().zip(news).enumerate() {
                    children[i].update(cell.child(i), o, n)?;
                }
                Ok(())
            }
        }
    }

    fn for_each_leaf(&self, cell: Cell, f: &mut impl FnMut(Cell, &Summary)) {
        match self {
            Self::Leaf(s) => f(cell, s),
            Self::Inner(children) => {
                for (i, c) in children.iter().enumerate() {
                    c.for_each_leaf(cell.child(i), f);
                }
            }
        }
    }
}

/// The QuadTree "with summarizing" of section 2.10.1 (not implemented in the paper): the first frame's tree, frozen, one [`Summary`] per leaf, updated every frame with the paper's formula.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryTree {
    options: QuadTreeOptions,
    root: SNode,
}

impl SummaryTree {
    /// Builds the exact tree of the rays with `options` and summarises each leaf (section 2.10.1: "when the QuadTree summarizes a node"); fails on invalid options.
    pub fn from_rays(options: QuadTreeOptions, rays: &[IncidentRay]) -> Result<Self> {
        let tree = QuadTree::from_rays(options, rays)?;
        Ok(Self {
            options,
            root: SNode::from_tree(&tree, 0, 0),
        })
    }

    /// The shape options of the first frame's tree.
    pub fn options(&self) -> QuadTreeOptions {
        self.options
    }

    /// One frame (section 2.10.1): each leaf receives the New and Old Rays whose directions fall in its cell and applies [`Summary::updated`]. Fails, leaving the tree unchanged, when a leaf would lose more rays than it holds.
    pub fn update(&mut self, old: &[IncidentRay], new: &[IncidentRay]) -> Result<()> {
        let mut root = self.root.clone();
        root.update(
            Cell::ROOT,
            old.iter().map(|&r| Entry::new(r)).collect(),
            new.iter().map(|&r| Entry::new(r)).collect(),
        )?;
        self.root = root;
        Ok(())
    }

    /// The leaves' summaries, in tree order.
    pub fn summaries(&self) -> Vec<Summary> {
        let mut out = Vec::new();
        self.root
            .for_each_leaf(Cell::ROOT, &mut |_, s| out.push(*s));
        out
    }

    /// Number of rays the summaries stand for.
    pub fn len(&self) -> u64 {
        self.summaries().iter().map(|s| s.count).sum()
    }

    /// Whether the summaries stand for no ray.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Total power of the summaries.
    pub fn power(&self) -> Rgb {
        self.summaries()
            .iter()
            .map(|s| s.power)
            .sum::<DVec3>()
            .as_vec3()
    }

    /// `Σ_leaves f_r(R̂, ωo) Φ_leaf` (section 2.10.1, "a small number of rays is enough to estimate the radiance"), `wo` local, one BRDF evaluation per leaf; the bound is not computed here (it is infinite), see [`SummaryTree::error_bound`].
    pub fn estimate(&self, brdf: &dyn Brdf, wo: Vec3) -> Estimate {
        let mut acc = Accumulator::default();
        self.root.for_each_leaf(Cell::ROOT, &mut |_, s| {
            if let Some(d) = s.direction() {
                acc.value += brdf.eval(d, wo).as_dvec3() * s.power;
                acc.evaluations += 1;
            }
        });
        Estimate {
            value: acc.value.as_vec3(),
            bound: Rgb::INFINITY,
            evaluations: acc.evaluations,
        }
    }

    /// Bound on the summaries' error (section 2.10.1 degradation): `Σ_leaves Φ_leaf (f_hi − f_lo)`, the BRDF's range sampled on a `grid × grid` grid of the leaf's cell, its mirror direction and `R̂`; infinite where the BRDF is not finite.
    pub fn error_bound(&self, brdf: &dyn Brdf, wo: Vec3, grid: usize) -> Rgb {
        let mut bound = DVec3::ZERO;
        self.root.for_each_leaf(Cell::ROOT, &mut |cell, s| {
            let Some(d) = s.direction() else { return };
            let (lo, hi) = cell.bounds();
            bound += match sampled_range(brdf, wo, lo, hi, grid, &[d]) {
                Some((min, max, _)) => s.power * (max - min),
                None => DVec3::INFINITY,
            };
        });
        bound.as_vec3()
    }

    /// Number of leaves (summaries).
    pub fn leaves(&self) -> usize {
        self.summaries().len()
    }

    /// Checks the invariants: an empty summary is exactly [`Summary::EMPTY`]; a non-empty one has a finite mean of length at most 1 above the horizon and a finite power.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let mut error = None;
        self.root.for_each_leaf(Cell::ROOT, &mut |cell, s| {
            if error.is_some() {
                return;
            }
            let ok = if s.count == 0 {
                *s == Summary::EMPTY
            } else {
                s.mean.is_finite()
                    && s.mean.length() <= 1.0 + 1e-6
                    && s.mean.z > 0.0
                    && s.power.is_finite()
            };
            if !ok {
                error = Some(format!("cell {cell:?}: invalid summary {s:?}"));
            }
        });
        error.map_or(Ok(()), Err)
    }
}

/// One frame of [`summary_degradation`].
#[derive(Debug, Clone, PartialEq)]
pub struct DegradationRow {
    /// Frame index (0: the summaries are built).
    pub frame: usize,
    /// Rays crossing the disc this frame.
    pub rays: usize,
    /// New Rays this frame (equation 2.5).
    pub new: usize,
    /// Old Rays this frame (equation 2.6).
    pub old: usize,
    /// Per view, relative error of the incrementally updated summaries against the exact per-ray sum.
    pub incremental: Vec<f64>,
    /// Per view, relative error of summaries rebuilt from this frame's rays (the static QuadTree's own error).
    pub rebuilt: Vec<f64>,
    /// Per view, [`SummaryTree::error_bound`] of the incremental summaries relative to the exact sum.
    pub bound: Vec<f64>,
}

/// The degradation of summarised QuadTrees over frames (section 2.10.1: "the list of rays in the QuadTree gets degraded after repeated insertion and deletion of rays").
#[derive(Debug, Clone, PartialEq)]
pub struct DegradationTable {
    /// The tree options.
    pub options: QuadTreeOptions,
    /// The view directions `ωo`, local frame.
    pub views: Vec<Vec3>,
    /// One row per frame.
    pub rows: Vec<DegradationRow>,
}

/// Mean of the three channels, the scalar the relative errors are taken on.
fn grey(c: Rgb) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

/// `|a − b| / b`, infinite when `b` is zero and `a` is not.
fn relative(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / b.abs() }
}

/// Measures the degradation of section 2.10.1: summaries built from `frames[0]` and updated frame by frame with the multiset differences (equations 2.5, 2.6), against the exact per-ray sum and against summaries rebuilt from each frame, for each local view direction; errors on the mean of the channels. Fails on invalid options.
pub fn summary_degradation(
    brdf: &dyn Brdf,
    frames: &[Vec<IncidentRay>],
    views: &[Vec3],
    options: QuadTreeOptions,
) -> Result<DegradationTable> {
    options.validate()?;
    let mut rows = Vec::with_capacity(frames.len());
    let Some(first) = frames.first() else {
        return Ok(DegradationTable {
            options,
            views: views.to_vec(),
            rows,
        });
    };
    let mut tree = SummaryTree::from_rays(options, first)?;
    let views: Vec<Vec3> = views.iter().map(|v| v.normalize_or_zero()).collect();
    for (t, rays) in frames.iter().enumerate() {
        let (old, new) = if t == 0 {
            (Vec::new(), Vec::new())
        } else {
            ray_difference(&frames[t - 1], rays)
        };
        tree.update(&old, &new)?;
        let exact = RayList::from_rays(rays);
        let rebuilt = SummaryTree::from_rays(options, rays)?;
        let mut row = DegradationRow {
            frame: t,
            rays: rays.len(),
            new: new.len(),
            old: old.len(),
            incremental: Vec::new(),
            rebuilt: Vec::new(),
            bound: Vec::new(),
        };
        for &wo in &views {
            let e = grey(exact.estimate(brdf, wo).value);
            row.incremental
                .push(relative(grey(tree.estimate(brdf, wo).value), e));
            row.rebuilt
                .push(relative(grey(rebuilt.estimate(brdf, wo).value), e));
            row.bound
                .push(grey(tree.error_bound(brdf, wo, GRID)) / e.abs());
        }
        rows.push(row);
    }
    Ok(DegradationTable {
        options,
        views,
        rows,
    })
}

impl fmt::Display for DegradationTable {
    /// A Markdown table: frame, rays, New and Old Rays, then per view the incremental error, the rebuilt error and the sampled bound, in percent.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "| frame | rays | new | old |")?;
        for v in &self.views {
            let theta = v.z.clamp(-1.0, 1.0).acos().to_degrees();
            let phi = v.y.atan2(v.x).to_degrees();
            write!(f, " θo {theta:.0}° φo {phi:.0}°: incr. / rebuilt / bound |")?;
        }
        writeln!(f)?;
        write!(f, "|---:|---:|---:|---:|")?;
        for _ in &self.views {
            write!(f, "---:|")?;
        }
        writeln!(f)?;
        for r in &self.rows {
            write!(f, "| {} | {} | {} | {} |", r.frame, r.rays, r.new, r.old)?;
            for i in 0..self.views.len() {
                write!(
                    f,
                    " {:.2}% / {:.2}% / {:.1}% |",
                    100.0 * r.incremental[i],
                    100.0 * r.rebuilt[i],
                    100.0 * r.bound[i]
                )?;
            }
            writeln!(f)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The descent by a point's deepest cell takes the children [`Cell::child_of`] takes, at every depth, for points on and beside cell edges and the square's sides.
    #[test]
    fn descent_by_the_deepest_cell_is_child_of() {
        let mut points = vec![0.0f32, 1.0, 0.5, 0.25, 0.75, 1.0 / 3.0];
        for depth in 1..=MAX_DEPTH {
            for k in [1u32, 3, 5, (1 << depth) - 1] {
                let edge = k as f32 / (1u64 << depth) as f32;
                points.extend([edge, edge.next_down(), edge.next_up()]);
            }
        }
        let mut state = 12345u64;
        for _ in 0..2000 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            points.push((state >> 40) as f32 / (1u64 << 24) as f32);
        }
        points.retain(|x| (0.0..=1.0).contains(x));
        for (i, &x) in points.iter().enumerate() {
            let uv = Vec2::new(x, points[(i * 7 + 3) % points.len()]);
            let deepest = deepest_cell(uv);
            let mut cell = Cell::ROOT;
            while cell.depth < MAX_DEPTH {
                let child = cell.child_of(uv);
                assert_eq!(
                    cell.child_toward(deepest),
                    child,
                    "{uv} at depth {}",
                    cell.depth
                );
                cell = cell.child(child);
            }
            assert!(cell.contains(uv));
        }
    }
}
