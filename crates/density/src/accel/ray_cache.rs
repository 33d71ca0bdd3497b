//! The ray cache of section 1.2.1 and 2.6 (after Lastra et al.): a linear hierarchy of spheres of decreasing radius, each keeping the segments that traverse it, and the spatially coherent visiting order of the discs that makes it pay.
//!
//! The spheres are those circumscribing the cells of an octree over the
//! disc set's bounding cube, grown by the largest disc reach: the sphere of
//! depth `k` holds every disc whose centre lies in its cell, lies inside its
//! parent's sphere, and keeps the parent's segments that traverse it. A
//! query for a disc inside the innermost sphere tests only that sphere's
//! segments. When the disc is not inside, spheres are popped until one
//! holds it, and the hierarchy is rebuilt below it down to the cell whose
//! circumradius drops below [`FINEST`] reaches. Visiting the discs in Morton
//! order of their centres in the same cube (section 2.6) walks the octree
//! cell by cell, so each sphere is built once per run. Kept lists stay in
//! ascending segment order, so sums over them are in segment order.

use glam::DVec3;

use super::InvariantError;
use super::envelope::{Box3, SegmentEnvelope};

/// The ray cache's innermost sphere (section 2.6) is the first whose cell's circumradius is at most this many largest disc reaches (its radius is then at most `FINEST + 1` reaches); 3 was the fastest of 0.5–8 on the `detp` bench (Cornell box, radii 0.05 and 0.1).
pub const FINEST: f64 = 3.0;
/// A sphere of the ray cache with at most this many segments is not subdivided further (section 2.6).
pub const MIN_SEGMENTS: usize = 32;
/// Bits per axis of the cell coordinates (octree depth limit).
const BITS: u32 = 21;

/// One sphere of the hierarchy and the segments that traverse it.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    /// Octree depth of the cell (`None` for the root, which keeps every segment).
    depth: Option<u32>,
    /// Cell coordinates at that depth.
    cell: [u64; 3],
    /// Centre.
    centre: DVec3,
    /// Radius (infinite for the root).
    radius: f64,
    /// Indices (ascending) of the segments that come within `radius` (+ their pad) of `centre`.
    ids: Vec<u32>,
}

/// The ray cache (sections 1.2.1, 2.6): a stack of nested spheres over a set of segment envelopes.
#[derive(Debug, Clone)]
pub(crate) struct RayCache<'a> {
    /// The segments (by index); `None` for a segment that crosses nothing.
    segments: &'a [Option<SegmentEnvelope>],
    /// The octree's cube.
    cube: Box3,
    /// The largest disc reach (added to every cell's circumradius).
    max_reach: f64,
    /// Depth of the innermost spheres.
    max_depth: u32,
    /// Root first, innermost last.
    levels: Vec<Level>,
    /// Number of spheres built since creation.
    built: u64,
    /// Number of queries answered.
    queries: u64,
}

/// The cube of side the largest extent of `bounds`, centred on it (section 2.6: the octree, and the Morton order, live in it).
pub(crate) fn bounding_cube(bounds: &Box3) -> Box3 {
    if bounds.is_empty() {
        return Box3 {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
        };
    }
    let c = bounds.centre();
    let half = 0.5 * (bounds.max - bounds.min).max_element();
    Box3 {
        min: c - DVec3::splat(half),
        max: c + DVec3::splat(half),
    }
}

/// The cell coordinates of `p` at the finest depth (`BITS` bits per axis) in `cube`.
fn quantise(p: DVec3, cube: &Box3) -> [u64; 3] {
    let side = (cube.max.x - cube.min.x).max(f64::MIN_POSITIVE);
    let scale = (1u64 << BITS) as f64;
    let q = ((p - cube.min) / side * scale).clamp(DVec3::ZERO, DVec3::splat(scale - 1.0));
    [q.x as u64, q.y as u64, q.z as u64]
}

