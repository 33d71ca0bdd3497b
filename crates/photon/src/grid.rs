//! A uniform grid over hit positions, the spatial index of the CPU splat estimator (section 2.2).
//!
//! Points are bucketed into cubic cells (planar surfaces use `(u, v, 0)`,
//! so the grid is one layer thick) by a counting sort; a query visits the
//! cells overlapping the ball around the query point. The number of cells
//! is capped at four per point (at least 64), so memory stays linear in the
//! number of points whatever the radius.

use glam::Vec3;

/// A uniform grid over 3D points with fixed-radius queries (section 2.2).
#[derive(Debug, Clone, Default)]
pub struct PointGrid {
    /// Lower corner of the grid.
    origin: Vec3,
    /// Edge of a cell.
    cell: f32,
    /// Cells per axis.
    dims: [usize; 3],
    /// `cell_start[c]..cell_start[c + 1]` are cell `c`'s points in `sorted`.
    cell_start: Vec<u32>,
    /// The points, cell by cell.
    sorted: Vec<Vec3>,
    /// Original index of each sorted point.
    index: Vec<u32>,
}

impl PointGrid {
    /// Buckets `points` into cells of edge about `cell` (enlarged when there would be more than `max(4 n, 64)` cells); non-finite points are left out.
    pub fn build(points: &[Vec3], cell: f32) -> Self {
        let finite: Vec<u32> = (0..points.len() as u32)
            .filter(|&i| points[i as usize].is_finite())
            .collect();
        if finite.is_empty() {
            return Self::default();
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &i in &finite {
            lo = lo.min(points[i as usize]);
            hi = hi.max(points[i as usize]);
        }
        let extent = (hi - lo).max(Vec3::splat(0.0));
        let max_cells = (4 * finite.len()).max(64) as f64;
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            extent.max_element().max(1.0)
        };
        let count = |c: f32| {
            let d = (extent / c).floor() + Vec3::ONE;
            f64::from(d.x) * f64::from(d.y) * f64::from(d.z)
        };
        while count(cell) > max_cells {
            cell *= 1.5;
        }
        let d = (extent / cell).floor() + Vec3::ONE;
        let dims = [d.x as usize, d.y as usize, d.z as usize];
        let mut grid = Self {
            origin: lo,
            cell,
            dims,
            cell_start: vec![0; dims[0] * dims[1] * dims[2] + 1],
            sorted: Vec::with_capacity(finite.len()),
            index: Vec::with_capacity(finite.len()),
        };
        let cells: Vec<usize> = finite
            .iter()
            .map(|&i| grid.cell_of(points[i as usize]))
            .collect();
        for &c in &cells {
            grid.cell_start[c + 1] += 1;
        }
        for c in 1..grid.cell_start.len() {
            grid.cell_start[c] += grid.cell_start[c - 1];
        }
        let mut fill = grid.cell_start.clone();
        let mut slots = vec![0u32; finite.len()];
        for (k, &c) in cells.iter().enumerate() {
            slots[fill[c] as usize] = finite[k];
            fill[c] += 1;
        }
        for i in slots {
            grid.sorted.push(points[i as usize]);
            grid.index.push(i);
        }
        grid
    }

    /// Integer cell coordinates of a point, clamped into the grid.
    fn coords(&self, p: Vec3) -> [usize; 3] {
        let c = ((p - self.origin) / self.cell).floor();
        [
            (c.x.max(0.0) as usize).min(self.dims[0] - 1),
            (c.y.max(0.0) as usize).min(self.dims[1] - 1),
            (c.z.max(0.0) as usize).min(self.dims[2] - 1),
        ]
    }

    /// Linear cell index of a point.
    fn cell_of(&self, p: Vec3) -> usize {
        let [x, y, z] = self.coords(p);
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Number of points indexed.
    pub fn len(&self) -> usize {
        self.sorted.len()
    }

    /// Whether no point is indexed.
    pub fn is_empty(&self) -> bool {
        self.sorted.is_empty()
    }

    /// Calls `f(index, distance²)` for every point within `radius` of `center` (inclusive), `index` being its position in the slice given to [`PointGrid::build`].
    pub fn for_each_within(&self, center: Vec3, radius: f32, mut f: impl FnMut(usize, f32)) {
        if self.sorted.is_empty() || !center.is_finite() || !(radius >= 0.0) || !radius.is_finite()
        {
            return;
        }
        // A slightly larger box of cells, so rounding never skips a cell holding a point at exactly `radius`.
        let slack = (radius + center.abs().max_element() + self.origin.abs().max_element()) * 1e-6;
        let reach = Vec3::splat(radius + slack);
        let lo = ((center - reach - self.origin) / self.cell).floor();
        let hi = ((center + reach - self.origin) / self.cell).floor();
        let dims = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        );
        if hi.cmplt(Vec3::ZERO).any() || lo.cmpge(dims).any() {
            return;
        }
        let lo = lo.max(Vec3::ZERO);
        let hi = hi.min(dims - Vec3::ONE);
        let r2 = radius * radius;
        for z in lo.z as usize..=hi.z as usize {
            for y in lo.y as usize..=hi.y as usize {
                let row = (z * self.dims[1] + y) * self.dims[0];
                let start = self.cell_start[row + lo.x as usize] as usize;
                let end = self.cell_start[row + hi.x as usize + 1] as usize;
                for k in start..end {
                    let d2 = (self.sorted[k] - center).length_squared();
                    if d2 <= r2 {
                        f(self.index[k] as usize, d2);
                    }
                }
            }
        }
    }

    /// The indices of the points within `radius` of `center`, sorted.
    pub fn within(&self, center: Vec3, radius: f32) -> Vec<usize> {
        let mut out = Vec::new();
        self.for_each_within(center, radius, |i, _| out.push(i));
        out.sort_unstable();
        out
    }

    /// Checks the grid's invariants (cell ranges ascending and covering every point once, every point in its cell); returns a message for the first broken one.
    pub fn validate(&self) -> Result<(), String> {
        if self.sorted.is_empty() {
            return Ok(());
        }
        if self.cell_start.windows(2).any(|w| w[0] > w[1]) {
            return Err("cell ranges are not ascending".into());
        }
        if *self.cell_start.last().unwrap_or(&0) as usize != self.sorted.len() {
            return Err("cell ranges do not cover every point".into());
        }
        let mut seen = vec![
            false;
            self.index
                .iter()
                .map(|&i| i as usize + 1)
                .max()
                .unwrap_or(0)
        ];
        for &i in &self.index {
            if std::mem::replace(&mut seen[i as usize], true) {
                return Err(format!("point {i} appears twice"));
            }
        }
        for c in 0..self.cell_start.len() - 1 {
            for k in self.cell_start[c] as usize..self.cell_start[c + 1] as usize {
                if self.cell_of(self.sorted[k]) != c {
                    return Err(format!("point {} is not in cell {c}", self.index[k]));
                }
            }
        }
        Ok(())
    }
}
