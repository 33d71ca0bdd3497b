//! Which photon paths may pass through a box (beyond the paper, for figure
//! 2.2 and section 2.5.2). Each frame of the quasi-static method makes two
//! passes over every ray of the ray set: figure 2.2 tests each against the
//! mobile object, and section 2.5.2 gathers every ray for the mobile
//! object's discs. Both look only at a small region round the mobile object,
//! yet read every segment of every path.
//!
//! Here each primary ray (the first level of section 2.3's two-level ray
//! list) keeps a 512-bit mask of the cells of a coarse 8 × 8 × 8 grid over
//! the scene that its path passes, and a pass visits only the paths whose
//! masks meet the cells of its region: 64 bytes a path instead of all its
//! segments, stored word by word (a word is one slice of the grid along
//! `z`), so that a pass reads only the words its region has cells in. The
//! masks are conservative: every point of a segment, followed as far as any
//! of those tests follows it (its length, or its hit plus its
//! artifact-control extension, plus the crossing test's slack), lies in a
//! marked cell, so the passes find exactly the rays they found by visiting
//! every path. A region not wholly inside the grid's box meets every path.
//!
//! Not the [`crate::SegmentGrid`]: that one lists each segment in fine cells
//! for discs to query; this one answers per path with a fixed 64 bytes, so
//! the update's bookkeeping is one mask per recalculated path.

use glam::Vec3;
use lustre_geometry::Aabb;
use rayon::prelude::*;

use crate::detp::{segment_reach, span_in_box};
use crate::ray_set::{PrimaryRay, RaySegment, RaySet};

/// Cells of the grid per axis.
pub const CELLS_PER_AXIS: usize = 8;

/// One bit per cell, cell `(x, y, z)` at bit `x + 8 y + 64 z`.
type Mask = [u64; CELLS_PER_AXIS * CELLS_PER_AXIS * CELLS_PER_AXIS / 64];

/// Every cell.
const ALL_CELLS: Mask = [u64::MAX; CELLS_PER_AXIS * CELLS_PER_AXIS * CELLS_PER_AXIS / 64];

/// The cells of a region a pass looks at ([`PathCells::region`]), or everywhere: a region the grid does not cover
/// meets every path, those whose paths lie wholly outside the grid (an empty mask) included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region(Option<Mask>);

/// Per primary ray, the cells of a coarse grid its path passes (beyond the paper, for figure 2.2 and section 2.5.2).
#[derive(Debug, Clone)]
pub struct PathCells {
    /// The gridded box: the box given at construction grown by a tenth of its largest extent on every side.
    lo: Vec3,
    hi: Vec3,
    /// The box a region must lie in to be answered by cells: the given box grown by a twentieth, so that a
    /// segment's clipping to the gridded box is never close to a point it must keep.
    inner_lo: Vec3,
    inner_hi: Vec3,
    /// Cell edge per axis.
    cell: Vec3,
    /// Padding of every piece and region box, far above `f32` rounding at the scene's scale.
    pad: f32,
    /// The slack the disc crossing test adds past a segment's end.
    slack: f32,
    /// The masks of every primary ray, in the ray set's order, word by word: `words[w][i]` is word `w` of path
    /// `i`'s mask, so that a pass reads only the words its region has cells in (a slice of the grid along `z`).
    words: Vec<Vec<u64>>,
}

impl PathCells {
    /// The masks of every path of `rays` over a grid round `bounds` (the scene's box, or the box the mobile objects can reach: the grid is finer the smaller it is, and only regions inside it are answered by cells), for a crossing test with `slack`.
    pub fn new(bounds: Aabb, slack: f32, rays: &RaySet) -> Self {
        let size = bounds.extent().max_element();
        let size = if size.is_finite() && size > 0.0 {
            size
        } else {
            1.0
        };
        let scale = bounds.min.abs().max(bounds.max.abs()).max_element();
        let mut cells = Self {
            lo: bounds.min - Vec3::splat(0.1 * size),
            hi: bounds.max + Vec3::splat(0.1 * size),
            inner_lo: bounds.min - Vec3::splat(0.05 * size),
            inner_hi: bounds.max + Vec3::splat(0.05 * size),
            cell: Vec3::ONE,
            pad: 1e-3 * size + 1e-5 * scale,
            slack: slack.max(0.0),
            words: Vec::new(),
        };
        cells.cell = (cells.hi - cells.lo) / CELLS_PER_AXIS as f32;
        let masks: Vec<Mask> = rays.rays.par_iter().map(|p| cells.path_mask(p)).collect();
        cells.words = (0..ALL_CELLS.len())
            .into_par_iter()
            .map(|w| masks.iter().map(|m| m[w]).collect())
            .collect();
        cells
    }

