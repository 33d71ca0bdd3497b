//! Ray queries on a binary PLOC BVH (Meister & Bittner 2018, obvhs) in two
//! wide forms: closest hits on our eight-wide BVH with `f32` boxes
//! ([`crate::wide_bvh`]), any hits and box queries on obvhs' compressed wide
//! BVH (Ylitie et al. 2017); single rays and rayon-parallel batches.

use glam::{UVec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance};
use obvhs::ray::RayHit;
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use crate::ray::{Hit, LeanHit, Ray, intersect_triangle_a};
use crate::scene::{Scene, TriangleId, WorldTriangle};
use crate::wide_bvh::WideBvh;

/// A BVH over every triangle of a scene in world space.
///
/// It holds its own copy of the world-space triangles, so it answers queries
/// without the scene; after [`Scene::set_object_transform`] build it again with
/// [`Bvh::build`] (a full PLOC rebuild is cheap at the sizes the papers use).
#[derive(Debug, Clone)]
pub struct Bvh {
    cwbvh: Option<CwBvh>,
    /// The eight-wide BVH of the closest-hit queries (`None` when empty or too deep; the CWBVH answers then).
    wide: Option<WideBvh>,
    /// Corner positions in BVH leaf order, for coherent memory access.
    ordered: Vec<[Vec3A; 3]>,
    /// The shading attributes, by scene-wide triangle id.
    triangles: Vec<WorldTriangle>,
}

fn to_obvhs(ray: &Ray) -> obvhs::ray::Ray {
    // obvhs picks the traversal octant from the direction's comparison with
    // zero but inverts -0.0 to -∞, so a -0.0 component makes it miss: adding
    // +0.0 turns -0.0 into +0.0 and leaves every other value alone.
    obvhs::ray::Ray::new(
        Vec3A::from(ray.origin),
        Vec3A::from(ray.direction + Vec3::ZERO),
        ray.t_min,
        ray.t_max,
    )
}

impl Bvh {
    /// Builds the BVH of the scene's current pose.
    pub fn build(scene: &Scene) -> Self {
        Self::from_triangles(scene.world_triangles())
    }

    /// Builds the BVH over world-space triangles (scene-wide ids are their indices).
    pub fn from_triangles(triangles: Vec<WorldTriangle>) -> Self {
        if triangles.is_empty() {
            return Self {
                cwbvh: None,
                wide: None,
                ordered: Vec::new(),
                triangles,
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
        // obvhs' build_cwbvh_from_tris (no pre-split) with a wider PLOC search
        // and more reinsertion than its medium settings (about 10% faster
        // incoherent closest hits on the Embree comparison's scene, about 25%
        // longer builds), keeping the binary tree for the eight-wide BVH.
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
        let cwbvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
        let corners: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.positions).collect();
        let wide = WideBvh::from_bvh2(&bvh2, &corners);
        let ordered = cwbvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize].positions.map(Vec3A::from))
            .collect();
        Self {
            cwbvh: Some(cwbvh),
            wide,
            ordered,
            triangles,
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

    /// Checks the BVH's invariants (every primitive reachable once, child
    /// bounds inside parents); panics with obvhs' message if one fails.
    pub fn validate(&self) {
        if let Some(bvh) = &self.cwbvh {
            let tris: Vec<Triangle> = self
                .triangles
                .iter()
                .map(|t| Triangle {
                    v0: t.positions[0].into(),
                    v1: t.positions[1].into(),
                    v2: t.positions[2].into(),
                })
                .collect();
            bvh.validate(&tris, false);
        }
    }

    /// The closest intersection with `t` in `[ray.t_min, ray.t_max]`: [`Bvh::closest_hit_lean`] and [`Bvh::hit_record`].
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_lean(ray).map(|h| self.hit_record(ray, h))
    }

