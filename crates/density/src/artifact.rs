//! Artifact Control for DETP (section 1.2.1, after Lastra et al. 2002): the reachable area of discs cut by walls and corners, and the extension of rays through concave parts of the vertex's own mesh.
//!
//! **Walls and corners.** "No photon can reach the part of the disc behind
//! the wall. The solution is using the reachable area of the circle in the
//! irradiance estimation." [`reachable_area`] takes `n × n` deterministic
//! stratified points on the disc (the centres of an `n × n` grid of the
//! square, through Shirley & Chiu's equal-area concentric map, so each
//! stands for `π r² / n²`); a point `p` is reachable when the path from the
//! vertex to `p`, lifted `offset · r` above the disc plane, meets no triangle
//! of another mesh. Triangles of the vertex's own mesh are left to the
//! concave rule below, so the two rules never count one region twice. The
//! reachable area is `π r² k / n²` for `k` reachable points. Its error comes
//! only from the grid cells the boundary of the reachable region crosses: at
//! most `π r² c / n²` for `c` such cells, `c ≲ 2.5 n` for a chord (a wall),
//! so at most about `2.5 π r² / n` (8 % at `n = 32`); midpoint sampling makes
//! the signed errors of neighbouring cells cancel, and the error measured
//! against the analytic areas is far smaller (`tests/artifact.rs`: one wall
//! at 25 distances, worst 0.9 %, 0.42 %, 0.41 % of `π r²` at `n` = 16, 32,
//! 64; two perpendicular walls, worst 0.54 % at `n = 32`). The criterion
//! also marks as unreachable a point hidden from the vertex by an obstacle
//! that is not a wall (a pillar between the vertex and `p`).
//!
//! Walls through the vertex itself (a floor vertex on the foot of a wall)
//! are told apart by their orientation: a path leaving such a wall through
//! its front face is not blocked, one entering it is, so the half in front
//! of the wall is reachable. Paths of a vertex on its mesh's border start a
//! little into its own surface ([`inward_directions`]), off the edges of walls
//! that end at the vertex: a floor corner meeting two walls gets a quarter
//! of its disc. A vertex on the free edge of a wall that stops there (the
//! front corners of the open Cornell box) sees partly past that edge.
//!
//! **Concave surfaces.** "Taking into account rays which intersect the disc
//! after intersecting the mesh the vertex is in, but before any other
//! intersection with the scene." [`extension`] follows a segment past its hit
//! through triangles of the mesh it hit until it meets any other triangle,
//! capped at `max`; stored in [`RaySegment::extension`], it lets
//! [`Disc::reach`] count such crossings for discs of that mesh.
//!
//! **Shortcuts** (beyond the paper, same results). A disc that no triangle
//! of another mesh comes near is wholly reachable ([`reachable_area_near`]
//! asks a [`TriangleGrid`] before casting any path), and a mesh that is not
//! concave ([`is_concave`]: no vertex in front of another's tangent plane,
//! such as a wall or a box) cannot have a disc crossed past a hit on it, so
//! the ray set measures the extension only on concave meshes.

use std::collections::HashMap;
use std::f32::consts::PI;
use std::ops::Range;

use glam::Vec3;
use lustre_geometry::sampling::{Frame, sample_concentric_disk};
use lustre_geometry::{Bvh, MeshId, Ray, Scene, TriangleId};
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::detp::{Disc, detp};
use crate::error::{DensityError, Result};
use crate::ray_set::{RaySegment, RaySet};
use crate::triangle_grid::TriangleGrid;

/// Most triangles of the own mesh a query steps through before it gives up.
const MAX_STEPS: usize = 256;

/// How far behind a visibility path's start its BVH queries begin (m): obvhs 0.4's compressed wide BVH, which lustre-geometry used before its eight-wide one, clamped each child box's entry distance to at least `10⁻⁴`, so a thin box, such as a wall's, that the ray left within `10⁻⁴` of its origin was culled and a wall that close was missed; paths start `offset · r` from walls through the vertex (`5 · 10⁻⁵` at `r` = 0.05), which with discs of 0.04 m let half of a corner's blocked paths through. The eight-wide traversal has no such clamp; querying from further back is kept because it changes no result and guards against any traversal that skips hits near the origin.
const BACK_OFF: f32 = 4e-4;