impl<'a> RayCache<'a> {
    /// A cache holding only its root (every segment) over discs inside `bounds`, whose reaches are at most `max_reach` (section 2.6).
    pub(crate) fn new(
        segments: &'a [Option<SegmentEnvelope>],
        bounds: &Box3,
        max_reach: f64,
    ) -> Self {
        let ids = segments
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.map(|_| i as u32))
            .collect();
        let cube = bounding_cube(bounds);
        let side = cube.max.x - cube.min.x;
        let mut max_depth = 0;
        while max_depth < BITS
            && circumradius(side, max_depth) > FINEST * max_reach.max(side * 1e-6)
        {
            max_depth += 1;
        }
        Self {
            segments,
            cube,
            max_reach,
            max_depth,
            levels: vec![Level {
                depth: None,
                cell: [0; 3],
                centre: cube.centre(),
                radius: f64::INFINITY,
                ids,
            }],
            built: 0,
            queries: 0,
        }
    }

    /// The sphere of a cell: its centre and circumradius grown by the largest reach.
    fn sphere(&self, depth: u32, cell: [u64; 3]) -> (DVec3, f64) {
        let side = self.cube.max.x - self.cube.min.x;
        let size = side / (1u64 << depth) as f64;
        let centre = self.cube.min
            + (DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) + 0.5) * size;
        (
            centre,
            circumradius(side, depth) * (1.0 + 1e-9) + self.max_reach,
        )
    }

    /// Whether the ball of radius `reach` about `centre` lies inside a sphere.
    fn holds(sphere_centre: DVec3, sphere_radius: f64, centre: DVec3, reach: f64) -> bool {
        sphere_radius.is_infinite() || sphere_centre.distance(centre) + reach <= sphere_radius
    }

    /// The segments (ascending indices) that may cross a disc whose envelope is the ball of radius `reach` about `centre` (section 2.6): pops to the innermost sphere of the disc's octree cells that holds the ball, and rebuilds the hierarchy below it.
    pub(crate) fn query(&mut self, centre: DVec3, reach: f64) -> &[u32] {
        self.queries += 1;
        let q = quantise(centre, &self.cube);
        while self.levels.len() > 1 {
            let top = &self.levels[self.levels.len() - 1];
            let depth = top.depth.unwrap_or(0);
            let shift = BITS - depth;
            let same = (0..3).all(|a| q[a] >> shift == top.cell[a]);
            if same && Self::holds(top.centre, top.radius, centre, reach) {
                break;
            }
            self.levels.pop();
        }
        loop {
            let top = &self.levels[self.levels.len() - 1];
            let depth = top.depth.map_or(0, |d| d + 1);
            if top.ids.len() <= MIN_SEGMENTS || depth > self.max_depth {
                break;
            }
            let shift = BITS - depth;
            let cell = q.map(|v| v >> shift);
            let (c, r) = self.sphere(depth, cell);
            if !Self::holds(c, r, centre, reach) {
                break;
            }
            let ids = top
                .ids
                .iter()
                .copied()
                .filter(|&i| self.segments[i as usize].is_some_and(|s| s.meets_sphere(c, r)))
                .collect();
            self.levels.push(Level {
                depth: Some(depth),
                cell,
                centre: c,
                radius: r,
                ids,
            });
            self.built += 1;
        }
        &self.levels[self.levels.len() - 1].ids
    }

    /// Number of spheres built so far (the cache misses of section 2.6).
    pub(crate) fn spheres_built(&self) -> u64 {
        self.built
    }

    /// Number of queries answered.
    pub(crate) fn queries(&self) -> u64 {
        self.queries
    }

    /// Checks the hierarchy (section 2.6): each sphere the one of a child cell of its parent's cell, inside its parent (up to rounding), each list exactly the parent's segments that traverse it, the root holding every segment that can cross a disc, lists ascending.
    pub(crate) fn validate(&self) -> Result<(), InvariantError> {
        let fail = |message: String| InvariantError {
            structure: "ray cache",
            message,
        };
        let root: Vec<u32> = self
            .segments
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.map(|_| i as u32))
            .collect();
        if self.levels.first().map(|l| &l.ids) != Some(&root) {
            return Err(fail("the root does not hold exactly every segment".into()));
        }
        for (k, pair) in self.levels.windows(2).enumerate() {
            let (parent, child) = (&pair[0], &pair[1]);
            let expected_depth = parent.depth.map_or(0, |d| d + 1);
            if child.depth != Some(expected_depth) || expected_depth > self.max_depth {
                return Err(fail(format!("sphere {} at the wrong depth", k + 1)));
            }
            if parent.depth.is_some() && (0..3).any(|a| child.cell[a] >> 1 != parent.cell[a]) {
                return Err(fail(format!("sphere {} is not a child cell", k + 1)));
            }
            if (child.centre, child.radius) != self.sphere(expected_depth, child.cell) {
                return Err(fail(format!("sphere {} is not its cell's", k + 1)));
            }
            let inside = parent.radius.is_infinite()
                || parent.centre.distance(child.centre) + child.radius
                    <= parent.radius * (1.0 + 1e-12);
            if !inside {
                return Err(fail(format!("sphere {} is not inside its parent", k + 1)));
            }
            if child.ids.windows(2).any(|w| w[0] >= w[1]) {
                return Err(fail(format!("sphere {} list not ascending", k + 1)));
            }
            let expected: Vec<u32> = parent
                .ids
                .iter()
                .copied()
                .filter(|&i| {
                    self.segments[i as usize]
                        .is_some_and(|s| s.meets_sphere(child.centre, child.radius))
                })
                .collect();
            if expected != child.ids {
                return Err(fail(format!(
                    "sphere {} keeps {} segments, expected {}",
                    k + 1,
                    child.ids.len(),
                    expected.len()
                )));
            }
        }
        Ok(())
    }
}

/// Circumradius of the octree cells of depth `depth` in a cube of side `side`.
fn circumradius(side: f64, depth: u32) -> f64 {
    side / (1u64 << depth) as f64 * 0.5 * 3f64.sqrt()
}

/// Interleaves the low 21 bits of `v` with two zero bits between each.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1fffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    x = (x | (x << 2)) & 0x1249249249249249;
    x
}

/// The 63-bit Morton code of a point in the octree cube of a box (section 2.6: a spatially coherent order of the queries, walking the ray cache's octree cell by cell).
pub(crate) fn morton(p: DVec3, bounds: &Box3) -> u64 {
    let q = quantise(p, &bounding_cube(bounds));
    spread(q[0]) | (spread(q[1]) << 1) | (spread(q[2]) << 2)
}

/// The visiting order of the discs (section 2.6): by Morton code of their centres when `sorted`, else as given; discs without an envelope are left out.
pub(crate) fn visiting_order(centres: &[Option<DVec3>], bounds: &Box3, sorted: bool) -> Vec<u32> {
    let mut order: Vec<(u64, u32)> = centres
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.map(|c| (if sorted { morton(c, bounds) } else { 0 }, i as u32)))
        .collect();
    if sorted {
        order.sort_unstable();
    }
    order.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_interleaves_every_bit() {
        for v in [0u64, 1, 2, 3, 0x155555, 0x1fffff, 123_456] {
            let mut expected = 0u64;
            for bit in 0..21 {
                expected |= ((v >> bit) & 1) << (3 * bit);
            }
            assert_eq!(spread(v), expected, "{v:#x}");
        }
    }
}