    /// The closest intersection's distance, triangle and barycentrics, without the shading record (CWBVH traversal, Ylitie et al. 2017, and Möller-Trumbore).
    pub fn closest_hit_lean(&self, ray: &Ray) -> Option<LeanHit> {
        if let Some(wide) = &self.wide {
            // The direction as the CWBVH path gives it to the triangle test (-0.0 as +0.0).
            let direction = Vec3A::from(ray.direction + Vec3::ZERO);
            return wide
                .closest_hit(ray, direction)
                .map(|(triangle, h)| LeanHit {
                    triangle,
                    t: h.t,
                    u: h.u,
                    v: h.v,
                });
        }
        self.closest_hit_cwbvh(ray)
    }

    /// [`Bvh::closest_hit_lean`] by the CWBVH (the fallback, and the reference the eight-wide BVH is tested against).
    #[doc(hidden)]
    pub fn closest_hit_cwbvh(&self, ray: &Ray) -> Option<LeanHit> {
        let bvh = self.cwbvh.as_ref()?;
        let mut hit = RayHit::none();
        let mut best = None;
        bvh.ray_traverse(to_obvhs(ray), &mut hit, |r, id| match intersect_triangle_a(
            r.origin,
            r.direction,
            r.tmin,
            r.tmax,
            &self.ordered[id],
        ) {
            Some(h) => {
                best = Some((id, h));
                h.t
            }
            None => f32::INFINITY,
        });
        let (slot, h) = best?;
        Some(LeanHit {
            triangle: bvh.primitive_indices[slot],
            t: h.t,
            u: h.u,
            v: h.v,
        })
    }

    /// The full hit record of `hit` on `ray` (a hit this BVH returned for that ray): position, geometric and interpolated shading normals, interpolated UVs, surface and material.
    pub fn hit_record(&self, ray: &Ray, hit: LeanHit) -> Hit {
        let tri = &self.triangles[hit.triangle as usize];
        let w = 1.0 - hit.u - hit.v;
        let [p0, p1, p2] = tri.positions;
        let geometric_normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let shading = w * tri.normals[0] + hit.u * tri.normals[1] + hit.v * tri.normals[2];
        Hit {
            triangle: hit.triangle,
            surface: tri.surface,
            material: tri.material,
            t: hit.t,
            u: hit.u,
            v: hit.v,
            position: ray.at(hit.t),
            geometric_normal,
            shading_normal: shading.try_normalize().unwrap_or(geometric_normal),
            uv: w * tri.uvs[0] + hit.u * tri.uvs[1] + hit.v * tri.uvs[2],
        }
    }

    /// Whether anything lies on the ray with `t` in `[ray.t_min, ray.t_max]` (shadow rays).
    pub fn any_hit(&self, ray: &Ray) -> bool {
        let Some(bvh) = &self.cwbvh else {
            return false;
        };
        !bvh.ray_traverse_miss(to_obvhs(ray), |r, id| {
            intersect_triangle_a(r.origin, r.direction, r.tmin, r.tmax, &self.ordered[id])
                .map_or(f32::INFINITY, |h| h.t)
        })
    }

    /// Calls `f` with the scene-wide id of every triangle whose bounding box overlaps the box `min..=max` (each once, in no particular order).
    pub fn overlapping(&self, min: Vec3, max: Vec3, mut f: impl FnMut(TriangleId)) {
        let Some(bvh) = &self.cwbvh else {
            return;
        };
        let query = obvhs::aabb::Aabb::new(Vec3A::from(min), Vec3A::from(max));
        let (min, max) = (Vec3A::from(min), Vec3A::from(max));
        let mut state = bvh.new_traversal(Vec3A::ONE);
        let mut node;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_aabb(&query, state.oct_inv4),
            {
                let slot = state.primitive_id as usize;
                let [a, b, c] = self.ordered[slot];
                if a.min(b).min(c).cmple(max).all() && a.max(b).max(c).cmpge(min).all() {
                    f(bvh.primitive_indices[slot]);
                }
            }
        );
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
