//! A balanced kd-tree of impact points for the `k`-nearest search of Photon Maps (section 1.2, Jensen's "spatial data structure which keeps the photon impacts").

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

/// Implicit balanced kd-tree (section 1.2, Photon Maps): the points are reordered so that the median of every range splits it on axis `depth mod 3`.
#[derive(Debug, Clone, Default)]
pub struct KdTree {
    /// Points in tree order.
    points: Vec<Vec3>,
    /// Input index of each point in tree order.
    ids: Vec<u32>,
}

impl KdTree {
    /// Builds the tree; fails on a non-finite point or more than 2^32 points.
    pub fn build(points: &[Vec3]) -> Result<Self> {
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
        let mut order: Vec<(Vec3, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        split(&mut order, 0);
        Ok(Self {
            points: order.iter().map(|o| o.0).collect(),
            ids: order.iter().map(|o| o.1).collect(),
        })
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
        let mut heap = BinaryHeap::with_capacity(k + 1);
        if k > 0 {
            let bound = Bound { k, max_squared };
            self.search(query, bound, &keep, 0, self.points.len(), 0, &mut heap);
        }
        heap.into_sorted_vec()
    }

    /// Recursive search of the range `lo..hi` at `depth`, keeping the `k` best accepted by `keep` in a max-heap.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        query: Vec3,
        bound: Bound,
        keep: &dyn Fn(u32) -> bool,
        lo: usize,
        hi: usize,
        depth: usize,
        heap: &mut BinaryHeap<Neighbour>,
    ) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let p = self.points[mid];
        let candidate = Neighbour {
            index: self.ids[mid],
            distance_squared: p.distance_squared(query),
        };
        let k = bound.k;
        if candidate.distance_squared > bound.max_squared || !keep(candidate.index) {
            // Not a candidate, but its subtrees still are.
        } else if heap.len() < k {
            heap.push(candidate);
        } else if heap.peek().is_some_and(|worst| candidate < *worst) {
            heap.pop();
            heap.push(candidate);
        }
        let axis = depth % 3;
        let delta = query[axis] - p[axis];
        let (near, far) = if delta < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(query, bound, keep, near.0, near.1, depth + 1, heap);
        let reach = if heap.len() < k {
            bound.max_squared
        } else {
            heap.peek()
                .map_or(bound.max_squared, |worst| worst.distance_squared)
        };
        if delta * delta <= reach {
            self.search(query, bound, keep, far.0, far.1, depth + 1, heap);
        }
    }
}

/// The limits of a search: how many points and how far.
#[derive(Debug, Clone, Copy)]
struct Bound {
    k: usize,
    max_squared: f32,
}

/// Places the median of `points` on axis `depth mod 3` in the middle, smaller before, larger after, then recurses on both halves.
fn split(points: &mut [(Vec3, u32)], depth: usize) {
    if points.len() <= 1 {
        return;
    }
    let axis = depth % 3;
    let mid = points.len() / 2;
    points.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (left, right) = points.split_at_mut(mid);
    split(left, depth + 1);
    split(&mut right[1..], depth + 1);
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
