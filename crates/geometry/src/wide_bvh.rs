//! An eight-wide BVH with uncompressed `f32` boxes for closest-hit queries on
//! one ray at a time: a binary PLOC BVH (obvhs) collapsed to eight children
//! per node (Wald et al. 2008, "Getting rid of packets"), children visited
//! nearest first, leaves of one or two blocks of four triangles stored side
//! by side (a corner and two edges, by coordinate) and tested four at once.
//!
//! Boxes are padded outward at build time and the slab test's far distance
//! is widened (Ize 2013, "Robust BVH ray traversal"), so that a triangle the
//! Möller-Trumbore test hits is never culled by a box that rounding made a
//! hair too small: the closest hit is the one a test of every triangle finds.
//!
//! Why our own traversal rather than obvhs' compressed wide BVH, which
//! lustre-geometry used before: on a 516,096-triangle scene, one thread,
//! that one reached about 0.37 (camera rays) and 0.38 (random rays) of
//! Embree's rays per second with its full hit records, and it missed hits
//! closer than `10⁻⁴` to the origin and some grazing hits along flat boxes;
//! this one reaches about 0.75 and 0.55–0.7 with full records, 0.97 and
//! 0.72–0.86 with [`crate::Bvh::closest_hit_lean`] (an Intel Xeon with
//! AVX-512, where Embree uses it; BENCHMARKS.md, `cargo xtask bench embree`).
//! obvhs still builds the binary tree.
//!
//! The queries are compiled twice, for the x86-64 baseline and for AVX2, and
//! the `multiversion` crate picks one at run time: writing the
//! dispatch ourselves would take `unsafe` (calling a `#[target_feature]`
//! function), which the workspace forbids; the crate's macro keeps it out of
//! our code.

use glam::{Vec3, Vec3A, Vec4};
use multiversion::multiversion;
use obvhs::bvh2::Bvh2;

use crate::ray::{Ray, TriangleHit, Triangles4, intersect_triangles4};

/// Children per node.
const WIDTH: usize = 8;

/// Groups of four children (one `Vec4` each) per node.
const GROUPS: usize = WIDTH / 4;

/// Largest number of triangles in a leaf (lanes of its [`Triangles4`] blocks).
const LEAF_MAX: u32 = 4 * LEAF_BLOCKS;

/// Largest number of blocks of four triangles in a leaf.
const LEAF_BLOCKS: u32 = 2;

/// Entries of the traversal stack kept in an array; more (a tree deeper than
/// `STACK / (WIDTH - 1)` levels may need them) go to a vector.
const STACK: usize = 64;

/// Relative outward padding of every box (about 16 units in the last place).
const BOX_PAD: f32 = 1e-6;

/// Relative widening of the slab test's far distance (more than Ize's 1 + 2γ₃).
const FAR_WIDEN: f32 = 1e-6;

/// One node: what each of its eight children is and their boxes by axis
/// (structure of arrays, so that the slab tests run four side by side).
/// 224 bytes in four cache lines, the child indices first: the box test
/// reads all four lines at once, so that the indices it picks from are never
/// a second wait.
#[derive(Debug, Clone)]
#[repr(C, align(64))]
struct Node {
    /// An inner child's node index, or a leaf's index in `leaves` with [`LEAF`] set.
    child: [u32; WIDTH],
    /// Lower corners of the children's boxes: `lo[axis][child / 4][child % 4]`; `+∞` for an empty slot.
    lo: [[Vec4; GROUPS]; 3],
    /// Upper corners of the children's boxes, as `lo`; `-∞` for an empty slot.
    hi: [[Vec4; GROUPS]; 3],
}

/// The bit of [`Node::child`] that marks a leaf.
const LEAF: u32 = 1 << 31;

/// Where a leaf's [`Node::child`] keeps its block count less one (below it, the first block's index).
const BLOCKS_SHIFT: u32 = 30;

/// A child to visit: as [`Node::child`] gives it, and its entry distance.
#[derive(Debug, Clone, Copy, Default)]
struct Entry {
    child: u32,
    t: f32,
}

/// A block of up to four triangles (a leaf has one or two); unused lanes hold
/// a triangle with zero edges, which nothing hits. 160 bytes on 32-byte
/// boundaries: three cache lines, never four.
#[derive(Debug, Clone)]
#[repr(align(32))]
struct Leaf {
    /// The triangles side by side.
    triangles: Triangles4,
    /// Their scene-wide ids, by lane (beside them, in the cache lines the test reads).
    ids: [u32; 4],
}

