//! Reprojection of radiance maps into a reflected view as sized points, and their reconstruction (Bastos et al. 1999, section 8.1.3, "Reprojection" and "Reconstruction", equation 3).
//!
//! **Reprojection.** A texel's world point is its camera's
//! [`crate::sampling::SampleCamera::unproject`] at its depth, projected into the desired
//! (reflected) view ([`PinholeView::project`]).
//!
//! **Point size, equation 3.** `PointSize = 1/Step = DistanceScale ·
//! Angular / Window` per axis. Derivation, for a point `X` at reference
//! depth `zr` and desired depth `zd`: the texel is a patch parallel to the
//! reference image plane of world size `zr/frx` along `u` and `zr/fry`
//! along `v` (`fr` the reference focal lengths in pixels, [`crate::sampling::SampleCamera`]'s
//! pinhole). The desired view maps a small world offset `Δ` at `X` to the
//! pixel offset `(fdx/zd) Δ·ax` along x, with `ax = xd − (xc/zd) fd` its
//! local x axis (`xd`, `fd` the desired right and forward axes, `xc` the
//! point's desired camera x; the second term is the perspective change of
//! a depth offset off the view's centre). So the patch spans
//! `(fdx/zd)(zr/frx |u·ax| + zr/fry |v·ax|)` pixels along x. Hence
//! `DistanceScale = zr/zd` (the paper's `Ref_depth/Des_depth`),
//! `Window_x = frx/fdx` (the resolution scaling from the reference to the
//! desired image, in pixels per unit of `tan` angle) and
//! `Angular_x = |u·ax| + (frx/fry)|v·ax|` (the dot products of the
//! desired axes with the reference X and Y axes; at the view's centre `ax`
//! is the desired x axis itself), and likewise for y with `u`, `v`
//! swapped. The size is estimated once per quadtree leaf at its
//! representative point (the paper's cost-saving hierarchy) or per texel
//! ([`PointSizing::PerPoint`], the paper's best and slowest).
//!
//! **Magnification and minification.** A size of at least one pixel is
//! drawn as a screen-aligned box of that size (zero-order reconstruction,
//! a box splat). Below one pixel the leaf is minified: every
//! `Step = ⌊1/size⌋`-th texel is reprojected along that axis, drawn at
//! `size · Step` pixels, so that the skipped texels' area is still covered.
//!
//! **Culling.** A quadtree node whose world bounds lie wholly behind the
//! desired eye or wholly off one side of its image is skipped with its
//! subtree (the paper's view-frustum culling of sub-regions).
//!
//! [`reconstruct`] draws the points into an image with a depth test, the
//! CPU counterpart of the GPU reprojection pass in `lustre-mpr`.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::quadtree::{MapQuadtree, QuadNode};
use crate::radiance_map::RadianceMap;
use crate::view::PinholeView;

/// Where equation 3's point size is estimated (section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PointSizing {
    /// Once per quadtree leaf, at its representative point (the paper's hierarchy).
    #[default]
    PerNode,
    /// At every texel's own point (the paper's best and slowest).
    PerPoint,
}

/// One reprojected point: pixel position, desired depth, box size in pixels, radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectedPoint {
    /// Pixel position (row 0 at the top).
    pub pixel: Vec2,
    /// Depth along the desired view's axis.
    pub depth: f32,
    /// Width and height of its box in pixels.
    pub size: Vec2,
    /// Its radiance.
    pub radiance: Rgb,
}

/// Equation 3's factors at a point, for inspection and tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSizeTerms {
    /// `Ref_depth / Des_depth`.
    pub distance_scale: f32,
    /// `Angular_x`, `Angular_y`.
    pub angular: Vec2,
    /// `Window_x`, `Window_y`: reference over desired focal length.
    pub window: Vec2,
}

impl PointSizeTerms {
    /// `PointSize = DistanceScale · Angular / Window` per axis (equation 3).
    pub fn point_size(&self) -> Vec2 {
        self.distance_scale * self.angular / self.window
    }
}