/// Settings of Artifact Control (section 1.2.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtifactOptions {
    /// Points per axis of the stratified grid on the disc (`n²` visibility rays per vertex), at least 1.
    pub samples_per_axis: u32,
    /// Height of the visibility paths above the disc plane, in disc radii (positive).
    pub offset: f32,
    /// Cap of the concave extension, in disc radii (non-negative; 0 disables the concave rule).
    pub max_extension: f32,
}

impl Default for ArtifactOptions {
    fn default() -> Self {
        Self {
            samples_per_axis: 32,
            offset: 1e-3,
            max_extension: 4.0,
        }
    }
}

impl ArtifactOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        if self.samples_per_axis == 0 || self.samples_per_axis > 4096 {
            return Err(DensityError::InvalidOption {
                option: "samples_per_axis",
                message: format!("{} is not in 1..=4096", self.samples_per_axis),
            });
        }
        if !(self.offset > 0.0 && self.offset.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "offset",
                message: format!("{} is not a positive finite height", self.offset),
            });
        }
        if !(self.max_extension >= 0.0 && self.max_extension.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "max_extension",
                message: format!("{} is not a finite non-negative length", self.max_extension),
            });
        }
        Ok(())
    }
}

/// The scene-wide triangle ids of a mesh (they are contiguous, section 1.2.1 "the mesh the vertex is in"); empty for a mesh that does not exist.
pub fn mesh_triangles(scene: &Scene, mesh: MeshId) -> Range<TriangleId> {
    match scene.meshes().get(mesh as usize) {
        Some(m) => {
            let start = scene.triangle_id(mesh, 0);
            start..start + m.indices.len() as TriangleId
        }
        None => 0..0,
    }
}

/// The next distance after `t` (one ulp: two surfaces met at distances one ulp apart are both seen).
fn step_past(t: f32) -> f32 {
    t.next_up()
}

/// Whether the path `origin + t dir`, `t ∈ [0, length]`, meets a triangle outside `own`; a hit within `near` of the origin that the path leaves through its front face is ignored (the path starts on that surface). One any-hit query that passes over the own mesh's triangles: on a dense mesh a path along the surface crosses many of them, and stepping from one to the next with closest-hit queries cost a third of a glossy model's DETP estimate.
fn blocked(
    bvh: &Bvh,
    origin: Vec3,
    dir: Vec3,
    length: f32,
    own: &Range<TriangleId>,
    near: f32,
) -> bool {
    // Queried from `BACK_OFF` behind the origin, distances shifted by it (see `BACK_OFF`).
    let from = origin - BACK_OFF * dir;
    let end = length + BACK_OFF;
    let triangles = bvh.triangles();
    bvh.any_hit_where(&Ray::segment(from, dir, BACK_OFF, end), |id, t| {
        if own.contains(&id) {
            return false;
        }
        if t - BACK_OFF > near {
            return true;
        }
        let [p0, p1, p2] = triangles[id as usize].positions;
        // Leaving through the front face: the surface the path starts on.
        dir.dot((p1 - p0).cross(p2 - p0)) < 0.0
    })
}

/// The reachable area of a disc (section 1.2.1, walls and corners): `π r²` times the fraction of the `n × n` stratified points whose path from the vertex, `offset · r` above the plane, meets no triangle outside `own` (the vertex's mesh). `inward` is a unit tangent direction into the vertex's own surface for a vertex on its mesh's border (zero otherwise, see [`inward_directions`]): the paths start `offset · r` that way, off the edges of walls that end at the vertex (a floor corner). Fails on a bad disc, `inward` or options.
pub fn reachable_area(
    bvh: &Bvh,
    disc: &Disc,
    own: Range<TriangleId>,
    inward: Vec3,
    options: &ArtifactOptions,
) -> Result<f32> {
    check_area_inputs(disc, inward, options)?;
    Ok(reachable_area_unchecked(bvh, disc, &own, inward, options))
}