/// Where a triangle sits in the leaves: its block and lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lane {
    block: u32,
    lane: u32,
}

/// The wide BVH.
#[derive(Debug, Clone)]
pub(crate) struct WideBvh {
    nodes: Vec<Node>,
    /// The triangles of every leaf.
    leaves: Vec<Leaf>,
}

/// Builder state: the binary tree and its subtree triangle counts.
struct Collapse<'a> {
    bvh2: &'a Bvh2,
    corners: &'a [[Vec3; 3]],
    counts: Vec<u32>,
    out: WideBvh,
}

impl Collapse<'_> {
    /// Triangles under the binary node `i`, written to `counts` for it and every node below (post-order).
    fn count(&mut self, i: usize) -> u32 {
        let node = &self.bvh2.nodes[i];
        let n = if node.prim_count > 0 {
            node.prim_count
        } else {
            let first = node.first_index as usize;
            self.count(first) + self.count(first + 1)
        };
        self.counts[i] = n;
        n
    }

    /// Appends the id of every triangle under the binary node `i` to `ids`.
    fn gather(&self, i: usize, ids: &mut Vec<u32>) {
        let node = &self.bvh2.nodes[i];
        let first = node.first_index as usize;
        if node.prim_count > 0 {
            ids.extend_from_slice(
                &self.bvh2.primitive_indices[first..first + node.prim_count as usize],
            );
        } else {
            self.gather(first, ids);
            self.gather(first + 1, ids);
        }
    }

    /// Makes a leaf of the (at most four) triangles under the binary node `i` and returns its index.
    fn leaf(&mut self, i: usize) -> u32 {
        let mut ids = Vec::with_capacity(LEAF_MAX as usize);
        self.gather(i, &mut ids);
        let first = self.out.leaves.len() as u32;
        for chunk in ids.chunks(4) {
            let mut lanes = [[Vec3A::ZERO; 3]; 4];
            let mut lane_ids = [u32::MAX; 4];
            for (k, &id) in chunk.iter().enumerate() {
                let [p0, p1, p2] = self.corners[id as usize].map(Vec3A::from);
                lanes[k] = [p0, p1 - p0, p2 - p0];
                lane_ids[k] = id;
            }
            let by_axis = |which: usize| {
                [0, 1, 2].map(|axis| Vec4::from_array(lanes.map(|l| l[which][axis])))
            };
            self.out.leaves.push(Leaf {
                triangles: Triangles4 {
                    p0: by_axis(0),
                    e1: by_axis(1),
                    e2: by_axis(2),
                },
                ids: lane_ids,
            });
        }
        // The block count less one above the first block's index.
        first | ((self.out.leaves.len() as u32 - first - 1) << BLOCKS_SHIFT)
    }

    /// Whether the binary node `i` becomes a leaf of the wide tree.
    fn is_leaf(&self, i: usize) -> bool {
        self.bvh2.nodes[i].prim_count > 0 || self.counts[i] <= LEAF_MAX
    }

    /// Builds the wide node for the binary node `i` (an inner node, or the root) and returns its index.
    fn node(&mut self, i: usize) -> u32 {
        // Open the largest candidate with more triangles than one block holds
        // (an inner binary node) until WIDTH children are found: nodes fill
        // up, and leaves of five to eight triangles split into fuller blocks
        // while a slot is free (about 8% faster incoherent rays than opening
        // only subtrees too big for a leaf).
        let mut open = if self.bvh2.nodes[i].prim_count > 0 {
            vec![i]
        } else {
            let first = self.bvh2.nodes[i].first_index as usize;
            vec![first, first + 1]
        };
        while open.len() < WIDTH {
            let largest = open
                .iter()
                .enumerate()
                .filter(|&(_, &c)| self.bvh2.nodes[c].prim_count == 0 && self.counts[c] > 4)
                .max_by(|a, b| {
                    let area = |c: usize| self.bvh2.nodes[c].aabb.half_area();
                    area(*a.1).total_cmp(&area(*b.1))
                })
                .map(|(k, _)| k);
            let Some(k) = largest else { break };
            let first = self.bvh2.nodes[open[k]].first_index as usize;
            open[k] = first;
            open.push(first + 1);
        }
        let index = self.out.nodes.len();
        self.out.nodes.push(Node {
            lo: [[Vec4::INFINITY; GROUPS]; 3],
            hi: [[Vec4::NEG_INFINITY; GROUPS]; 3],
            child: [0; WIDTH],
        });
        for (slot, &c) in open.iter().enumerate() {
            let aabb = self.bvh2.nodes[c].aabb;
            let pad = aabb.min.abs().max(aabb.max.abs()).max_element() * BOX_PAD;
            let (lo, hi) = (aabb.min - pad, aabb.max + pad);
            let child = if self.is_leaf(c) {
                self.leaf(c) | LEAF
            } else {
                self.node(c)
            };
            let node = &mut self.out.nodes[index];
            for axis in 0..3 {
                node.lo[axis][slot / 4][slot % 4] = lo[axis];
                node.hi[axis][slot / 4][slot % 4] = hi[axis];
            }
            node.child[slot] = child;
        }
        index as u32
    }
}

