//! Disc indexing (section 2.7): a static spatial index over the discs' bounding boxes, each ray segment traversed through it.
//!
//! The index is a bounding volume hierarchy split at the median disc
//! centre along the widest axis, a node becoming a leaf at `max_per_leaf`
//! discs or `max_depth` levels. Each disc lies in exactly one leaf (an
//! object partition), so a segment reports each disc at most once and a
//! large disc is never copied into both children — the slow-down the paper
//! sees with large discs in its voxels (section 2.7) shows up here only as
//! larger, overlapping node boxes. The tree is read-only while segments
//! traverse it, so segments run in parallel without contention, as the
//! paper notes. Boxes can be refitted in place for discs that move
//! rigidly, keeping the tree's topology.
//!
//! Beyond the paper, each node also bounds its discs' normals with a cone
//! (an axis and the largest angle to it). A disc is crossed only from its
//! front, against its normal, so a segment travelling within `90° − angle`
//! of the axis (less a margin of a milliradian, far above the `f32`
//! rounding of the ray–disc test's `d·n`) can cross none of the node's
//! discs: the photons leaving a surface skip the discs round their origin
//! without testing them one by one.

use glam::DVec3;

use super::InvariantError;
use super::envelope::{Box3, SegmentEnvelope};

/// Largest allowed `max_depth` of the disc index (section 2.7; bounds the traversal stack).
pub const MAX_DEPTH_LIMIT: u32 = 64;

/// Angle (radians) added to a normal cone before it rejects a segment: a rejected segment's true `d·n` is then at least `|d| sin(10⁻³)`, thousands of times the `f32` rounding of the ray–disc test's back-face check.
const CONE_MARGIN: f64 = 1e-3;

/// The normals of a node's discs, all within an angle of `axis` (beyond the paper, see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
struct NormalCone {
    /// Unit axis (zero when the normals have no useful axis).
    axis: DVec3,
    /// `sin(angle + margin)`: a segment with `d·axis ≥ min_cos |d|` travels along every normal; infinite when no segment does.
    min_cos: f64,
}

impl NormalCone {
    /// A cone that rejects nothing.
    const ANY: Self = Self {
        axis: DVec3::ZERO,
        min_cos: f64::INFINITY,
    };

    /// The cone round the unit normals of `items` (discs without a box are left out).
    fn of(items: &[u32], boxes: &[Option<Box3>], normals: &[DVec3]) -> Self {
        let normal = |i: &u32| {
            let i = *i as usize;
            boxes[i].and(normals.get(i).copied())
        };
        let sum: DVec3 = items.iter().filter_map(normal).sum();
        let len = sum.length();
        if !(len > 0.0 && len.is_finite()) {
            return Self::ANY;
        }
        let axis = sum / len;
        let mut angle = 0.0f64;
        for n in items.iter().filter_map(normal) {
            let cos = n.dot(axis) / n.length();
            angle = angle.max(cos.clamp(-1.0, 1.0).acos());
        }
        let bound = angle + CONE_MARGIN;
        if !(bound < std::f64::consts::FRAC_PI_2) {
            return Self::ANY;
        }
        Self {
            axis,
            min_cos: bound.sin(),
        }
    }

    /// Whether a segment travels along every normal of the cone, so that it crosses none of its discs from the front.
    #[inline]
    fn rejects(&self, s: &SegmentEnvelope) -> bool {
        s.direction.dot(self.axis) >= self.min_cos * s.len
    }
}

/// One node: its box and either two children (the left one right after it) or a run of `items`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    /// Box of every disc below.
    bounds: Box3,
    /// Cone of every disc normal below (beyond the paper).
    cone: NormalCone,
    /// First and one-past-last index into `items` of the discs below.
    span: (u32, u32),
    /// Leaf: first item; inner node: index of the right child.
    first: u32,
    /// Leaf: number of items (at least 1); inner node: 0.
    count: u32,
    /// Depth (root 0).
    depth: u32,
}

/// The disc index of section 2.7: a hierarchy over disc boxes with a bounded leaf size and depth.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscIndex {
    /// Nodes in depth-first order (root first).
    nodes: Vec<Node>,
    /// Disc indices, leaf by leaf.
    items: Vec<u32>,
    /// Largest number of discs per leaf.
    max_per_leaf: usize,
    /// Largest depth of a node.
    max_depth: u32,
    /// Whether the boxes were refitted since the build (the leaf sizes then hold for the positions at build).
    refitted: bool,
}