    /// Recomputes the masks of the paths `primaries` (indices into `rays.rays`) after their segments changed, and
    /// grows the list to `rays`' length.
    pub fn refresh(&mut self, rays: &RaySet, primaries: &[usize]) {
        let fresh: Vec<(usize, Mask)> = primaries
            .par_iter()
            .filter_map(|&i| rays.rays.get(i).map(|p| (i, self.path_mask(p))))
            .collect();
        self.words
            .par_iter_mut()
            .enumerate()
            .for_each(|(w, words)| {
                words.resize(rays.rays.len(), ALL_CELLS[w]);
                for (i, mask) in &fresh {
                    words[*i] = mask[w];
                }
            });
    }

    /// The cells of the box `lo..=hi`; everywhere when it is not wholly inside the grid's inner box (or not finite).
    pub fn region(&self, lo: Vec3, hi: Vec3) -> Region {
        if !self.covers(lo, hi) {
            return Region(None);
        }
        let (lo, hi) = (lo - Vec3::splat(self.pad), hi + Vec3::splat(self.pad));
        let mut mask = [0; ALL_CELLS.len()];
        self.mark_box(lo, hi, &mut mask);
        Region(Some(mask))
    }

    /// Whether the box `lo..=hi` lies wholly inside the grid's inner box, so that its [`PathCells::region`] is cells rather than every cell.
    pub fn covers(&self, lo: Vec3, hi: Vec3) -> bool {
        let (lo, hi) = (lo - Vec3::splat(self.pad), hi + Vec3::splat(self.pad));
        lo.is_finite()
            && hi.is_finite()
            && lo.cmpge(self.inner_lo).all()
            && hi.cmple(self.inner_hi).all()
    }

    /// Whether the path of primary ray `primary` may pass through `region` (true for a path it has no mask for, and
    /// for every path when the region is everywhere).
    pub fn may_meet(&self, primary: usize, region: &Region) -> bool {
        let Some(cells) = &region.0 else {
            return true;
        };
        if self.words[0].len() <= primary {
            return true;
        }
        // Only the words the region has cells in are read.
        self.words
            .iter()
            .zip(cells)
            .any(|(words, &r)| r != 0 && words[primary] & r != 0)
    }

    /// The ascending indices, below `count`, of the paths that [`PathCells::may_meet`] `region`: the masks
    /// read word by word, in parallel over runs of paths, so that a pass afterwards visits only those.
    pub fn paths_meeting(&self, region: &Region, count: usize) -> Vec<usize> {
        /// Paths per parallel task.
        const RUN: usize = 1 << 14;
        let Some(cells) = &region.0 else {
            return (0..count).collect();
        };
        let words: Vec<(&[u64], u64)> = self
            .words
            .iter()
            .zip(cells)
            .filter(|&(_, &r)| r != 0)
            .map(|(w, &r)| (w.as_slice(), r))
            .collect();
        let masked = self.words[0].len().min(count);
        let mut out: Vec<usize> = (0..masked.div_ceil(RUN))
            .into_par_iter()
            .flat_map_iter(|run| {
                let words = &words;
                (run * RUN..((run + 1) * RUN).min(masked))
                    .filter(move |&i| words.iter().any(|&(w, r)| w[i] & r != 0))
            })
            .collect();
        out.extend(masked..count);
        out
    }

    /// The cells a path passes.
    fn path_mask(&self, path: &PrimaryRay) -> Mask {
        let mut mask = [0; ALL_CELLS.len()];
        for segment in &path.segments {
            if !self.mark_segment(segment, &mut mask) {
                return ALL_CELLS;
            }
        }
        mask
    }