/// Fails on a bad disc, `inward` or options (the checks of [`reachable_area`]).
fn check_area_inputs(disc: &Disc, inward: Vec3, options: &ArtifactOptions) -> Result<()> {
    options.validate()?;
    check_disc(disc)?;
    if !inward.is_finite() || inward.length() > 1.0 + 1e-3 {
        return Err(DensityError::InvalidOption {
            option: "inward",
            message: format!("{inward} is not a unit or zero direction"),
        });
    }
    Ok(())
}

/// For each vertex of a mesh, the unit direction along its tangent plane into the mesh when the vertex is on the mesh's border (the angles of its triangles, welded by position, sum to less than 2π: the border angle of section 2.9.1), else zero; input to [`reachable_area`].
pub fn inward_directions(positions: &[Vec3], normals: &[Vec3], indices: &[[u32; 3]]) -> Vec<Vec3> {
    let key = |p: Vec3| {
        let p = p + Vec3::ZERO;
        [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
    };
    let mut around: HashMap<[u32; 3], (f32, Vec3)> = HashMap::new();
    for tri in indices {
        let Some(corners) = tri
            .iter()
            .map(|&i| positions.get(i as usize).copied())
            .collect::<Option<Vec<Vec3>>>()
        else {
            continue;
        };
        for k in 0..3 {
            let p = corners[k];
            let a = (corners[(k + 1) % 3] - p).normalize_or_zero();
            let b = (corners[(k + 2) % 3] - p).normalize_or_zero();
            if a == Vec3::ZERO || b == Vec3::ZERO {
                continue;
            }
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            let entry = around.entry(key(p)).or_insert((0.0, Vec3::ZERO));
            entry.0 += angle;
            entry.1 += angle * (a + b).normalize_or_zero();
        }
    }
    positions
        .iter()
        .zip(normals)
        .map(|(&p, &n)| match around.get(&key(p)) {
            Some(&(angle, toward)) if angle < 2.0 * PI - 1e-3 => {
                let n = n.normalize_or_zero();
                (toward - toward.dot(n) * n).normalize_or_zero()
            }
            _ => Vec3::ZERO,
        })
        .collect()
}

/// Fails unless the disc has a finite centre, a positive finite radius and a unit normal.
pub(crate) fn check_disc(disc: &Disc) -> Result<()> {
    let unit = (disc.normal.length() - 1.0).abs() < 1e-3;
    if disc.radius > 0.0 && disc.radius.is_finite() && disc.centre.is_finite() && unit {
        Ok(())
    } else {
        Err(DensityError::InvalidOption {
            option: "disc",
            message: format!(
                "{disc:?} needs a finite centre, a positive finite radius and a unit normal"
            ),
        })
    }
}

/// [`reachable_area`] that first asks `grid` (built over `bvh`'s triangles) whether any triangle outside `own` comes near the disc, and returns `π r²` without casting a path when none does: the same area, since only such triangles block a path ([`crate::triangle_grid`]). Fails as [`reachable_area`] does.
pub fn reachable_area_near(
    bvh: &Bvh,
    grid: &TriangleGrid,
    disc: &Disc,
    own: Range<TriangleId>,
    inward: Vec3,
    options: &ArtifactOptions,
) -> Result<f32> {
    check_area_inputs(disc, inward, options)?;
    Ok(reachable_area_gridded(
        bvh, grid, disc, &own, inward, options,
    ))
}

/// [`reachable_area_near`] without the checks.
fn reachable_area_gridded(
    bvh: &Bvh,
    grid: &TriangleGrid,
    disc: &Disc,
    own: &Range<TriangleId>,
    inward: Vec3,
    options: &ArtifactOptions,
) -> f32 {
    if grid.foreign_near(disc.centre, path_reach(disc, options), own) {
        reachable_area_unchecked(bvh, disc, own, inward, options)
    } else {
        PI * disc.radius * disc.radius
    }
}

/// Half-edge of a cube around the disc's centre that holds every visibility path of [`reachable_area`] (they stay within `r + 3.01 · offset · r` of the centre), with a margin of 1 % of `r` for rounding.
fn path_reach(disc: &Disc, options: &ArtifactOptions) -> f32 {
    disc.radius * (1.01 + 4.0 * options.offset)
}

fn reachable_area_unchecked(
    bvh: &Bvh,
    disc: &Disc,
    own: &Range<TriangleId>,
    inward: Vec3,
    options: &ArtifactOptions,
) -> f32 {
    let n = options.samples_per_axis;
    let r = disc.radius;
    let frame = Frame::from_normal(disc.normal);
    let lift = options.offset * r;
    // Paths start `lift` above the vertex and `lift` into its surface (border vertices), then `lift` behind, so that a wall through the vertex itself is met rather than skipped, and `10⁻³ lift` to the side, so that a path does not run through the line where two such walls meet (both would be met at one distance, and the one skipped first could hide the other).
    let near = 3.0 * lift;
    let lifted = disc.centre + lift * (disc.normal + inward);
    let mut reachable = 0u64;
    for j in 0..n {
        for i in 0..n {
            let u = glam::Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let d = sample_concentric_disk(u) * r;
            let offset = frame.s * d.x + frame.t * d.y;
            let length = offset.length();
            if !(length > 0.0) {
                reachable += 1;
                continue;
            }
            let dir = offset / length;
            let start = lifted + lift * (1e-3 * disc.normal.cross(dir) - dir);
            let path = disc.centre + lift * disc.normal + offset - start;
            let span = path.length();
            if !blocked(bvh, start, path / span, span, own, near) {
                reachable += 1;
            }
        }
    }
    PI * r * r * reachable as f32 / (n as f32 * n as f32)
}

/// Reachable areas of every vertex (section 1.2.1), `[mesh][vertex]`, with discs of `radius` on the tangent planes of the meshes' world normals as [`detp`] does, in parallel; zero for a vertex without a valid normal. Fails on a bad radius or options, or a BVH of another scene.
pub fn reachable_areas(
    scene: &Scene,
    bvh: &Bvh,
    radius: f32,
    options: &ArtifactOptions,
) -> Result<Vec<Vec<f32>>> {
    check_common(scene, bvh, radius, options)?;
    let grid = TriangleGrid::new(bvh, 2.0 * radius);
    Ok((0..scene.meshes().len() as MeshId)
        .map(|m| {
            let own = mesh_triangles(scene, m);
            let positions = scene.world_positions(m);
            let normals = scene.world_normals(m);
            let inward =
                inward_directions(&positions, &normals, &scene.meshes()[m as usize].indices);
            positions
                .par_iter()
                .zip(normals.par_iter())
                .zip(inward.par_iter())
                .map(|((&centre, &normal), &inward)| {
                    let normal = normal.normalize_or_zero();
                    if normal == Vec3::ZERO {
                        return 0.0;
                    }
                    let disc = Disc {
                        centre,
                        normal,
                        radius,
                        mesh: Some(m),
                    };
                    reachable_area_gridded(bvh, &grid, &disc, &own, inward, options)
                })
                .collect()
        })
        .collect())
}

fn check_common(scene: &Scene, bvh: &Bvh, radius: f32, options: &ArtifactOptions) -> Result<()> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(DensityError::InvalidOption {
            option: "radius",
            message: format!("{radius} is not a positive finite disc radius"),
        });
    }
    options.validate()?;
    if bvh.len() != scene.triangle_count() {
        return Err(DensityError::InvalidOption {
            option: "bvh",
            message: format!(
                "the BVH holds {} triangles, the scene {}",
                bvh.len(),
                scene.triangle_count()
            ),
        });
    }
    Ok(())
}

