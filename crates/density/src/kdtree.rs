//! A balanced kd-tree of impact points for the `k`-nearest search of Photon Maps (section 1.2, Jensen's "spatial data structure which keeps the photon impacts").
//!
//! Each range is split at its median on the axis of its widest extent and
//! ranges of a few points are leaves, scanned whole. Splitting on
//! `depth mod 3` instead made every split across a wall's or floor's plane
//! (all its impacts share that coordinate) useless to a query on it, and the
//! search visited both halves of each. An oriented tree
//! ([`KdTree::build_oriented`]) also bounds each subtree's normals, so the
//! search for the impacts that face like a vertex (Jensen's normal filter)
//! skips the rest: a vertex under a box whose bottom no photon reaches no
//! longer scans every impact of the floor around it.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::Vec3;

use crate::error::{DensityError, Result};

/// A neighbour found by a `k`-nearest search (section 1.2): the point's index in the input and its squared distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    /// Index of the point in the slice given to [`KdTree::build`].
    pub index: u32,
    /// Squared Euclidean distance to the query.
    pub distance_squared: f32,
}

impl Eq for Neighbour {}

impl PartialOrd for Neighbour {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Neighbour {
    fn cmp(&self, other: &Self) -> Ordering {
        self.distance_squared
            .total_cmp(&other.distance_squared)
            .then(self.index.cmp(&other.index))
    }
}

/// Implicit balanced kd-tree (section 1.2, Photon Maps): the points are reordered so that the median of every range splits it on the axis of the range's widest extent, down to leaves of a few points.
///
/// A tree built with [`KdTree::build_oriented`] also keeps a unit normal per
/// point and, per node, the box bounding its points' normals, so that the
/// search for the points facing like a query ([`KdTree::nearest_facing`],
/// Jensen 2001's normal filter) skips the subtrees where none does (the
/// impacts on the floor, for a vertex on the underside of a box standing on
/// it).
#[derive(Debug, Clone, Default)]
pub struct KdTree {
    /// Points in tree order.
    points: Vec<Vec3>,
    /// Input index of each point in tree order.
    ids: Vec<u32>,
    /// Split axis of the node whose median sits at each slot (unused in leaves).
    axes: Vec<u8>,
    /// Unit (or zero) normal of each point in tree order (oriented trees only, else empty).
    normals: Vec<Vec3>,
    /// Per slot, the box of the normals of the subtree whose median sits there, in 127ths rounded outwards, minimum then maximum per axis (oriented trees' inner nodes).
    normal_boxes: Vec<[i8; 6]>,
}

impl KdTree {
    /// Builds the tree; fails on a non-finite point or more than 2^32 points.
    pub fn build(points: &[Vec3]) -> Result<Self> {
        check_points(points)?;
        let mut order: Vec<(Vec3, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        let mut axes = vec![0u8; order.len()];
        split(&mut order, &mut axes);
        Ok(Self {
            points: order.iter().map(|o| o.0).collect(),
            ids: order.iter().map(|o| o.1).collect(),
            axes,
            normals: Vec::new(),
            normal_boxes: Vec::new(),
        })
    }

    /// Builds the tree of points with normals (normalised; a zero normal faces nowhere) for [`KdTree::nearest_facing`]; fails as [`KdTree::build`] does, or on a count of normals other than the count of points or a normal that is not finite.
    pub fn build_oriented(points: &[Vec3], normals: &[Vec3]) -> Result<Self> {
        if normals.len() != points.len() {
            return Err(DensityError::InvalidOption {
                option: "normals",
                message: format!("{} normals for {} points", normals.len(), points.len()),
            });
        }
        if let Some(i) = normals.iter().position(|n| !n.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "normals",
                message: format!("normal #{i} is not finite: {}", normals[i]),
            });
        }
        let mut tree = Self::build(points)?;
        tree.normals = tree
            .ids
            .iter()
            .map(|&i| normals[i as usize].normalize_or_zero())
            .collect();
        tree.normal_boxes = vec![[0; 6]; tree.points.len()];
        let len = tree.points.len();
        tree.bound_normals(0, len);
        Ok(tree)
    }

