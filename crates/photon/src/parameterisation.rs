//! The position of a hit on its surface (section 3.1, "the position on the surface (u, v)").
//!
//! The paper stores a hit as a surface number and a position `(u, v)` on it
//! but does not say how surfaces are parameterised. Lustre defines:
//!
//! - **Planar surfaces** ([`SurfaceKind::Planar`]): a [`PlanarFrame`] with an
//!   origin (the first corner of the surface's first triangle) and two
//!   orthonormal in-plane axes: `u_axis` along that triangle's first edge,
//!   `v_axis = normal × u_axis`, so `(u_axis, v_axis, normal)` is
//!   right-handed. `(u, v)` are metres along the axes:
//!   `x = origin + u u_axis + v v_axis`. The frame also bounds the surface's
//!   corners in `(u, v)` (used to quantise positions on disk) and is the
//!   shading frame for BRDFs on the surface (tangent = `u_axis`).
//! - **Curved surfaces** ([`SurfaceKind::Curved`]): the index of the
//!   triangle within [`Surface::triangles`] plus the barycentric weights
//!   `(b1, b2)` of its corners 1 and 2 (corner 0 weighs `1 - b1 - b2`).

use glam::{Vec2, Vec3};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Scene, Surface, SurfaceId, SurfaceKind, TriangleId};

/// The planar parameterisation of one planar surface (section 3.1): origin, orthonormal axes, bounds in `(u, v)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarFrame {
    /// The point with `(u, v) = (0, 0)`.
    pub origin: Vec3,
    /// Unit first in-plane axis.
    pub u_axis: Vec3,
    /// Unit second in-plane axis, `normal × u_axis`.
    pub v_axis: Vec3,
    /// Unit plane normal (the winding's side).
    pub normal: Vec3,
    /// Smallest `(u, v)` of the surface's corners.
    pub min: Vec2,
    /// Largest `(u, v)` of the surface's corners.
    pub max: Vec2,
}

impl PlanarFrame {
    /// `(u, v)` of a world point, projected onto the plane.
    pub fn to_uv(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.u_axis), d.dot(self.v_axis))
    }

    /// The world point at `(u, v)`.
    pub fn to_world(&self, uv: Vec2) -> Vec3 {
        self.origin + uv.x * self.u_axis + uv.y * self.v_axis
    }

    /// The shading frame `(u_axis, v_axis, normal)`, flipped to `(u_axis, -v_axis, -normal)` when `side` is below the plane (two-sided surfaces).
    pub fn shading_frame(&self, side: Vec3) -> Frame {
        if side.dot(self.normal) >= 0.0 {
            Frame {
                s: self.u_axis,
                t: self.v_axis,
                n: self.normal,
            }
        } else {
            Frame {
                s: self.u_axis,
                t: -self.v_axis,
                n: -self.normal,
            }
        }
    }
}

/// How positions on one surface are written (section 3.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceParam {
    /// `(u, v)` in metres in a [`PlanarFrame`].
    Planar(PlanarFrame),
    /// Triangle index within the surface plus barycentrics `(b1, b2)`.
    Curved,
}

/// The parameterisation of every surface of a scene (section 3.1), with the lookups the tracer and the estimator need.
#[derive(Debug, Clone)]
pub struct SurfaceParams {
    /// One per surface.
    params: Vec<SurfaceParam>,
    /// Scene-wide ids of each surface's triangles, in [`Surface::triangles`] order.
    triangle_ids: Vec<Vec<TriangleId>>,
    /// Index within its surface of every scene-wide triangle.
    local_index: Vec<u32>,
    /// World corners of every scene-wide triangle.
    corners: Vec<[Vec3; 3]>,
    /// Texture coordinates of the corners of every scene-wide triangle.
    uvs: Vec<[Vec2; 3]>,
    /// Surface areas in m².
    areas: Vec<f32>,
}

/// A frame for a planar surface from its plane normal and first triangle.
fn planar_frame(normal: Vec3, triangles: &[[Vec3; 3]]) -> PlanarFrame {
    let first = triangles.first().copied().unwrap_or([Vec3::ZERO; 3]);
    let origin = first[0];
    let edge = first[1] - first[0];
    let u_axis = (edge - edge.dot(normal) * normal)
        .try_normalize()
        .unwrap_or_else(|| Frame::from_normal(normal).s);
    let v_axis = normal.cross(u_axis).normalize_or_zero();
    let mut frame = PlanarFrame {
        origin,
        u_axis,
        v_axis,
        normal,
        min: Vec2::splat(f32::INFINITY),
        max: Vec2::splat(f32::NEG_INFINITY),
    };
    for t in triangles {
        for &p in t {
            let uv = frame.to_uv(p);
            frame.min = frame.min.min(uv);
            frame.max = frame.max.max(uv);
        }
    }
    if !frame.min.is_finite() || !frame.max.is_finite() {
        frame.min = Vec2::ZERO;
        frame.max = Vec2::ZERO;
    }
    frame
}