impl WideBvh {
    /// Collapses the binary tree `bvh2` over the triangles `corners`; `None` when empty.
    ///
    /// Panics with 2³⁰ leaf blocks or more (a billion triangles at least).
    pub(crate) fn from_bvh2(bvh2: &Bvh2, corners: &[[Vec3; 3]]) -> Option<Self> {
        if bvh2.nodes.is_empty() {
            return None;
        }
        let mut c = Collapse {
            bvh2,
            corners,
            counts: vec![0; bvh2.nodes.len()],
            out: WideBvh {
                nodes: Vec::new(),
                leaves: Vec::new(),
            },
        };
        c.count(0);
        c.node(0);
        assert!(
            c.out.leaves.len() <= 1 << BLOCKS_SHIFT,
            "{} triangles are more than the BVH's leaf encoding holds",
            corners.len()
        );
        Some(c.out)
    }

    /// The closest Möller-Trumbore hit with `t` in `[t_min, t_max]` and its triangle's scene-wide id; `direction` as the triangle test takes it. `on_best` gets the id of each hit that becomes the closest so far, as it is found.
    #[inline]
    pub(crate) fn closest_hit(
        &self,
        ray: &Ray,
        direction: Vec3A,
        on_best: impl FnMut(u32),
    ) -> Option<(u32, TriangleHit, Lane)> {
        closest_hit_dispatch(self, ray, direction, on_best)
    }

    /// The unnormalised geometric normal `e1 × e2` of the triangle in `lane`, from the edges the
    /// triangle test read (the same operations as `(p1 - p0).cross(p2 - p0)` on its corners, so
    /// the same bits).
    pub(crate) fn edge_cross(&self, lane: Lane) -> Vec3 {
        let tris = &self.leaves[lane.block as usize].triangles;
        let k = lane.lane as usize;
        let edge = |e: &[Vec4; 3]| Vec3::new(e[0][k], e[1][k], e[2][k]);
        edge(&tris.e1).cross(edge(&tris.e2))
    }

