//! The disc index's leaves packed eight discs to a block (beyond the paper, section 2.7's leaf test made branch-free): each leaf's discs in structure-of-arrays blocks, tested against a segment lane by lane with the very `f32` operations of [`Disc::is_crossed_by`].
//!
//! A leaf's candidates are tested all at once instead of one call each:
//! disc indexing's candidates fail the ray–disc test for unpredictable
//! reasons (behind the disc, short of its plane, outside its radius), so
//! the branches of one test per candidate cost more than the arithmetic.
//! Every lane computes `d·n`, `t`, the crossing point and its distance in
//! the order `is_crossed_by` does (glam's `Vec3` operations component by
//! component, no fused multiply–add), so a lane accepts exactly when
//! `is_crossed_by` does; the fixed-size loops are left to the compiler to
//! vectorise. Unused lanes hold a NaN radius and never accept.

use glam::Vec3;

use crate::detp::Disc;
use crate::ray_set::RaySegment;

/// Discs per block.
pub(crate) const LANES: usize = 8;

/// Eight discs of one leaf, component by component.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(align(32))]
struct Block {
    /// Centre `x`, `y`, `z`.
    centre: [[f32; LANES]; 3],
    /// Normal `x`, `y`, `z`.
    normal: [[f32; LANES]; 3],
    /// `r · r` as `is_crossed_by` rounds it (NaN in unused lanes).
    radius2: [f32; LANES],
    /// The disc's mesh, when it has one.
    mesh: [u32; LANES],
    /// Whether the disc has a mesh (its artifact-control extension applies to segments ending on that mesh).
    has_mesh: [bool; LANES],
    /// The disc's index in its set.
    item: [u32; LANES],
}

impl Block {
    /// A block with every lane unused.
    const EMPTY: Self = Self {
        centre: [[0.0; LANES]; 3],
        normal: [[0.0; LANES]; 3],
        radius2: [f32::NAN; LANES],
        mesh: [0; LANES],
        has_mesh: [false; LANES],
        item: [u32::MAX; LANES],
    };
}

/// The leaves of a disc index packed in blocks of [`LANES`] discs (see the module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct PackedLeaves {
    /// The blocks, leaf by leaf.
    blocks: Vec<Block>,
    /// For each position in the index's item list that starts a leaf, the leaf's first block.
    first_block: Vec<u32>,
}

impl PackedLeaves {
    /// Packs the leaves `(first, count)` of `items` (the index's item list), with the discs they name.
    pub(crate) fn new(
        discs: &[Disc],
        items: &[u32],
        leaves: impl Iterator<Item = (u32, u32)>,
    ) -> Self {
        let mut packed = Self {
            blocks: Vec::new(),
            first_block: vec![0; items.len()],
        };
        for (first, count) in leaves {
            let (a, b) = (first as usize, (first + count) as usize);
            packed.first_block[a] = packed.blocks.len() as u32;
            for chunk in items[a..b].chunks(LANES) {
                let mut block = Block::EMPTY;
                for (lane, &i) in chunk.iter().enumerate() {
                    let d = &discs[i as usize];
                    for axis in 0..3 {
                        block.centre[axis][lane] = d.centre[axis];
                        block.normal[axis][lane] = d.normal[axis];
                    }
                    block.radius2[lane] = d.radius * d.radius;
                    block.mesh[lane] = d.mesh.unwrap_or(0);
                    block.has_mesh[lane] = d.mesh.is_some();
                    block.item[lane] = i;
                }
                packed.blocks.push(block);
            }
        }
        packed
    }

    /// Calls `f` with every disc of the leaf starting at item `first` with `count` discs that `segment` crosses, exactly those [`Disc::is_crossed_by`] accepts with `slack`.
    #[inline]
    pub(crate) fn for_each_crossed(
        &self,
        first: u32,
        count: u32,
        segment: &SegmentLanes,
        mut f: impl FnMut(u32),
    ) {
        for block in self.leaf_blocks(first, count) {
            let [crossed] = crossed_lanes(block, [segment]);
            for_each_lane(crossed, |lane| f(block.item[lane]));
        }
    }