impl SurfaceParams {
    /// Parameterises every surface of the scene in its current pose.
    pub fn new(scene: &Scene) -> Self {
        let world = scene.world_triangles();
        let corners: Vec<[Vec3; 3]> = world.iter().map(|t| t.positions).collect();
        let uvs: Vec<[Vec2; 3]> = world.iter().map(|t| t.uvs).collect();
        let mut local_index = vec![0u32; corners.len()];
        let mut triangle_ids = Vec::with_capacity(scene.surfaces().len());
        let mut params = Vec::with_capacity(scene.surfaces().len());
        for surface in scene.surfaces() {
            let ids: Vec<TriangleId> = surface
                .triangles
                .iter()
                .map(|&t| scene.triangle_id(surface.mesh, t))
                .collect();
            for (i, &id) in ids.iter().enumerate() {
                local_index[id as usize] = i as u32;
            }
            params.push(match surface.kind {
                SurfaceKind::Planar(plane) => {
                    let tris: Vec<[Vec3; 3]> = ids.iter().map(|&id| corners[id as usize]).collect();
                    SurfaceParam::Planar(planar_frame(plane.normal, &tris))
                }
                SurfaceKind::Curved => SurfaceParam::Curved,
            });
            triangle_ids.push(ids);
        }
        Self {
            params,
            triangle_ids,
            local_index,
            corners,
            uvs,
            areas: scene.surfaces().iter().map(|s: &Surface| s.area).collect(),
        }
    }

    /// Number of surfaces.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether the scene has no surface.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameterisation of a surface; `None` when it does not exist.
    pub fn get(&self, surface: SurfaceId) -> Option<&SurfaceParam> {
        self.params.get(surface as usize)
    }

    /// All parameterisations, by surface id.
    pub fn all(&self) -> &[SurfaceParam] {
        &self.params
    }

    /// Area of a surface in m² (0 when it does not exist).
    pub fn area(&self, surface: SurfaceId) -> f32 {
        self.areas.get(surface as usize).copied().unwrap_or(0.0)
    }

    /// Number of triangles of a surface.
    pub fn triangle_count(&self, surface: SurfaceId) -> usize {
        self.triangle_ids.get(surface as usize).map_or(0, Vec::len)
    }

    /// Index within its surface of a scene-wide triangle.
    pub fn local_triangle(&self, triangle: TriangleId) -> u32 {
        self.local_index
            .get(triangle as usize)
            .copied()
            .unwrap_or(u32::MAX)
    }

    /// World corners of triangle `local` of `surface`.
    pub fn corners(&self, surface: SurfaceId, local: u32) -> Option<[Vec3; 3]> {
        let id = *self
            .triangle_ids
            .get(surface as usize)?
            .get(local as usize)?;
        self.corners.get(id as usize).copied()
    }

    /// The position `(u, v)` recorded for a world point `p` on triangle `triangle` (scene-wide) of `surface`, whose barycentrics are `bary` (section 3.1).
    pub fn position_of(&self, surface: SurfaceId, p: Vec3, bary: Vec2) -> Vec2 {
        match self.get(surface) {
            Some(SurfaceParam::Planar(frame)) => frame.to_uv(p),
            _ => bary,
        }
    }

    /// The affine texture mapping of triangle `triangle` (within the surface), extended over its plane; `None` for a surface or triangle that does not exist, or a degenerate triangle.
    pub fn texture_map(&self, surface: SurfaceId, triangle: u32) -> Option<UvMap> {
        let id = *self
            .triangle_ids
            .get(surface as usize)?
            .get(triangle as usize)?;
        UvMap::new(*self.corners.get(id as usize)?, *self.uvs.get(id as usize)?)
    }

    /// The world point of a recorded position; `None` for a surface or triangle that does not exist.
    pub fn world_position(&self, surface: SurfaceId, triangle: u32, uv: Vec2) -> Option<Vec3> {
        match self.get(surface)? {
            SurfaceParam::Planar(frame) => Some(frame.to_world(uv)),
            SurfaceParam::Curved => {
                let [a, b, c] = self.corners(surface, triangle)?;
                Some(a + uv.x * (b - a) + uv.y * (c - a))
            }
        }
    }
}

/// A triangle's texture mapping extended over its plane: `uv(x) = uv + (du · (x − origin), dv · (x − origin))`, exact on the triangle, and on the neighbours that share its affine mapping (a quad's two halves); the mapping the splats of its photons read their diffuse map by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvMap {
    /// The triangle's corner 0.
    pub origin: Vec3,
    /// Texture coordinates at `origin`.
    pub uv: Vec2,
    /// Gradient of `u` in the plane (per m).
    pub du: Vec3,
    /// Gradient of `v` in the plane (per m).
    pub dv: Vec3,
}

impl UvMap {
    /// The mapping of the triangle with world corners `p` and texture coordinates `t`; `None` when it is degenerate.
    pub fn new(p: [Vec3; 3], t: [Vec2; 3]) -> Option<Self> {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if !(det.abs() > f32::EPSILON * d11 * d22) {
            return None;
        }
        // Gradients of the barycentrics b1 and b2 in the plane.
        let g1 = (d22 * e1 - d12 * e2) / det;
        let g2 = (d11 * e2 - d12 * e1) / det;
        let (t1, t2) = (t[1] - t[0], t[2] - t[0]);
        Some(Self {
            origin: p[0],
            uv: t[0],
            du: g1 * t1.x + g2 * t2.x,
            dv: g1 * t1.y + g2 * t2.y,
        })
    }

    /// The texture coordinates at a world point (projected onto the plane).
    pub fn at(&self, x: Vec3) -> Vec2 {
        let d = x - self.origin;
        self.uv + Vec2::new(self.du.dot(d), self.dv.dot(d))
    }
}
