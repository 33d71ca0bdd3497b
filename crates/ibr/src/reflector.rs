//! Planar reflectors and their reflector elements (Bastos et al. 1999, section 8.1.3, "Sampling of the plenoptic function", first stage).
//!
//! A reflector is a planar surface of the scene, described by the rectangle
//! of least area that bounds its triangles in its plane: a centre, two unit
//! in-plane axes `u`, `v` and half-extents. The rectangle's edges are
//! aligned with one of the surface's own edges (for a rectangular or
//! square surface, its sides), chosen as the edge direction whose bounding
//! rectangle has least area. Sampling the reflector "uniformly at a given
//! planar resolution" cuts this rectangle into `nu × nv` equal
//! quadrilaterals, the reflector elements; each element inscribes the base
//! of its hemisphere, whose radius is therefore half the element's
//! diagonal.

use glam::Vec3;
use lustre_geometry::{Plane, Scene, SurfaceKind};

use crate::error::{IbrError, Result, out_of_range};

/// A planar reflector: the bounding rectangle of a planar surface in its plane (section 8.1.3).
#[derive(Debug, Clone, PartialEq)]
pub struct Reflector {
    /// The scene's surface id.
    pub surface: u32,
    /// The reflector's plane; its normal points to the side the reflector reflects.
    pub plane: Plane,
    /// Centre of the bounding rectangle.
    pub centre: Vec3,
    /// Unit in-plane axis of the rectangle's first side.
    pub u: Vec3,
    /// Unit in-plane axis of the second side, `normal × u`.
    pub v: Vec3,
    /// Half the rectangle's extent along `u`.
    pub half_u: f32,
    /// Half the rectangle's extent along `v`.
    pub half_v: f32,
}

/// One reflector element: a quadrilateral of the reflector at the planar resolution, the base of one hemisphere of sample cameras (section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReflectorElement {
    /// Its centre, the centre of its hemisphere.
    pub centre: Vec3,
    /// Unit in-plane axis `u` (the reflector's).
    pub u: Vec3,
    /// Unit in-plane axis `v` (the reflector's).
    pub v: Vec3,
    /// Unit normal, towards the reflected side.
    pub normal: Vec3,
    /// Half the element's extent along `u`.
    pub half_u: f32,
    /// Half the element's extent along `v`.
    pub half_v: f32,
}

impl ReflectorElement {
    /// The hemisphere's radius: the element inscribes its base, so half its diagonal.
    pub fn hemisphere_radius(&self) -> f32 {
        (self.half_u * self.half_u + self.half_v * self.half_v).sqrt()
    }

    /// Its corners, counter-clockwise about the normal from `-u -v`.
    pub fn corners(&self) -> [Vec3; 4] {
        let (du, dv) = (self.u * self.half_u, self.v * self.half_v);
        [
            self.centre - du - dv,
            self.centre + du - dv,
            self.centre + du + dv,
            self.centre - du + dv,
        ]
    }
}

impl Reflector {
    /// The reflector of planar surface `surface` of `scene`: its least-area bounding rectangle, edge-aligned (module documentation).
    pub fn from_surface(scene: &Scene, surface: u32) -> Result<Self> {
        let s = scene
            .surfaces()
            .get(surface as usize)
            .ok_or_else(|| out_of_range("surface", surface, "a surface id of the scene"))?;
        let SurfaceKind::Planar(plane) = s.kind else {
            return Err(IbrError::NotAReflector {
                surface,
                reason: "it is curved".into(),
            });
        };
        let positions = scene.world_positions(s.mesh);
        let mesh = &scene.meshes()[s.mesh as usize];
        let corners: Vec<Vec3> = s
            .triangles
            .iter()
            .flat_map(|&t| mesh.indices[t as usize])
            .map(|i| positions[i as usize])
            .collect();
        Self::from_points(surface, plane, &corners)
    }

    /// The least-area edge-aligned bounding rectangle in `plane` of `corners`, taken three at a time as triangles.
    pub fn from_points(surface: u32, plane: Plane, corners: &[Vec3]) -> Result<Self> {
        let n = plane.normal;
        let not = |reason: &str| IbrError::NotAReflector {
            surface,
            reason: reason.into(),
        };
        if corners.len() < 3 || !n.is_finite() {
            return Err(not("it has no triangle"));
        }
        let mut best: Option<(f32, Self)> = None;
        for tri in corners.chunks_exact(3) {
            for k in 0..3 {
                let edge = tri[(k + 1) % 3] - tri[k];
                let edge = edge - n * n.dot(edge);
                if !(edge.length_squared() > 1e-12) {
                    continue;
                }
                let u = edge.normalize();
                let v = n.cross(u);
                let (mut lo, mut hi) = (
                    glam::Vec2::splat(f32::INFINITY),
                    glam::Vec2::splat(f32::NEG_INFINITY),
                );
                for &p in corners {
                    let q = glam::Vec2::new(p.dot(u), p.dot(v));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                let size = hi - lo;
                let area = size.x * size.y;
                if best.as_ref().is_none_or(|(a, _)| area < *a - 1e-9) {
                    let mid = (lo + hi) * 0.5;
                    let centre = u * mid.x + v * mid.y + n * plane.offset;
                    best = Some((
                        area,
                        Self {
                            surface,
                            plane,
                            centre,
                            u,
                            v,
                            half_u: 0.5 * size.x,
                            half_v: 0.5 * size.y,
                        },
                    ));
                }
            }
        }
        match best {
            Some((area, r)) if area > 0.0 && area.is_finite() => Ok(r),
            _ => Err(not("it has no area")),
        }
    }

    /// The reflector's area (of its bounding rectangle).
    pub fn area(&self) -> f32 {
        4.0 * self.half_u * self.half_v
    }

    /// The `nu × nv` reflector elements at planar resolution `(nu, nv)`, row by row along `v` (section 8.1.3: "we uniformly sample the planar reflector at a given planar resolution").
    pub fn elements(&self, nu: u32, nv: u32) -> Result<Vec<ReflectorElement>> {
        if !(1..=1024).contains(&nu) || !(1..=1024).contains(&nv) {
            return Err(out_of_range(
                "planar resolution",
                format!("{nu}x{nv}"),
                "1 to 1024 elements per side",
            ));
        }
        let (hu, hv) = (self.half_u / nu as f32, self.half_v / nv as f32);
        let mut out = Vec::with_capacity((nu * nv) as usize);
        for j in 0..nv {
            for i in 0..nu {
                let su = -self.half_u + (2 * i + 1) as f32 * hu;
                let sv = -self.half_v + (2 * j + 1) as f32 * hv;
                out.push(ReflectorElement {
                    centre: self.centre + self.u * su + self.v * sv,
                    u: self.u,
                    v: self.v,
                    normal: self.plane.normal,
                    half_u: hu,
                    half_v: hv,
                });
            }
        }
        Ok(out)
    }
}