    /// Records the normal box of every inner node of `lo..hi` and returns the range's.
    fn bound_normals(&mut self, lo: usize, hi: usize) -> [i8; 6] {
        if hi - lo <= LEAF {
            let mut b = EMPTY_BOX;
            for &n in &self.normals[lo..hi] {
                b = merge(b, quantise(n));
            }
            return b;
        }
        let mid = lo + (hi - lo) / 2;
        let b = merge(
            merge(self.bound_normals(lo, mid), self.bound_normals(mid + 1, hi)),
            quantise(self.normals[mid]),
        );
        self.normal_boxes[mid] = b;
        b
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the tree holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The `k` points nearest to `query`, nearest first (fewer when the tree holds fewer; ties broken by index).
    pub fn nearest(&self, query: Vec3, k: usize) -> Vec<Neighbour> {
        self.nearest_where(query, k, |_| true)
    }

    /// The `k` points nearest to `query` among those whose input index `keep` accepts, nearest first (Jensen 2001's photon filter: only the impacts that belong to the query's surface count).
    pub fn nearest_where(
        &self,
        query: Vec3,
        k: usize,
        keep: impl Fn(u32) -> bool,
    ) -> Vec<Neighbour> {
        self.nearest_within(query, k, f32::INFINITY, keep)
    }

    /// The `k` points nearest to `query` among those `keep` accepts and at a squared distance of at most `max_squared`, nearest first (Jensen 2001's photon search with a maximum distance, which bounds the search where few points are accepted).
    pub fn nearest_within(
        &self,
        query: Vec3,
        k: usize,
        max_squared: f32,
        keep: impl Fn(u32) -> bool,
    ) -> Vec<Neighbour> {
        Search::run(self, query, k, max_squared, ByIndex(keep)).into_sorted_vec()
    }

    /// Jensen 2001's filtered search with a maximum distance relative to the unfiltered `k`-th nearest: the `k` points nearest to `query` whose normal `m` has `m · normal ≥ min_cos`, within `factor_squared` times the squared distance of the `k`-th nearest point of all (of the farthest where the tree holds fewer than `k`), nearest first. The same as [`KdTree::nearest`] followed by [`KdTree::nearest_within`] with that bound and that test, but the second search skips the subtrees whose normal box has no normal that passes. A tree built without normals ([`KdTree::build`]) lets every point pass.
    pub fn nearest_facing(
        &self,
        query: Vec3,
        k: usize,
        factor_squared: f32,
        normal: Vec3,
        min_cos: f32,
    ) -> RelativeNearest {
        let all = Search::run(self, query, k, f32::INFINITY, ByIndex(|_| true));
        let unfiltered = all.len();
        let max_squared = all
            .peek()
            .map_or(0.0, |kth| factor_squared * kth.distance_squared);
        let found = if self.normals.is_empty() {
            Search::run(self, query, k, max_squared, ByIndex(|_| true))
        } else {
            Search::run(self, query, k, max_squared, Facing { normal, min_cos })
        };
        RelativeNearest {
            found: found.into_sorted_vec(),
            unfiltered,
            max_squared,
        }
    }
}

/// The outcome of [`KdTree::nearest_facing`].
#[derive(Debug, Clone, PartialEq)]
pub struct RelativeNearest {
    /// The accepted points within the bound, nearest first.
    pub found: Vec<Neighbour>,
    /// How many points the unfiltered search found: `k`, or every point of a smaller tree.
    pub unfiltered: usize,
    /// The bound: `factor_squared` times the squared distance of the last unfiltered point (0 for an empty tree).
    pub max_squared: f32,
}

/// Fails on a non-finite point or more than 2^32 points.
fn check_points(points: &[Vec3]) -> Result<()> {
    if points.len() > u32::MAX as usize {
        return Err(DensityError::InvalidOption {
            option: "points",
            message: "more than 2^32 points".into(),
        });
    }
    if let Some(i) = points.iter().position(|p| !p.is_finite()) {
        return Err(DensityError::InvalidOption {
            option: "points",
            message: format!("point #{i} is not finite: {}", points[i]),
        });
    }
    Ok(())
}

/// Points per leaf: ranges this small are scanned rather than split.
const LEAF: usize = 8;

/// Points of a range whose extent picks its split axis.
const AXIS_SAMPLE: usize = 64;

/// The normal box that holds nothing (its merge with any box is that box).
const EMPTY_BOX: [i8; 6] = [127, 127, 127, -127, -127, -127];

/// A unit normal's box in 127ths: each component rounded down for the minimum and up for the maximum.
fn quantise(n: Vec3) -> [i8; 6] {
    let down = |v: f32| (v * 127.0).floor().clamp(-127.0, 127.0) as i8;
    let up = |v: f32| (v * 127.0).ceil().clamp(-127.0, 127.0) as i8;
    [down(n.x), down(n.y), down(n.z), up(n.x), up(n.y), up(n.z)]
}

/// The smallest box holding both.
fn merge(a: [i8; 6], b: [i8; 6]) -> [i8; 6] {
    [
        a[0].min(b[0]),
        a[1].min(b[1]),
        a[2].min(b[2]),
        a[3].max(b[3]),
        a[4].max(b[4]),
        a[5].max(b[5]),
    ]
}

/// Which points a search accepts, and which subtrees it may skip.
trait Filter {
    /// Whether the point at a tree slot is accepted.
    fn keep(&self, tree: &KdTree, slot: usize) -> bool;
    /// Whether no point of the subtree whose median sits at `mid` can be accepted.
    fn skips(&self, _tree: &KdTree, _mid: usize) -> bool {
        false
    }
}

/// A predicate on the points' input indices.
struct ByIndex<K>(K);

impl<K: Fn(u32) -> bool> Filter for ByIndex<K> {
    fn keep(&self, tree: &KdTree, slot: usize) -> bool {
        (self.0)(tree.ids[slot])
    }
}

/// The points whose normal `m` has `m · normal ≥ min_cos` (oriented trees).
struct Facing {
    normal: Vec3,
    min_cos: f32,
}

impl Filter for Facing {
    fn keep(&self, tree: &KdTree, slot: usize) -> bool {
        tree.normals[slot].dot(self.normal) >= self.min_cos
    }