    /// [`WideBvh::closest_hit`]'s body, compiled once per instruction set by [`closest_hit_dispatch`].
    #[inline(always)]
    fn closest_hit_body(
        &self,
        ray: &Ray,
        direction: Vec3A,
        mut on_best: impl FnMut(u32),
    ) -> Option<(u32, TriangleHit, Lane)> {
        let mut best: Option<((usize, usize), TriangleHit)> = None;
        self.traverse::<true>(ray, direction, |block, mask, t, u, v, t_max| {
            // Lane by lane, as one triangle after the other would.
            let mut mask = mask;
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if t[k] <= *t_max {
                    *t_max = t[k];
                    on_best(self.leaves[block].ids[k]);
                    best = Some((
                        (block, k),
                        TriangleHit {
                            t: t[k],
                            u: u[k],
                            v: v[k],
                        },
                    ));
                }
            }
            false
        });
        // The id once, for the closest hit only.
        best.map(|((block, k), h)| {
            let lane = Lane {
                block: block as u32,
                lane: k as u32,
            };
            (self.leaves[block].ids[k], h, lane)
        })
    }

    /// Whether a Möller-Trumbore hit at `t` in `[t_min, t_max)` (the CWBVH's any-hit interval: `t_max` itself excluded) is one `accept` takes (scene-wide id, distance); each hit met is offered until one is taken.
    #[inline]
    pub(crate) fn any_hit_where(
        &self,
        ray: &Ray,
        direction: Vec3A,
        accept: impl FnMut(u32, f32) -> bool,
    ) -> bool {
        any_hit_dispatch(self, ray, direction, accept)
    }

    /// [`WideBvh::any_hit_where`]'s body, compiled once per instruction set by [`any_hit_dispatch`].
    #[inline(always)]
    fn any_hit_body(
        &self,
        ray: &Ray,
        direction: Vec3A,
        mut accept: impl FnMut(u32, f32) -> bool,
    ) -> bool {
        let mut found = false;
        self.traverse::<false>(ray, direction, |block, mask, t, _, _, t_max| {
            found = (0..4).any(|k| {
                mask & (1 << k) != 0 && t[k] < *t_max && accept(self.leaves[block].ids[k], t[k])
            });
            found
        });
        found
    }

    /// Calls `f` with the scene-wide id of every triangle in a leaf whose box overlaps `min..=max` (a superset of the triangles whose own boxes do; each once).
    pub(crate) fn overlapping(&self, min: Vec3A, max: Vec3A, mut f: impl FnMut(u32)) {
        let (lo, hi) = (
            min.to_array().map(Vec4::splat),
            max.to_array().map(Vec4::splat),
        );
        let mut stack = vec![0u32];
        while let Some(child) = stack.pop() {
            if child & LEAF != 0 {
                let first = (child & ((1 << BLOCKS_SHIFT) - 1)) as usize;
                let blocks = ((child & !LEAF) >> BLOCKS_SHIFT) as usize + 1;
                for leaf in &self.leaves[first..first + blocks] {
                    leaf.ids
                        .iter()
                        .filter(|&&id| id != u32::MAX)
                        .for_each(|&id| f(id));
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            for g in 0..GROUPS {
                let mut overlap = 0xf;
                for axis in 0..3 {
                    overlap &= (node.lo[axis][g].cmple(hi[axis])
                        & node.hi[axis][g].cmpge(lo[axis]))
                    .bitmask();
                }
                for k in 0..4 {
                    if overlap & (1 << k) != 0 {
                        stack.push(node.child[4 * g + k]);
                    }
                }
            }
        }
    }

    /// Checks that every id in `0..count` sits in exactly one leaf lane and that every box holds
    /// what lies under it (`corners` by id); the first violation found, in words.
    pub(crate) fn validate(&self, corners: &[[Vec3; 3]]) -> Result<(), String> {
        let mut seen = vec![false; corners.len()];
        let mut stack = vec![(0u32, Vec3A::NEG_INFINITY, Vec3A::INFINITY)];
        while let Some((child, lo, hi)) = stack.pop() {
            let inside = |p: Vec3A| p.cmpge(lo).all() && p.cmple(hi).all();
            if child & LEAF != 0 {
                let first = (child & ((1 << BLOCKS_SHIFT) - 1)) as usize;
                let blocks = ((child & !LEAF) >> BLOCKS_SHIFT) as usize + 1;
                for leaf in self
                    .leaves
                    .get(first..first + blocks)
                    .ok_or("leaf out of range")?
                {
                    for &id in leaf.ids.iter().filter(|&&id| id != u32::MAX) {
                        let tri = corners
                            .get(id as usize)
                            .ok_or(format!("id {id} out of range"))?;
                        if std::mem::replace(&mut seen[id as usize], true) {
                            return Err(format!("triangle {id} in two leaves"));
                        }
                        if !tri.iter().all(|&p| inside(p.into())) {
                            return Err(format!("triangle {id} outside its leaf's box"));
                        }
                    }
                }
                continue;
            }
            let node = self.nodes.get(child as usize).ok_or("node out of range")?;
            for k in 0..WIDTH {
                let corner = |b: &[[Vec4; GROUPS]; 3]| {
                    Vec3A::new(b[0][k / 4][k % 4], b[1][k / 4][k % 4], b[2][k / 4][k % 4])
                };
                let (clo, chi) = (corner(&node.lo), corner(&node.hi));
                if clo.cmpgt(chi).any() {
                    continue; // an empty slot
                }
                if !(inside(clo) && inside(chi)) {
                    return Err(format!("a child box of node {child} outside its parent's"));
                }
                stack.push((node.child[k], clo, chi));
            }
        }
        match seen.iter().position(|s| !s) {
            Some(id) => Err(format!("triangle {id} in no leaf")),
            None => Ok(()),
        }
    }

    /// Visits the leaf blocks the ray reaches, nearest child first when `SORTED`; `leaf` gets the
    /// block's index, its Möller-Trumbore hit mask, `t`, `u`, `v` and the current `t_max` (which
    /// it may lower), and ends the traversal by returning `true`.
    #[inline(always)]
    fn traverse<const SORTED: bool>(
        &self,
        ray: &Ray,
        direction: Vec3A,
        mut leaf: impl FnMut(usize, u32, [f32; 4], [f32; 4], [f32; 4], &mut f32) -> bool,
    ) {
        let origin = Vec3A::from(ray.origin);
        // No zero component: ±f32::MAX keeps (box - origin) * inv free of NaN.
        let inv = Vec3A::from_array(direction.to_array().map(|d| {
            let inv = 1.0 / d;
            if inv.is_finite() {
                inv
            } else {
                f32::MAX.copysign(d)
            }
        }));
        let negative = [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0];
        let (o, i) = (
            origin.to_array().map(Vec4::splat),
            inv.to_array().map(Vec4::splat),
        );
        let t_min4 = Vec4::splat(ray.t_min);
        let (t_min, mut t_max) = (ray.t_min, ray.t_max);
        let mut stack = [Entry::default(); STACK];
        let mut overflow: Vec<Entry> = Vec::new();
        let mut top = 0;
        let mut current = Entry { child: 0, t: t_min };
        loop {
            if current.child & LEAF == 0 {
                let node = &self.nodes[current.child as usize];
                let mut hits = [Entry::default(); WIDTH];
                let mut n = 0;
                let mut hit = 0;
                let mut t_near = [0.0; WIDTH];
                for g in 0..GROUPS {
                    let slab = |axis: usize, lo: bool| {
                        let bound = if lo {
                            node.lo[axis][g]
                        } else {
                            node.hi[axis][g]
                        };
                        (bound - o[axis]) * i[axis]
                    };
                    let near = [0, 1, 2].map(|axis| slab(axis, !negative[axis]));
                    let far = [0, 1, 2].map(|axis| slab(axis, negative[axis]));
                    let t_n = near[0].max(near[1]).max(near[2].max(t_min4));
                    let f = far[0].min(far[1]).min(far[2]);
                    // Widened away from zero either side, without NaN at ±∞.
                    let t_far = (f * (1.0 + FAR_WIDEN))
                        .max(f * (1.0 - FAR_WIDEN))
                        .min(Vec4::splat(t_max));
                    hit |= t_n.cmple(t_far).bitmask() << (4 * g);
                    t_near[4 * g..4 * g + 4].copy_from_slice(&t_n.to_array());
                }
                for k in 0..WIDTH {
                    if hit & (1 << k) != 0 {
                        let entry = Entry {
                            child: node.child[k],
                            t: t_near[k],
                        };
                        let mut j = n;
                        // Insertion by distance, nearest first.
                        while SORTED && j > 0 && hits[j - 1].t > entry.t {
                            hits[j] = hits[j - 1];
                            j -= 1;
                        }
                        hits[j] = entry;
                        n += 1;
                    }
                }
                if n > 0 {
                    for k in (1..n).rev() {
                        if top < STACK {
                            stack[top] = hits[k];
                        } else {
                            overflow.push(hits[k]);
                        }
                        top += 1;
                    }
                    current = hits[0];
                    continue;
                }
            } else {
                let first = (current.child & ((1 << BLOCKS_SHIFT) - 1)) as usize;
                let blocks = ((current.child & !LEAF) >> BLOCKS_SHIFT) as usize + 1;
                for block in first..first + blocks {
                    let (mask, t, u, v) = intersect_triangles4(
                        origin,
                        direction,
                        t_min,
                        t_max,
                        &self.leaves[block].triangles,
                    );
                    if mask != 0 && leaf(block, mask, t, u, v, &mut t_max) {
                        return;
                    }
                }
            }
            // The next entry not farther than the closest hit so far.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let entry = if top < STACK {
                    stack[top]
                } else {
                    match overflow.pop() {
                        Some(entry) => entry,
                        None => continue,
                    }
                };
                if entry.t <= t_max {
                    current = entry;
                    break;
                }
            }
        }
    }
}

