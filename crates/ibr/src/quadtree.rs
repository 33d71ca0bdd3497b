//! The quadtree over a radiance map's texels: nodes hold points of a bounded depth range or at most a minimum count, each with a representative point for point size and bounds for view-frustum culling (Bastos et al. 1999, section 8.1.3, "Reconstruction").
//!
//! A node covers a rectangle of texels. It is split into four while its
//! valid texels (those that see something) span depths `z` with
//! `z_max > (1 + tolerance) z_min` and number more than the minimum count.
//! The depth range is relative because equation 3's point size goes as
//! `1/z`: a relative range of `ε` bounds the point-size error within a
//! node by `ε`. Its representative point is the average of its valid
//! texels' world points (the paper's), its bounds their bounding box.
//! Nodes without valid texels are dropped.

use glam::Vec3;

use crate::error::{Result, out_of_range};
use crate::radiance_map::RadianceMap;
use crate::sampling::SampleCamera;

/// When a quadtree node stops splitting (section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadtreeSettings {
    /// Largest relative depth range of a leaf, `z_max / z_min − 1`.
    pub depth_tolerance: f32,
    /// A node of at most this many valid texels is a leaf.
    pub min_points: u32,
}

impl Default for QuadtreeSettings {
    /// 5 % depth range, 4 points. On `cornell`'s floor seen from its camera
    /// (2 maps a hemisphere) 10 % and 16 points left 4.7 % of the reflected
    /// image uncovered: a leaf's points share its representative's size, and
    /// where sizes are near one pixel a few per cent too small open
    /// one-pixel cracks; 5 % and 4 points leave 0.2 %.
    fn default() -> Self {
        Self {
            depth_tolerance: 0.05,
            min_points: 4,
        }
    }
}

/// One quadtree node: a texel rectangle, its depth range, representative point and bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadNode {
    /// First texel column.
    pub x: u32,
    /// First texel row.
    pub y: u32,
    /// Columns covered.
    pub width: u32,
    /// Rows covered.
    pub height: u32,
    /// Valid texels inside.
    pub count: u32,
    /// Least depth of its valid texels.
    pub z_min: f32,
    /// Greatest depth of its valid texels.
    pub z_max: f32,
    /// Average world point of its valid texels.
    pub representative: Vec3,
    /// Lower corner of its valid texels' world bounding box.
    pub bounds_min: Vec3,
    /// Upper corner of its valid texels' world bounding box.
    pub bounds_max: Vec3,
    /// Index of its first child in [`MapQuadtree::nodes`] (children are consecutive), `None` for a leaf.
    pub first_child: Option<u32>,
    /// How many children it has (1 to 4; empty quadrants are dropped).
    pub children: u32,
}

/// The quadtree of one radiance map; node 0 is the root (absent for a map that sees nothing).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MapQuadtree {
    /// The nodes, parents before children.
    pub nodes: Vec<QuadNode>,
}

impl QuadtreeSettings {
    /// Checks the ranges: tolerance finite and positive, minimum count at least 1.
    pub fn validate(&self) -> Result<()> {
        if !(self.depth_tolerance > 0.0 && self.depth_tolerance.is_finite()) {
            return Err(out_of_range(
                "quadtree depth tolerance",
                self.depth_tolerance,
                "a positive number",
            ));
        }
        if self.min_points == 0 {
            return Err(out_of_range("quadtree minimum points", 0, "at least 1"));
        }
        Ok(())
    }
}

impl MapQuadtree {
    /// Builds the quadtree of `map` (module documentation).
    pub fn build(map: &RadianceMap, settings: &QuadtreeSettings) -> Result<Self> {
        settings.validate()?;
        let mut tree = Self::default();
        if let Some(root) = summarise(map, 0, 0, map.width, map.height) {
            tree.nodes.push(root);
            let mut k = 0;
            while k < tree.nodes.len() {
                let node = tree.nodes[k];
                let splittable = node.width > 1 || node.height > 1;
                let wide = node.z_max > (1.0 + settings.depth_tolerance) * node.z_min;
                if splittable && wide && node.count > settings.min_points {
                    let first = tree.nodes.len() as u32;
                    let (w0, h0) = (node.width.div_ceil(2), node.height.div_ceil(2));
                    let quads = [
                        (node.x, node.y, w0, h0),
                        (node.x + w0, node.y, node.width - w0, h0),
                        (node.x, node.y + h0, w0, node.height - h0),
                        (node.x + w0, node.y + h0, node.width - w0, node.height - h0),
                    ];
                    let children: Vec<QuadNode> = quads
                        .into_iter()
                        .filter(|&(_, _, w, h)| w > 0 && h > 0)
                        .filter_map(|(x, y, w, h)| summarise(map, x, y, w, h))
                        .collect();
                    tree.nodes[k].first_child = Some(first);
                    tree.nodes[k].children = children.len() as u32;
                    tree.nodes.extend(children);
                }
                k += 1;
            }
        }
        Ok(tree)
    }

    /// The leaves, in tree order.
    pub fn leaves(&self) -> impl Iterator<Item = &QuadNode> {
        self.nodes.iter().filter(|n| n.first_child.is_none())
    }

    /// Bytes the nodes take.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<QuadNode>()
    }
}

/// The node over texels `[x, x + w) × [y, y + h)` of `map`, `None` if none of them sees anything.
fn summarise(map: &RadianceMap, x: u32, y: u32, w: u32, h: u32) -> Option<QuadNode> {
    let (mut count, mut z_min, mut z_max) = (0u32, f32::INFINITY, f32::NEG_INFINITY);
    let (mut sum, mut lo, mut hi) = (
        glam::DVec3::ZERO,
        Vec3::splat(f32::INFINITY),
        Vec3::splat(f32::NEG_INFINITY),
    );
    for j in y..y + h {
        for i in x..x + w {
            let z = map.depth[map.index(i, j)];
            if !z.is_finite() {
                continue;
            }
            let p = map
                .camera
                .unproject(SampleCamera::texel_st(i, j, map.width, map.height), z);
            count += 1;
            z_min = z_min.min(z);
            z_max = z_max.max(z);
            sum += p.as_dvec3();
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    (count > 0).then(|| QuadNode {
        x,
        y,
        width: w,
        height: h,
        count,
        z_min,
        z_max,
        representative: (sum / f64::from(count)).as_vec3(),
        bounds_min: lo,
        bounds_max: hi,
        first_child: None,
        children: 0,
    })
}
