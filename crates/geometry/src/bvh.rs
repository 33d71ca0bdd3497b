//! Ray queries on a binary PLOC BVH (Meister & Bittner 2018, built by obvhs)
//! collapsed to eight children per node with `f32` boxes and leaves of
//! triangles tested four at once ([`crate::wide_bvh`]): closest hit and any
//! hit, single rays and rayon-parallel batches, and box queries.

use glam::{Vec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance};
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use crate::material::MaterialId;
use crate::ray::{Hit, LeanHit, Ray};
use crate::scene::{Scene, SurfaceId, TriangleId, WorldTriangle};
use crate::wide_bvh::WideBvh;

/// A BVH over every triangle of a scene in world space.
///
/// It holds its own copy of the world-space triangles, so it answers queries
/// without the scene; after [`Scene::set_object_transform`] build it again with
/// [`Bvh::build`] (a full PLOC rebuild is cheap at the sizes the papers use).
#[derive(Debug, Clone)]
pub struct Bvh {
    /// The eight-wide BVH (`None` when there is no triangle).
    wide: Option<WideBvh>,
    /// The world-space triangles, by scene-wide triangle id.
    triangles: Vec<WorldTriangle>,
    /// What [`Bvh::closest_hit`]'s record reads of each triangle, by scene-wide id.
    shading: Vec<Shading>,
    /// Each triangle's material.
    materials: Materials,
}

/// The part of a triangle's record that the leaves do not hold, in one cache
/// line: corner normals, corner UVs and surface (the geometric normal comes
/// from the edges the triangle test has just read, the material from
/// [`Materials`]). On incoherent rays over a large scene the record's read is
/// a cache miss that evicts the traversal's nodes; one 64-byte line instead
/// of the two or three of a 104-byte [`WorldTriangle`] (BENCHMARKS.md).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Shading {
    normals: [Vec3; 3],
    uvs: [Vec2; 3],
    surface: SurfaceId,
}

/// Each triangle's material, looked up the cheapest way the triangles allow.
#[derive(Debug, Clone)]
enum Materials {
    /// By surface id: every surface's triangles share one material (a
    /// scene's surfaces lie within one mesh, which has one material), and the
    /// ids are dense; a small table the caches keep.
    BySurface(Vec<MaterialId>),
    /// By scene-wide triangle id, for any other triangles.
    ByTriangle(Vec<MaterialId>),
}

impl Materials {
    /// The lookup for `triangles`.
    fn new(triangles: &[WorldTriangle]) -> Self {
        let by_triangle = || Self::ByTriangle(triangles.iter().map(|t| t.material).collect());
        let Some(last) = triangles.iter().map(|t| t.surface as usize).max() else {
            return by_triangle();
        };
        if last >= triangles.len() {
            return by_triangle();
        }
        let mut table = vec![None; last + 1];
        for t in triangles {
            match table[t.surface as usize] {
                None => table[t.surface as usize] = Some(t.material),
                Some(m) if m == t.material => {}
                Some(_) => return by_triangle(),
            }
        }
        Self::BySurface(table.into_iter().map(|m| m.unwrap_or(0)).collect())
    }

    /// The material of triangle `id` on surface `surface`.
    #[inline]
    fn get(&self, id: TriangleId, surface: SurfaceId) -> MaterialId {
        match self {
            Self::BySurface(table) => table[surface as usize],
            Self::ByTriangle(list) => list[id as usize],
        }
    }
}

/// The ray direction the triangle test takes: -0.0 components as +0.0, as
/// the obvhs traversal before the eight-wide BVH needed them (bit-identical
/// distances and barycentrics to those it gave).
fn test_direction(ray: &Ray) -> Vec3A {
    Vec3A::from(ray.direction + Vec3::ZERO)
}

impl Bvh {
    /// Builds the BVH of the scene's current pose.
    pub fn build(scene: &Scene) -> Self {
        Self::from_triangles(scene.world_triangles())
    }