/// The concave extension of a segment (section 1.2.1): how far past its hit it can be followed through triangles in `own` (the hit triangle's mesh) before it meets any other triangle, at most `max`; zero for a segment that leaves the scene, whose hit is not in `own`, or for a `max` that is not positive and finite.
pub fn extension(bvh: &Bvh, segment: &RaySegment, own: Range<TriangleId>, max: f32) -> f32 {
    let Some(hit) = segment.hit else {
        return 0.0;
    };
    if !(max > 0.0 && max.is_finite() && own.contains(&hit.triangle)) {
        return 0.0;
    }
    let end = hit.distance + max;
    let mut t = hit.distance;
    for _ in 0..MAX_STEPS {
        match bvh.closest_hit(&Ray::segment(segment.origin, segment.direction, t, end)) {
            None => return max,
            Some(h) if own.contains(&h.triangle) => t = step_past(h.t),
            Some(h) => return (h.t - hit.distance).clamp(0.0, max),
        }
    }
    (t - hit.distance).clamp(0.0, max)
}

/// Most vertices of a mesh that [`is_concave`] tests (the test is quadratic); a larger mesh counts as concave.
pub const MAX_CONVEXITY_VERTICES: usize = 4096;

/// Whether the concave rule (section 1.2.1) can matter on a mesh: some vertex lies more than `tolerance` in front of another vertex's tangent plane. A ray followed past its hit on a mesh that is not concave (a flat wall, a box) only goes further behind every tangent plane of the mesh, so its extension could only add crossings within `tolerance / |cos|` past the hit, which the slack of [`Disc::is_crossed_by`] already covers unless the ray runs almost along the plane; the ray set leaves such segments unextended. A mesh that does not exist or has more than [`MAX_CONVEXITY_VERTICES`] vertices counts as concave.
pub fn is_concave(scene: &Scene, mesh: MeshId, tolerance: f32) -> bool {
    let Some(m) = scene.meshes().get(mesh as usize) else {
        return true;
    };
    if m.positions.len() > MAX_CONVEXITY_VERTICES {
        return true;
    }
    let positions = scene.world_positions(mesh);
    let normals = scene.world_normals(mesh);
    positions
        .par_iter()
        .zip(normals.par_iter())
        .any(|(&v, &n)| {
            let n = n.normalize_or_zero();
            n != Vec3::ZERO && positions.iter().any(|&x| (x - v).dot(n) > tolerance)
        })
}

