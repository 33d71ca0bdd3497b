//! A uniform grid over a BVH's triangles (beyond the paper): which triangles of other meshes come near a disc, so that Artifact Control (section 1.2.1) skips the visibility paths of a disc nothing but its own mesh reaches.
//!
//! A disc's paths only ever count as blocked by a triangle outside the
//! vertex's mesh ([`crate::artifact`]), so when no such triangle's box meets
//! the box holding every path, every point is reachable and the area is
//! `π r²`, exactly what the `n²` paths would find. The grid answers that
//! question conservatively: a triangle is listed in every cell its bounding
//! box overlaps, and a query compares the boxes themselves, so it can only
//! say "near" too often (a box corner), never too rarely.

use std::ops::Range;

use glam::Vec3;
use lustre_geometry::{Bvh, TriangleId};

/// Most cells along one axis.
const MAX_CELLS_PER_AXIS: usize = 256;

/// The triangles of a BVH binned by their bounding boxes into cubic cells (beyond the paper).
#[derive(Debug, Clone)]
pub struct TriangleGrid {
    /// Corner of the grid's lowest cell.
    origin: Vec3,
    /// Edge of the cubic cells.
    cell: f32,
    /// Cells along each axis.
    dims: [usize; 3],
    /// Start of each cell's run in `ids`, one more entry than cells (compressed rows).
    starts: Vec<u32>,
    /// Triangle ids, cell by cell.
    ids: Vec<TriangleId>,
    /// Bounding box (min, max) of every triangle, by id; empty (min > max) for one collapsed to a point, which no ray meets.
    boxes: Vec<(Vec3, Vec3)>,
}

impl TriangleGrid {
    /// Bins the BVH's triangles into cells of edge at least `cell` (grown so that no axis has more than 256 cells); a cell no larger than twice the query reach keeps each query to at most eight cells. A non-positive or non-finite `cell` gives one cell.
    pub fn new(bvh: &Bvh, cell: f32) -> Self {
        let boxes: Vec<(Vec3, Vec3)> = bvh
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.positions;
                if a == b && b == c {
                    (Vec3::INFINITY, Vec3::NEG_INFINITY)
                } else {
                    (a.min(b).min(c), a.max(b).max(c))
                }
            })
            .collect();
        let (lo, hi) = boxes
            .iter()
            .filter(|(a, b)| a.cmple(*b).all())
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
                (lo.min(*a), hi.max(*b))
            });
        let extent = if lo.cmple(hi).all() {
            hi - lo
        } else {
            Vec3::ZERO
        };
        let largest = extent.max_element();
        let mut cell = if cell > 0.0 && cell.is_finite() {
            cell
        } else {
            largest.max(1.0)
        };
        cell = cell.max(largest / MAX_CELLS_PER_AXIS as f32);
        if !(cell > 0.0) {
            cell = 1.0;
        }
        let dims =
            [0, 1, 2].map(|k| ((extent[k] / cell).floor() as usize + 1).min(MAX_CELLS_PER_AXIS));
        let mut grid = Self {
            origin: if lo.is_finite() { lo } else { Vec3::ZERO },
            cell,
            dims,
            starts: Vec::new(),
            ids: Vec::new(),
            boxes,
        };
        // Two passes: count, then fill (compressed rows).
        let count = dims[0] * dims[1] * dims[2];
        let mut counts = vec![0u32; count + 1];
        for (a, b) in grid.boxes.iter().filter(|(a, b)| a.cmple(*b).all()) {
            grid.for_cells(*a, *b, |c| counts[c + 1] += 1);
        }
        for c in 0..count {
            counts[c + 1] += counts[c];
        }
        let mut next = counts.clone();
        let mut ids = vec![0; counts[count] as usize];
        for (id, (a, b)) in grid.boxes.iter().enumerate() {
            if a.cmple(*b).all() {
                grid.for_cells(*a, *b, |c| {
                    ids[next[c] as usize] = id as TriangleId;
                    next[c] += 1;
                });
            }
        }
        grid.starts = counts;
        grid.ids = ids;
        grid
    }

    /// Calls `f` with the index of every cell the box `[a, b]` overlaps (clamped to the grid).
    fn for_cells(&self, a: Vec3, b: Vec3, mut f: impl FnMut(usize)) {
        let index = |p: Vec3, k: usize| -> usize {
            let i = ((p[k] - self.origin[k]) / self.cell).floor();
            if i.is_nan() || i < 0.0 {
                0
            } else {
                (i as usize).min(self.dims[k] - 1)
            }
        };
        let lo = [0, 1, 2].map(|k| index(a, k));
        let hi = [0, 1, 2].map(|k| index(b, k));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    f((z * self.dims[1] + y) * self.dims[0] + x);
                }
            }
        }
    }

    /// Whether the bounding box of a triangle outside `own` meets the cube of half-edge `reach` around `centre` (conservative: `false` means no such triangle has a point in the cube).
    pub fn foreign_near(&self, centre: Vec3, reach: f32, own: &Range<TriangleId>) -> bool {
        let (a, b) = (centre - Vec3::splat(reach), centre + Vec3::splat(reach));
        if !(a.is_finite() && b.is_finite()) {
            return true;
        }
        let mut near = false;
        self.for_cells(a, b, |c| {
            if near {
                return;
            }
            let run = self.starts[c] as usize..self.starts[c + 1] as usize;
            near = self.ids[run].iter().any(|&id| {
                let (lo, hi) = self.boxes[id as usize];
                !own.contains(&id) && lo.cmple(b).all() && hi.cmpge(a).all()
            });
        });
        near
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
}