    /// For two segments with the same origin and direction (a re-traced path's first segment before and
    /// after, [`crate::Twins`]), calls `only_a` with every disc of the leaf that `a` crosses and
    /// `b` does not, and `only_b` with every one that `b` crosses and `a` does not; each test as
    /// [`PackedLeaves::for_each_crossed`] makes it, the part that does not depend on the segment's end once.
    #[inline]
    pub(crate) fn for_each_crossed_by_one(
        &self,
        first: u32,
        count: u32,
        a: &SegmentLanes,
        b: &SegmentLanes,
        mut only_a: impl FnMut(u32),
        mut only_b: impl FnMut(u32),
    ) {
        debug_assert!(a.origin == b.origin && a.direction == b.direction);
        for block in self.leaf_blocks(first, count) {
            let [by_a, by_b] = crossed_lanes(block, [a, b]);
            for_each_lane(by_a & !by_b, |lane| only_a(block.item[lane]));
            for_each_lane(by_b & !by_a, |lane| only_b(block.item[lane]));
        }
    }

    /// The blocks of the leaf starting at item `first` with `count` discs.
    #[inline]
    fn leaf_blocks(&self, first: u32, count: u32) -> &[Block] {
        let start = self.first_block[first as usize] as usize;
        &self.blocks[start..start + (count as usize).div_ceil(LANES)]
    }
}

/// Calls `f` with each lane whose bit is set in `mask`.
#[inline]
fn for_each_lane(mask: u32, mut f: impl FnMut(usize)) {
    if mask != 0 {
        for lane in 0..LANES {
            if mask & (1 << lane) != 0 {
                f(lane);
            }
        }
    }
}

/// One segment's values as every lane of a block needs them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SegmentLanes {
    /// Origin `o`.
    origin: Vec3,
    /// Direction `d`.
    direction: Vec3,
    /// [`Disc::reach`] plus the slack for a disc of the mesh the segment ends on.
    limit_same: f32,
    /// [`Disc::reach`] plus the slack for any other disc.
    limit_other: f32,
    /// The mesh the segment ends on, if it ends.
    hit_mesh: Option<u32>,
}

impl SegmentLanes {
    /// The nearest of the ends `t ≤ limit` this segment's test puts on a disc (NaN when one of them is NaN):
    /// a disc that one of two twins crosses and the other does not is met beyond the nearer of their two.
    pub(crate) fn nearest_limit(&self) -> f32 {
        let same = match self.hit_mesh {
            Some(_) => self.limit_same,
            None => self.limit_other,
        };
        if same.is_nan() || self.limit_other.is_nan() {
            f32::NAN
        } else {
            same.min(self.limit_other)
        }
    }

    /// The lanes' view of `segment` for discs tested with `slack`.
    pub(crate) fn new(segment: &RaySegment, slack: f32) -> Self {
        let length = segment.length();
        Self {
            origin: segment.origin,
            direction: segment.direction,
            limit_same: segment
                .hit
                .map_or(length, |hit| hit.distance + segment.extension)
                + slack,
            limit_other: length + slack,
            hit_mesh: segment.hit.map(|hit| hit.mesh),
        }
    }
}

/// Per segment, bit `lane` set when it crosses that lane's disc: `is_crossed_by`'s operations, lane by
/// lane. The segments share their origin and direction (those of the first), so the plane crossing and
/// its distance from the centre are computed once; only the end each reaches is their own.
#[inline]
fn crossed_lanes<const N: usize>(b: &Block, segments: [&SegmentLanes; N]) -> [u32; N] {
    let (o, d) = (segments[0].origin, segments[0].direction);
    let mut ok = [[false; LANES]; N];
    for l in 0..LANES {
        let (cx, cy, cz) = (b.centre[0][l], b.centre[1][l], b.centre[2][l]);
        let (nx, ny, nz) = (b.normal[0][l], b.normal[1][l], b.normal[2][l]);
        let denom = (d.x * nx) + (d.y * ny) + (d.z * nz);
        let t = ((cx - o.x) * nx + (cy - o.y) * ny + (cz - o.z) * nz) / denom;
        let (px, py, pz) = (o.x + t * d.x, o.y + t * d.y, o.z + t * d.z);
        let (ex, ey, ez) = (px - cx, py - cy, pz - cz);
        let dist2 = (ex * ex) + (ey * ey) + (ez * ez);
        let on_plane = (denom < 0.0) & (t >= 0.0) & (dist2 <= b.radius2[l]);
        for (ok, s) in ok.iter_mut().zip(segments) {
            let (mesh, ends) = (s.hit_mesh.unwrap_or(0), s.hit_mesh.is_some());
            let same = ends & b.has_mesh[l] & (b.mesh[l] == mesh);
            let limit = if same { s.limit_same } else { s.limit_other };
            ok[l] = on_plane & (t <= limit);
        }
    }
    ok.map(|ok| {
        let mut bits = 0;
        for (l, &ok) in ok.iter().enumerate() {
            bits |= u32::from(ok) << l;
        }
        bits
    })
}