/// Sets [`RaySegment::extension`] of every segment of a ray set (section 1.2.1, concave surfaces), in parallel, through the mesh each segment hit, capped at `max`. Fails on a `max` that is negative or not finite, or a BVH of another scene.
pub fn extend_ray_set(scene: &Scene, bvh: &Bvh, rays: &mut RaySet, max: f32) -> Result<()> {
    if !(max >= 0.0 && max.is_finite()) {
        return Err(DensityError::InvalidOption {
            option: "max_extension",
            message: format!("{max} is not a finite non-negative length"),
        });
    }
    if bvh.len() != scene.triangle_count() {
        return Err(DensityError::InvalidOption {
            option: "bvh",
            message: format!(
                "the BVH holds {} triangles, the scene {}",
                bvh.len(),
                scene.triangle_count()
            ),
        });
    }
    rays.rays.par_iter_mut().for_each(|r| {
        for s in &mut r.segments {
            s.extension = match s.hit {
                Some(h) => extension(bvh, s, mesh_triangles(scene, h.mesh), max),
                None => 0.0,
            };
        }
    });
    Ok(())
}

/// DETP with Artifact Control (section 1.2.1): the ray set's segments extended through their own meshes (`max_extension · radius`), then `E = Σ φ / A_reach` with each vertex's reachable area instead of `π r²`; zero where nothing is reachable. Fails on a bad radius or options, or a BVH of another scene.
pub fn artifact_controlled_detp(
    scene: &Scene,
    bvh: &Bvh,
    rays: &RaySet,
    radius: f32,
    options: &ArtifactOptions,
) -> Result<VertexIrradiance> {
    check_common(scene, bvh, radius, options)?;
    let mut extended = rays.clone();
    extend_ray_set(scene, bvh, &mut extended, options.max_extension * radius)?;
    let mut e = detp(scene, &extended, radius)?;
    let areas = reachable_areas(scene, bvh, radius, options)?;
    let full = PI * radius * radius;
    for (em, am) in e.iter_mut().zip(&areas) {
        for (ev, &a) in em.iter_mut().zip(am) {
            *ev = if a > 0.0 {
                *ev * (full / a)
            } else {
                Vec3::ZERO
            };
        }
    }
    Ok(e)
}