    /// The largest `m · normal` over the node's normal box, `Σ max(lo_i n_i, hi_i n_i)`, bounds it over the node's normals; with a margin for rounding.
    fn skips(&self, tree: &KdTree, mid: usize) -> bool {
        let b = tree.normal_boxes[mid];
        let n = self.normal;
        let most = |lo: i8, hi: i8, c: f32| (lo as f32 * c).max(hi as f32 * c);
        let bound = (most(b[0], b[3], n.x) + most(b[1], b[4], n.y) + most(b[2], b[5], n.z)) / 127.0;
        bound < self.min_cos - 1e-4
    }
}

/// One `k`-nearest search: the accepted points within `max_squared` in a max-heap.
struct Search<'a, F> {
    tree: &'a KdTree,
    query: Vec3,
    k: usize,
    max_squared: f32,
    filter: F,
    heap: BinaryHeap<Neighbour>,
}

impl<'a, F: Filter> Search<'a, F> {
    /// The `k` best points, as a max-heap.
    fn run(
        tree: &'a KdTree,
        query: Vec3,
        k: usize,
        max_squared: f32,
        filter: F,
    ) -> BinaryHeap<Neighbour> {
        let mut search = Self {
            tree,
            query,
            k,
            max_squared,
            filter,
            heap: BinaryHeap::with_capacity(k + 1),
        };
        if k > 0 {
            search.search(0, tree.points.len());
        }
        search.heap
    }

    /// How far a point may lie and still enter the heap.
    fn reach(&self) -> f32 {
        if self.heap.len() < self.k {
            self.max_squared
        } else {
            self.heap
                .peek()
                .map_or(self.max_squared, |worst| worst.distance_squared)
        }
    }