/// Equation 3's factors for world point `x` of a map seen by `reference` (its sample camera's [`crate::sampling::SampleCamera::pinhole`]) and by `desired`; `None` if `x` is not in front of both.
pub fn point_size_terms(
    reference: &PinholeView,
    desired: &PinholeView,
    x: Vec3,
) -> Option<PointSizeTerms> {
    let zr = reference.camera_coordinates(x).z;
    let c = desired.camera_coordinates(x);
    let zd = c.z;
    if !(zr > 0.0 && zd > 0.0) {
        return None;
    }
    let (u, v) = (reference.right, -reference.up);
    let fr = reference.focal;
    // The desired view's local axes at X (module documentation).
    let ax = desired.right - desired.forward * (c.x / zd);
    let ay = desired.up - desired.forward * (c.y / zd);
    let angular = Vec2::new(
        u.dot(ax).abs() + fr.x / fr.y * v.dot(ax).abs(),
        v.dot(ay).abs() + fr.y / fr.x * u.dot(ay).abs(),
    );
    Some(PointSizeTerms {
        distance_scale: zr / zd,
        angular,
        window: fr / desired.focal,
    })
}

/// Whether a node's world bounds lie wholly behind `view`'s eye or wholly off one side of its image.
fn culled(node: &QuadNode, view: &PinholeView) -> bool {
    let (lo, hi) = (node.bounds_min, node.bounds_max);
    let corners = (0..8).map(|k| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    });
    let cs: Vec<Vec3> = corners.map(|c| view.camera_coordinates(c)).collect();
    if cs.iter().all(|c| c.z <= 0.0) {
        return true;
    }
    if cs.iter().any(|c| c.z <= 0.0) {
        return false;
    }
    let px: Vec<Vec2> = cs.iter().map(|&c| view.pixel(c)).collect();
    let (w, h) = (view.width as f32, view.height as f32);
    px.iter().all(|p| p.x < 0.0)
        || px.iter().all(|p| p.x > w)
        || px.iter().all(|p| p.y < 0.0)
        || px.iter().all(|p| p.y > h)
}

/// One quadtree leaf to draw: its texel rectangle, the step its texels are taken at and the point size at its representative (equation 3; `None` where the representative is not in front of both views).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeafDraw {
    /// First texel column.
    pub x: u32,
    /// First texel row.
    pub y: u32,
    /// Columns covered.
    pub width: u32,
    /// Rows covered.
    pub height: u32,
    /// Every `step`-th texel is drawn along each axis (minification).
    pub step: glam::UVec2,
    /// Equation 3's point size at the leaf's representative point, in pixels.
    pub size: Option<Vec2>,
}

impl LeafDraw {
    /// The box size a point of this leaf is drawn at: `size · step`, at least one pixel.
    pub fn drawn_size(&self, size: Vec2) -> Vec2 {
        (size * self.step.as_vec2()).max(Vec2::ONE)
    }

    /// How many texels it draws: `⌈width/step.x⌉ · ⌈height/step.y⌉`.
    pub fn texels(&self) -> u32 {
        self.width.div_ceil(self.step.x) * self.height.div_ceil(self.step.y)
    }
}

/// The leaves of `tree` that survive view-frustum culling against `desired`, in drawing order, each with its step and representative point size (module documentation).
pub fn leaf_draws(map: &RadianceMap, tree: &MapQuadtree, desired: &PinholeView) -> Vec<LeafDraw> {
    let mut out = Vec::new();
    if tree.nodes.is_empty() {
        return out;
    }
    let reference = map.camera.pinhole(map.width, map.height);
    let mut stack = vec![0usize];
    while let Some(k) = stack.pop() {
        let node = &tree.nodes[k];
        if culled(node, desired) {
            continue;
        }
        if let Some(first) = node.first_child {
            stack.extend((first..first + node.children).map(|c| c as usize));
            continue;
        }
        let size =
            point_size_terms(&reference, desired, node.representative).map(|t| t.point_size());
        out.push(LeafDraw {
            x: node.x,
            y: node.y,
            width: node.width,
            height: node.height,
            step: size.map_or(glam::UVec2::ONE, step_of),
            size,
        });
    }
    out
}