impl DiscIndex {
    /// Builds the index over the discs that have a box (`boxes[i]` is disc `i`'s box, `None` for a disc nothing crosses; `normals[i]` its unit normal) (section 2.7).
    pub(crate) fn build(
        boxes: &[Option<Box3>],
        normals: &[DVec3],
        max_per_leaf: usize,
        max_depth: u32,
    ) -> Self {
        let mut items: Vec<u32> = boxes
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|_| i as u32))
            .collect();
        let mut index = Self {
            nodes: Vec::new(),
            items: Vec::new(),
            max_per_leaf: max_per_leaf.max(1),
            max_depth: max_depth.min(MAX_DEPTH_LIMIT),
            refitted: false,
        };
        if !items.is_empty() {
            let n = items.len();
            index.split(boxes, normals, &mut items, 0, n, 0);
        }
        index.items = items;
        index
    }

    /// Builds the subtree over `items[start..end]` and returns its node index.
    fn split(
        &mut self,
        boxes: &[Option<Box3>],
        normals: &[DVec3],
        items: &mut [u32],
        start: usize,
        end: usize,
        depth: u32,
    ) -> usize {
        let slice = &mut items[start..end];
        let bounds = slice
            .iter()
            .filter_map(|&i| boxes[i as usize])
            .fold(Box3::EMPTY, Box3::union);
        let (lo, hi) = slice.iter().filter_map(|&i| boxes[i as usize]).fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), b| {
                let c = b.centre();
                (lo.min(c), hi.max(c))
            },
        );
        let node = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            cone: NormalCone::of(slice, boxes, normals),
            span: (start as u32, end as u32),
            first: start as u32,
            count: slice.len() as u32,
            depth,
        });
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if slice.len() <= self.max_per_leaf || depth >= self.max_depth || !(extent[axis] > 0.0) {
            return node;
        }
        let mid = slice.len() / 2;
        let key = |i: &u32| boxes[*i as usize].map_or(0.0, |b| b.centre()[axis]);
        slice.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        self.split(boxes, normals, items, start, start + mid, depth + 1);
        let right = self.split(boxes, normals, items, start + mid, end, depth + 1);
        self.nodes[node].first = right as u32;
        self.nodes[node].count = 0;
        node
    }

    /// Recomputes every node's box from the discs' new boxes, keeping the tree (section 2.6: a rigid mobile keeps its spatial coherence); `boxes` must say `Some` for the same discs as at build.
    pub(crate) fn refit(&mut self, boxes: &[Option<Box3>], normals: &[DVec3]) {
        self.refitted = true;
        for n in (0..self.nodes.len()).rev() {
            let node = self.nodes[n];
            let (a, b) = (node.span.0 as usize, node.span.1 as usize);
            self.nodes[n].cone = NormalCone::of(&self.items[a..b], boxes, normals);
            self.nodes[n].bounds = if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                self.items[a..b]
                    .iter()
                    .filter_map(|&i| boxes.get(i as usize).copied().flatten())
                    .fold(Box3::EMPTY, Box3::union)
            } else {
                self.nodes[n + 1]
                    .bounds
                    .union(self.nodes[node.first as usize].bounds)
            };
        }
    }

    /// Calls `f` with every disc whose leaf the padded segment reaches (section 2.7), each disc at most once, less those of nodes whose normal cone the segment travels along (it crosses none of them from the front).
    #[inline]
    pub(crate) fn for_each_candidate(&self, s: &SegmentEnvelope, mut f: impl FnMut(u32)) {
        self.for_each_leaf(s, |first, count| {
            let a = first as usize;
            for &i in &self.items[a..a + count as usize] {
                f(i);
            }
        });
    }

    /// Calls `f(first, count)` with every leaf the padded segment reaches whose normal cone it does not travel along (section 2.7; [`DiscIndex::for_each_candidate`] gives their discs one by one).
    #[inline]
    pub(crate) fn for_each_leaf(&self, s: &SegmentEnvelope, mut f: impl FnMut(u32, u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; MAX_DEPTH_LIMIT as usize + 2];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = stack[top];
            let node = &self.nodes[n as usize];
            if node.cone.rejects(s) || !s.meets_box(&node.bounds) {
                continue;
            }
            if node.count > 0 {
                f(node.first, node.count);
            } else {
                stack[top] = node.first;
                stack[top + 1] = n + 1;
                top += 2;
            }
        }
    }

    /// The disc indices, leaf by leaf.
    pub(crate) fn items(&self) -> &[u32] {
        &self.items
    }

    /// Every leaf as `(first, count)` into [`DiscIndex::items`], in order.
    pub(crate) fn leaves(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.nodes
            .iter()
            .filter(|n| n.count > 0)
            .map(|n| (n.first, n.count))
    }

    /// Number of nodes of the disc index (section 2.7).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of leaves, the paper's voxels (section 2.7).
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.count > 0).count()
    }

    /// Largest depth of a node (section 2.7, the maximum depth).
    pub fn depth(&self) -> u32 {
        self.nodes.iter().map(|n| n.depth).max().unwrap_or(0)
    }

    /// Checks the index (section 2.7): every disc with a box in exactly one leaf and the others in none, each node's box holding its discs' boxes and its children's, leaves no larger than `max_per_leaf` unless at `max_depth` or unsplittable (at build: a refit keeps the build's leaves), no node deeper than `max_depth`.
    pub(crate) fn validate(
        &self,
        boxes: &[Option<Box3>],
        normals: &[DVec3],
    ) -> Result<(), InvariantError> {
        let fail = |message: String| InvariantError {
            structure: "disc index",
            message,
        };
        let mut seen = vec![0u32; boxes.len()];
        for &i in &self.items {
            let Some(s) = seen.get_mut(i as usize) else {
                return Err(fail(format!("item {i} is not a disc")));
            };
            *s += 1;
        }
        for (i, (&count, b)) in seen.iter().zip(boxes).enumerate() {
            let expected = u32::from(b.is_some());
            if count != expected {
                return Err(fail(format!(
                    "disc {i} is in {count} leaves, expected {expected}"
                )));
            }
        }
        if self.nodes.is_empty() {
            return if self.items.is_empty() {
                Ok(())
            } else {
                Err(fail("items without nodes".into()))
            };
        }
        let mut leaf_items = 0usize;
        for (n, node) in self.nodes.iter().enumerate() {
            if node.depth > self.max_depth {
                return Err(fail(format!(
                    "node {n} at depth {} > {}",
                    node.depth, self.max_depth
                )));
            }
            let (a, b) = (node.span.0 as usize, node.span.1 as usize);
            if a > b || b > self.items.len() {
                return Err(fail(format!("node {n} spans items {a}..{b}")));
            }
            if node.cone.min_cos.is_finite() {
                // Every normal below within the cone's angle of its axis (the margin excluded).
                let angle = node.cone.min_cos.clamp(-1.0, 1.0).asin() - CONE_MARGIN;
                for &i in &self.items[a..b] {
                    let (Some(Some(_)), Some(normal)) =
                        (boxes.get(i as usize), normals.get(i as usize))
                    else {
                        continue;
                    };
                    let cos = normal.dot(node.cone.axis) / normal.length();
                    if !(cos >= angle.cos() - 1e-9) {
                        return Err(fail(format!(
                            "node {n}'s normal cone misses disc {i}'s normal {normal}"
                        )));
                    }
                }
            }
            if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                if b > self.items.len() || node.span != (node.first, node.first + node.count) {
                    return Err(fail(format!("leaf {n} runs past the items or its span")));
                }
                leaf_items += node.count as usize;
                for &i in &self.items[a..b] {
                    let Some(Some(bx)) = boxes.get(i as usize) else {
                        return Err(fail(format!("leaf {n} holds disc {i} without a box")));
                    };
                    if !node.bounds.contains_box(bx) {
                        return Err(fail(format!("leaf {n} box misses disc {i}")));
                    }
                }
                if node.count as usize > self.max_per_leaf
                    && node.depth < self.max_depth
                    && !self.refitted
                {
                    let centres: Vec<_> = self.items[a..b]
                        .iter()
                        .filter_map(|&i| boxes[i as usize].map(|b| b.centre()))
                        .collect();
                    if centres.iter().any(|c| *c != centres[0]) {
                        return Err(fail(format!(
                            "leaf {n} holds {} > {} splittable discs",
                            node.count, self.max_per_leaf
                        )));
                    }
                }
            } else {
                let (l, r) = (n + 1, node.first as usize);
                if r <= l || r >= self.nodes.len() {
                    return Err(fail(format!("node {n} has children {l} and {r}")));
                }
                let (left, right) = (self.nodes[l].span, self.nodes[r].span);
                if left.0 != node.span.0 || left.1 != right.0 || right.1 != node.span.1 {
                    return Err(fail(format!("node {n}'s span is not its children's")));
                }
                for c in [l, r] {
                    if self.nodes[c].depth != node.depth + 1 {
                        return Err(fail(format!("child {c} of {n} at the wrong depth")));
                    }
                    if !node.bounds.contains_box(&self.nodes[c].bounds) {
                        return Err(fail(format!("node {n} box misses child {c}")));
                    }
                }
            }
        }
        if leaf_items != self.items.len() {
            return Err(fail("leaves do not cover the items exactly".into()));
        }
        Ok(())
    }
}