    fn offer(&mut self, slot: usize) {
        let candidate = Neighbour {
            index: self.tree.ids[slot],
            distance_squared: self.tree.points[slot].distance_squared(self.query),
        };
        if candidate.distance_squared > self.max_squared {
            return;
        }
        if self.heap.len() < self.k {
            if self.filter.keep(self.tree, slot) {
                self.heap.push(candidate);
            }
        } else if self.heap.peek().is_some_and(|worst| candidate < *worst)
            && self.filter.keep(self.tree, slot)
        {
            self.heap.pop();
            self.heap.push(candidate);
        }
    }

    /// Recursive search of the range `lo..hi`.
    fn search(&mut self, lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            for slot in lo..hi {
                self.offer(slot);
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        if self.filter.skips(self.tree, mid) {
            return;
        }
        self.offer(mid);
        let p = self.tree.points[mid];
        let axis = self.tree.axes[mid] as usize;
        let delta = self.query[axis] - p[axis];
        let (near, far) = if delta < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1);
        if delta * delta <= self.reach() {
            self.search(far.0, far.1);
        }
    }
}

/// Places the median of `points` on the axis of their widest extent (over a strided sample of [`AXIS_SAMPLE`] points) in the middle, smaller before, larger after, records that axis at the median's slot of `axes`, then recurses on both halves down to leaves of [`LEAF`] points. The widest axis, not `depth mod 3`: impacts on a plane all share one coordinate, and a split across it would prune nothing for a query on that plane.
fn split(points: &mut [(Vec3, u32)], axes: &mut [u8]) {
    if points.len() <= LEAF {
        return;
    }
    // The extent of an evenly strided sample of the range: enough to tell the widest axis, and zero across a plane of points.
    let stride = (points.len() / AXIS_SAMPLE).max(1);
    let (lo, hi) = points
        .iter()
        .step_by(stride)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = points.len() / 2;
    points.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    axes[mid] = axis as u8;
    let (left, right) = points.split_at_mut(mid);
    let (left_axes, right_axes) = axes.split_at_mut(mid);
    if splits_in_parallel(left.len()) {
        rayon::join(
            || split(left, left_axes),
            || split(&mut right[1..], &mut right_axes[1..]),
        );
    } else {
        split(left, left_axes);
        split(&mut right[1..], &mut right_axes[1..]);
    }
}

/// Whether halves this large are split in parallel.
fn splits_in_parallel(len: usize) -> bool {
    len >= 1 << 14
}

/// The `k` points nearest to `query` by exhaustive search, nearest first, ties broken by index (the reference the kd-tree is tested against).
pub fn brute_force_nearest(points: &[Vec3], query: Vec3, k: usize) -> Vec<Neighbour> {
    brute_force_nearest_where(points, query, k, |_| true)
}

/// The `k` points nearest to `query` among those whose index `keep` accepts, by exhaustive search (the reference for [`KdTree::nearest_where`]).
pub fn brute_force_nearest_where(
    points: &[Vec3],
    query: Vec3,
    k: usize,
    keep: impl Fn(u32) -> bool,
) -> Vec<Neighbour> {
    brute_force_nearest_within(points, query, k, f32::INFINITY, keep)
}

/// The `k` points nearest to `query` among those `keep` accepts within the squared distance `max_squared`, by exhaustive search (the reference for [`KdTree::nearest_within`]).
pub fn brute_force_nearest_within(
    points: &[Vec3],
    query: Vec3,
    k: usize,
    max_squared: f32,
    keep: impl Fn(u32) -> bool,
) -> Vec<Neighbour> {
    let mut all: Vec<Neighbour> = points
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i as u32))
        .map(|(i, p)| Neighbour {
            index: i as u32,
            distance_squared: p.distance_squared(query),
        })
        .filter(|n| n.distance_squared <= max_squared)
        .collect();
    all.sort();
    all.truncate(k);
    all
}