    /// Builds the BVH over world-space triangles (scene-wide ids are their indices).
    ///
    /// Panics with a billion triangles or more (the leaf encoding's limit).
    pub fn from_triangles(triangles: Vec<WorldTriangle>) -> Self {
        let shading = triangles
            .iter()
            .map(|t| Shading {
                normals: t.normals,
                uvs: t.uvs,
                surface: t.surface,
            })
            .collect();
        let materials = Materials::new(&triangles);
        if triangles.is_empty() {
            return Self {
                wide: None,
                triangles,
                shading,
                materials,
            };
        }
        let tris: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle {
                v0: t.positions[0].into(),
                v1: t.positions[1].into(),
                v2: t.positions[2].into(),
            })
            .collect();
        // obvhs' binary build (PLOC, then reinsertion; no pre-split) with a
        // wider PLOC search and more reinsertion than its medium settings:
        // about 10% faster incoherent closest hits on the Embree comparison's
        // scene for about twice the reinsertion time.
        let params = BvhBuildParams {
            ploc_search_distance: PlocSearchDistance::High,
            reinsertion_batch_ratio: 0.2,
            ..BvhBuildParams::medium_build()
        };
        let mut bvh2 = PlocBuilder::with_capacity(tris.len()).build(
            params.ploc_search_distance,
            &tris,
            (0..tris.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        let corners: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.positions).collect();
        Self {
            wide: WideBvh::from_bvh2(&bvh2, &corners),
            triangles,
            shading,
            materials,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the BVH holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The world-space triangles by scene-wide id.
    pub fn triangles(&self) -> &[WorldTriangle] {
        &self.triangles
    }

    /// Checks the BVH's invariants (every triangle in exactly one leaf, child
    /// boxes inside their parents, triangles inside their leaves' boxes);
    /// panics with the first violation found.
    pub fn validate(&self) {
        if let Some(wide) = &self.wide {
            let corners: Vec<[Vec3; 3]> = self.triangles.iter().map(|t| t.positions).collect();
            if let Err(why) = wide.validate(&corners) {
                panic!("invalid BVH: {why}");
            }
        }
    }

    /// The closest intersection with `t` in `[ray.t_min, ray.t_max]`: [`Bvh::closest_hit_lean`] and [`Bvh::hit_record`], the record built from the leaf's edges and the triangle's 64-byte shading line.
    ///
    /// Each hit that becomes the closest so far has its shading line loaded
    /// as it is found, so that the record's cache miss (on incoherent rays
    /// over a large scene) overlaps the rest of the traversal instead of
    /// following it (BENCHMARKS.md). The same record as `hit_record`, bit for bit.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let wide = self.wide.as_ref()?;
        let (triangle, h, lane) = wide.closest_hit(ray, test_direction(ray), |id| {
            std::hint::black_box(self.shading[id as usize].surface);
        })?;
        let shading = &self.shading[triangle as usize];
        Some(self.record(
            ray,
            LeanHit {
                triangle,
                t: h.t,
                u: h.u,
                v: h.v,
            },
            wide.edge_cross(lane),
            shading,
        ))
    }

    /// The closest intersection's distance, triangle and barycentrics, without the shading record (eight-wide BVH traversal, children nearest first, and Möller-Trumbore four triangles at a time).
    pub fn closest_hit_lean(&self, ray: &Ray) -> Option<LeanHit> {
        let (triangle, h, _) = self
            .wide
            .as_ref()?
            .closest_hit(ray, test_direction(ray), |_| {})?;
        Some(LeanHit {
            triangle,
            t: h.t,
            u: h.u,
            v: h.v,
        })
    }

    /// The full hit record of `hit` on `ray` (a hit this BVH returned for that ray): position, geometric and interpolated shading normals, interpolated UVs, surface and material.
    pub fn hit_record(&self, ray: &Ray, hit: LeanHit) -> Hit {
        let [p0, p1, p2] = self.triangles[hit.triangle as usize].positions;
        let shading = &self.shading[hit.triangle as usize];
        self.record(ray, hit, (p1 - p0).cross(p2 - p0), shading)
    }

    /// The record of `hit` given its triangle's unnormalised geometric normal `e1 × e2` and shading line.
    #[inline]
    fn record(&self, ray: &Ray, hit: LeanHit, edge_cross: Vec3, shading: &Shading) -> Hit {
        let w = 1.0 - hit.u - hit.v;
        let geometric_normal = edge_cross.normalize_or_zero();
        let [n0, n1, n2] = shading.normals;
        let [uv0, uv1, uv2] = shading.uvs;
        let normal = w * n0 + hit.u * n1 + hit.v * n2;
        Hit {
            triangle: hit.triangle,
            surface: shading.surface,
            material: self.materials.get(hit.triangle, shading.surface),
            t: hit.t,
            u: hit.u,
            v: hit.v,
            position: ray.at(hit.t),
            geometric_normal,
            shading_normal: normal.try_normalize().unwrap_or(geometric_normal),
            uv: w * uv0 + hit.u * uv1 + hit.v * uv2,
        }
    }

    /// Whether anything lies on the ray with `t` in `[ray.t_min, ray.t_max)` (shadow rays; a hit exactly at `t_max` does not count).
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit_where(ray, |_, _| true)
    }

    /// Whether a triangle that `accept` takes lies on the ray with `t` in `[ray.t_min, ray.t_max)`: `accept` gets each triangle met (scene-wide id, distance) in traversal order until it takes one, so triangles it refuses, such as a path's own mesh, cost no further query.
    pub fn any_hit_where(&self, ray: &Ray, accept: impl FnMut(TriangleId, f32) -> bool) -> bool {
        self.wide
            .as_ref()
            .is_some_and(|wide| wide.any_hit_where(ray, test_direction(ray), accept))
    }

    /// Calls `f` with the scene-wide id of every triangle whose bounding box overlaps the box `min..=max` (each once, in no particular order).
    pub fn overlapping(&self, min: Vec3, max: Vec3, mut f: impl FnMut(TriangleId)) {
        let Some(wide) = &self.wide else {
            return;
        };
        wide.overlapping(Vec3A::from(min), Vec3A::from(max), |id| {
            let [a, b, c] = self.triangles[id as usize].positions;
            if a.min(b).min(c).cmple(max).all() && a.max(b).max(c).cmpge(min).all() {
                f(id);
            }
        });
    }

    /// Closest hits of many rays, in parallel.
    pub fn closest_hits(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        rays.par_iter().map(|r| self.closest_hit(r)).collect()
    }

    /// Any-hit results of many rays, in parallel.
    pub fn any_hits(&self, rays: &[Ray]) -> Vec<bool> {
        rays.par_iter().map(|r| self.any_hit(r)).collect()
    }
}