/// [`WideBvh::closest_hit`] compiled for the base instruction set and for
/// AVX2, picked at run time: the same operations in the same order (Rust does
/// not fuse or reorder floating-point arithmetic), so the same hits bit for
/// bit; the AVX2 copy's three-operand encoding makes camera rays about a
/// tenth faster (BENCHMARKS.md).
#[multiversion(targets("x86_64+avx2"))]
fn closest_hit_dispatch<F: FnMut(u32)>(
    bvh: &WideBvh,
    ray: &Ray,
    direction: Vec3A,
    on_best: F,
) -> Option<(u32, TriangleHit, Lane)> {
    bvh.closest_hit_body(ray, direction, on_best)
}

/// [`WideBvh::any_hit_where`] compiled per instruction set, as [`closest_hit_dispatch`].
#[multiversion(targets("x86_64+avx2"))]
fn any_hit_dispatch<F: FnMut(u32, f32) -> bool>(
    bvh: &WideBvh,
    ray: &Ray,
    direction: Vec3A,
    accept: F,
) -> bool {
    bvh.any_hit_body(ray, direction, accept)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::intersect_triangle;
    use obvhs::aabb::Aabb;
    use obvhs::bvh2::node::Bvh2Node;

    #[test]
    fn a_deep_tree_overflows_the_stack_array_and_still_finds_the_closest_hit() {
        // 400 squares' halves across the z axis at z = 0..400, in a binary
        // chain whose leaf at each level is the farthest square left: a ray
        // along +z meets every box and pushes seven entries per wide level.
        let n = 400;
        let corners: Vec<[Vec3; 3]> = (0..n)
            .map(|k| {
                let z = k as f32;
                [
                    Vec3::new(-1.0, -1.0, z),
                    Vec3::new(1.0, -1.0, z),
                    Vec3::new(0.0, 1.0, z),
                ]
            })
            .collect();
        let bounds = |from: usize, to: usize| {
            Aabb::new(
                Vec3A::new(-1.0, -1.0, from as f32),
                Vec3A::new(1.0, 1.0, to as f32),
            )
        };
        let mut bvh2 = Bvh2::default();
        // Node 0: the chain over squares 0..n; inner node at 2j+1 covers 0..n-1-j.
        bvh2.nodes.push(Bvh2Node {
            aabb: bounds(0, n - 1),
            prim_count: 0,
            first_index: 1,
            ..Bvh2Node::default()
        });
        for j in 0..n - 1 {
            let far = n - 1 - j;
            bvh2.nodes.push(Bvh2Node {
                aabb: bounds(far, far),
                prim_count: 1,
                first_index: far as u32,
                ..Bvh2Node::default()
            });
            let rest = if far == 1 {
                Bvh2Node {
                    aabb: bounds(0, 0),
                    prim_count: 1,
                    first_index: 0,
                    ..Bvh2Node::default()
                }
            } else {
                Bvh2Node {
                    aabb: bounds(0, far - 1),
                    prim_count: 0,
                    first_index: 2 * j as u32 + 3,
                    ..Bvh2Node::default()
                }
            };
            bvh2.nodes.push(rest);
        }
        bvh2.primitive_indices = (0..n as u32).collect();
        let mut wide = WideBvh::from_bvh2(&bvh2, &corners).unwrap();
        assert_eq!(wide.validate(&corners), Ok(()));
        // A triangle moved out of its leaf's box, and one listed twice.
        let mut moved = corners.clone();
        moved[7][1].x = 5.0;
        assert!(wide.validate(&moved).unwrap_err().contains("outside"));
        let saved = wide.leaves[0].ids;
        wide.leaves[0].ids[1] = wide.leaves[0].ids[0];
        assert!(wide.validate(&corners).is_err());
        wide.leaves[0].ids = saved;
        for (origin, direction) in [
            (Vec3::new(0.0, 0.0, -1.0), Vec3::Z),
            (Vec3::new(0.1, 0.2, 150.5), Vec3::Z),
            (Vec3::new(0.1, 0.2, 420.0), -Vec3::Z),
        ] {
            let ray = Ray::new(origin, direction);
            let expected = corners
                .iter()
                .enumerate()
                .filter_map(|(i, &t)| intersect_triangle(&ray, t).map(|h| (i as u32, h.t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let got = wide
                .closest_hit(&ray, Vec3A::from(direction), |_| {})
                .map(|(id, h, _)| (id, h.t));
            assert_eq!(got, expected, "{ray:?}");
        }
    }
}