    /// Marks the cells a segment passes, followed to its reach; false when it cannot be followed (not finite).
    fn mark_segment(&self, segment: &RaySegment, mask: &mut Mask) -> bool {
        let (o, d) = (segment.origin, segment.direction);
        let reach = segment_reach(segment, self.slack);
        if !o.is_finite() || !d.is_finite() || reach.is_nan() {
            return false;
        }
        // The part of [0, reach] inside the gridded box.
        let Some((t0, mut t1)) = span_in_box(o, d, reach, self.lo, self.hi) else {
            return true;
        };
        if !t1.is_finite() {
            // A zero direction: the segment is its origin.
            t1 = t0;
        }
        // Pieces no longer than the smallest cell edge (at most 32: longer ones in a very flat grid), each marked by
        // its padded box.
        let step = self.cell.min_element();
        let pieces = (((t1 - t0) / step).ceil() as usize).clamp(1, 4 * CELLS_PER_AXIS);
        let mut a = o + t0 * d;
        for i in 1..=pieces {
            let t = if i == pieces {
                t1
            } else {
                t0 + (t1 - t0) * (i as f32 / pieces as f32)
            };
            let b = o + t * d;
            let pad = Vec3::splat(self.pad);
            self.mark_box(a.min(b) - pad, a.max(b) + pad, mask);
            a = b;
        }
        true
    }