/// The points of `map` reprojected into `desired`, sized by equation 3 under `sizing`, minified leaves thinned by their step, culled by `tree` (module documentation).
pub fn reproject(
    map: &RadianceMap,
    tree: &MapQuadtree,
    desired: &PinholeView,
    sizing: PointSizing,
) -> Vec<ProjectedPoint> {
    let mut out = Vec::new();
    let reference = map.camera.pinhole(map.width, map.height);
    for leaf in leaf_draws(map, tree, desired) {
        if sizing == PointSizing::PerNode && leaf.size.is_none() {
            continue;
        }
        for j in (leaf.y..leaf.y + leaf.height).step_by(leaf.step.y as usize) {
            for i in (leaf.x..leaf.x + leaf.width).step_by(leaf.step.x as usize) {
                let Some(x) = map.world_point(i, j) else {
                    continue;
                };
                let Some((pixel, depth)) = desired.project(x) else {
                    continue;
                };
                let size = match sizing {
                    PointSizing::PerNode => leaf.size,
                    PointSizing::PerPoint => {
                        point_size_terms(&reference, desired, x).map(|t| t.point_size())
                    }
                };
                let Some(size) = size else { continue };
                out.push(ProjectedPoint {
                    pixel,
                    depth,
                    size: leaf.drawn_size(size),
                    radiance: map.radiance_at(i, j),
                });
            }
        }
    }
    out
}

/// `Step = ⌊1/size⌋` per axis, at least 1 (minification).
fn step_of(size: Vec2) -> glam::UVec2 {
    let s = |x: f32| {
        if x > 0.0 && x < 1.0 {
            ((1.0 / x).floor() as u32).clamp(1, 64)
        } else {
            1
        }
    };
    glam::UVec2::new(s(size.x), s(size.y))
}

/// A reconstructed reflected image: radiance and depth per pixel (`+∞` where no point landed).
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Radiance per pixel, row-major.
    pub radiance: Vec<Rgb>,
    /// Desired depth per pixel.
    pub depth: Vec<f32>,
}

impl ReflectedImage {
    /// An empty image.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Self {
            width,
            height,
            radiance: vec![Rgb::ZERO; n],
            depth: vec![f32::INFINITY; n],
        }
    }

    /// Whether pixel `(x, y)` received a point.
    pub fn covered(&self, x: u32, y: u32) -> bool {
        self.depth[(y * self.width + x) as usize].is_finite()
    }
}

/// Draws `points` into `image` as depth-tested screen-aligned boxes: each covers the pixels whose centres lie in `[p − size/2, p + size/2)` (zero-order reconstruction, section 8.1.3).
pub fn reconstruct(image: &mut ReflectedImage, points: &[ProjectedPoint]) {
    let (w, h) = (image.width as i64, image.height as i64);
    for p in points {
        let lo = p.pixel - 0.5 * p.size;
        let hi = p.pixel + 0.5 * p.size;
        // Pixel x covers centre x + 0.5: x + 0.5 >= lo and x + 0.5 < hi.
        let x0 = ((lo.x - 0.5).ceil() as i64).max(0);
        let x1 = ((hi.x - 0.5).ceil() as i64).min(w);
        let y0 = ((lo.y - 0.5).ceil() as i64).max(0);
        let y1 = ((hi.y - 0.5).ceil() as i64).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let k = (y * w + x) as usize;
                if p.depth < image.depth[k] {
                    image.depth[k] = p.depth;
                    image.radiance[k] = p.radiance;
                }
            }
        }
    }
}