    /// Marks every cell the box `lo..=hi` overlaps (cells clamped to the grid).
    fn mark_box(&self, lo: Vec3, hi: Vec3, mask: &mut Mask) {
        let last = (CELLS_PER_AXIS - 1) as f32;
        let index = |p: Vec3| {
            ((p - self.lo) / self.cell)
                .floor()
                .clamp(Vec3::ZERO, Vec3::splat(last))
        };
        let (from, to) = (index(lo), index(hi));
        for z in from.z as usize..=to.z as usize {
            for y in from.y as usize..=to.y as usize {
                for x in from.x as usize..=to.x as usize {
                    let bit = x + CELLS_PER_AXIS * (y + CELLS_PER_AXIS * z);
                    mask[bit / 64] |= 1 << (bit % 64);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detp::segment_meets_box;
    use crate::ray_set::SegmentHit;
    use lustre_geometry::Rgb;

    /// A deterministic stream in [0, 1) (splitmix64).
    struct Stream(u64);

    impl Stream {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }

        fn point(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
            lo + (hi - lo) * Vec3::new(self.next(), self.next(), self.next())
        }
    }

    /// Random paths in the box `-1..1`: segments between random points, some leaving the scene (no hit), some with an
    /// artifact-control extension, some axis-aligned.
    fn random_rays(stream: &mut Stream, paths: usize) -> RaySet {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let rays = (0..paths)
            .map(|index| {
                let mut origin = stream.point(lo, hi);
                let segments = (0..1 + (stream.next() * 4.0) as usize)
                    .map(|_| {
                        let mut end = stream.point(lo, hi);
                        if stream.next() < 0.1 {
                            end.y = origin.y;
                        }
                        let direction = (end - origin).normalize_or(Vec3::X);
                        let distance = end.distance(origin);
                        let escapes = stream.next() < 0.2;
                        let hit = (!escapes).then_some(SegmentHit {
                            triangle: 0,
                            mesh: 0,
                            mobile: false,
                            position: end,
                            normal: Vec3::Y,
                            distance,
                        });
                        let mut segment = RaySegment::new(origin, direction, hit, Rgb::ONE);
                        if stream.next() < 0.2 {
                            segment.extension = 0.3 * stream.next();
                        }
                        origin = end;
                        segment
                    })
                    .collect();
                PrimaryRay {
                    light: 0,
                    index: index as u64,
                    segments,
                }
            })
            .collect();
        RaySet {
            rays,
            emitted_per_light: vec![paths as u64],
        }
    }

    #[test]
    fn every_path_through_a_box_is_kept_and_most_others_are_not() {
        let mut stream = Stream(7);
        let rays = random_rays(&mut stream, 3000);
        let slack = 1e-4;
        let cells = PathCells::new(
            Aabb {
                min: Vec3::splat(-1.0),
                max: Vec3::splat(1.0),
            },
            slack,
            &rays,
        );
        let (mut kept, mut meeting, mut total) = (0usize, 0usize, 0usize);
        for _ in 0..200 {
            let centre = stream.point(Vec3::splat(-1.0), Vec3::splat(1.0));
            let half = Vec3::splat(0.02 + 0.15 * stream.next());
            let (lo, hi) = (centre - half, centre + half);
            let region = cells.region(lo, hi);
            for (i, path) in rays.rays.iter().enumerate() {
                let meets = path
                    .segments
                    .iter()
                    .any(|s| segment_meets_box(s, slack, lo, hi));
                let may = cells.may_meet(i, &region);
                assert!(
                    may || !meets,
                    "path {i} meets {lo}..{hi} but its mask says not"
                );
                kept += usize::from(may);
                meeting += usize::from(meets);
                total += 1;
            }
            // The list of a pass: the same paths, in order; those without a mask (past its end) too.
            let listed: Vec<usize> = (0..rays.rays.len())
                .filter(|&i| cells.may_meet(i, &region))
                .collect();
            assert_eq!(cells.paths_meeting(&region, rays.rays.len()), listed);
            let longer = cells.paths_meeting(&region, rays.rays.len() + 2);
            assert_eq!(
                longer[listed.len()..],
                [rays.rays.len(), rays.rays.len() + 1]
            );
        }
        // The grid prunes: far fewer paths kept than visited, and not many more than those that meet.
        assert!(kept < total / 2, "kept {kept} of {total}");
        assert!(
            meeting > 0 && kept < 8 * meeting,
            "kept {kept}, meeting {meeting}"
        );
    }

    #[test]
    fn regions_outside_the_grid_and_refreshed_paths_are_answered_conservatively() {
        let mut stream = Stream(11);
        let mut rays = random_rays(&mut stream, 200);
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let mut cells = PathCells::new(bounds, 0.0, &rays);
        // Partly outside the scene's grown box: every path.
        let region = cells.region(Vec3::splat(0.9), Vec3::splat(1.3));
        assert!((0..rays.rays.len()).all(|i| cells.may_meet(i, &region)));
        // Even a path wholly outside the grid, whose mask is empty, when the region reaches where it is.
        let far = PrimaryRay {
            light: 0,
            index: 0,
            segments: vec![RaySegment::new(Vec3::splat(5.0), Vec3::X, None, Rgb::ONE)],
        };
        let mut beyond = rays.clone();
        beyond.rays.push(far);
        let outside = PathCells::new(bounds, 0.0, &beyond);
        let last = beyond.rays.len() - 1;
        assert!(outside.words.iter().all(|w| w[last] == 0));
        let region = outside.region(Vec3::splat(4.0), Vec3::splat(8.0));
        assert!(segment_meets_box(
            &beyond.rays[last].segments[0],
            0.0,
            Vec3::splat(4.0),
            Vec3::splat(8.0)
        ));
        assert!(outside.may_meet(last, &region));
        assert_eq!(
            outside.paths_meeting(&region, beyond.rays.len()),
            (0..beyond.rays.len()).collect::<Vec<_>>()
        );
        // A path moved into a corner the others may not reach is found there after a refresh, not before.
        let corner = (Vec3::splat(-1.0), Vec3::splat(-0.95));
        let moved = RaySegment::new(Vec3::splat(-0.99), Vec3::X, None, Rgb::ONE);
        rays.rays[5].segments = vec![moved];
        let region = cells.region(corner.0, corner.1);
        cells.refresh(&rays, &[5]);
        assert!(cells.may_meet(5, &region));
        let fresh = PathCells::new(bounds, 0.0, &rays);
        assert_eq!(cells.words, fresh.words);
        // New paths get masks too (a grown ray set).
        rays.rays.push(rays.rays[5].clone());
        cells.refresh(&rays, &[rays.rays.len() - 1]);
        assert!(cells.words.iter().all(|w| w.len() == rays.rays.len()));
        assert!(cells.may_meet(rays.rays.len() - 1, &region));
    }
}
