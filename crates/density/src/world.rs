//! The scene split into its static part and its mobile objects (section 2.2.2): rays meet the union of a static BVH, built once, and a BVH of the mobile objects at their current pose.

use glam::Vec3;
use lustre_geometry::{Aabb, Bvh, Hit, MeshId, ObjectId, Ray, Scene, TriangleId, WorldTriangle};

use crate::error::{DensityError, Result};

/// A first intersection with the world: the hit (scene-wide triangle id), its mesh and whether it belongs to a mobile object (section 2.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldHit {
    /// The hit, with `triangle` a scene-wide id.
    pub hit: Hit,
    /// The mesh of the triangle hit.
    pub mesh: MeshId,
    /// Whether the triangle belongs to a mobile object.
    pub mobile: bool,
}

/// A BVH over a subset of the scene's triangles, answering with scene-wide ids.
#[derive(Debug, Clone)]
struct Part {
    bvh: Bvh,
    ids: Vec<TriangleId>,
    bounds: Aabb,
}

impl Part {
    fn new(all: &[WorldTriangle], mesh_of: &[MeshId], keep: impl Fn(MeshId) -> bool) -> Self {
        let mut ids = Vec::new();
        let mut triangles = Vec::new();
        for (id, tri) in all.iter().enumerate() {
            if keep(mesh_of[id]) {
                ids.push(id as TriangleId);
                triangles.push(*tri);
            }
        }
        let bounds = Aabb::from_points(triangles.iter().flat_map(|t| t.positions));
        Self {
            bvh: Bvh::from_triangles(triangles),
            ids,
            bounds,
        }
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        if self.ids.is_empty() || !slab_overlaps(&self.bounds, ray) {
            return None;
        }
        let mut hit = self.bvh.closest_hit(ray)?;
        hit.triangle = self.ids[hit.triangle as usize];
        Some(hit)
    }
}

/// Whether a ray's interval `[t_min, t_max]` meets a box (slab test); conservative by a small margin.
fn slab_overlaps(bounds: &Aabb, ray: &Ray) -> bool {
    if bounds.is_empty() {
        return false;
    }
    let pad = 1e-4 * bounds.extent().max_element().max(1e-6);
    let lo = bounds.min - Vec3::splat(pad);
    let hi = bounds.max + Vec3::splat(pad);
    let inv = ray.direction.recip();
    let t0 = (lo - ray.origin) * inv;
    let t1 = (hi - ray.origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    // NaN (0 * ∞ for an origin on a slab plane parallel to the ray) must not reject: treat as unbounded.
    let enter = [near.x, near.y, near.z, ray.t_min]
        .into_iter()
        .filter(|v| !v.is_nan())
        .fold(f32::NEG_INFINITY, f32::max);
    let exit = [far.x, far.y, far.z, ray.t_max]
        .into_iter()
        .filter(|v| !v.is_nan())
        .fold(f32::INFINITY, f32::min);
    enter <= exit
}

/// The static scene and its mobile objects (section 2.2.2: "the 'static' scene and the 'mobile', which can move and rotate with respect to the static scene"; several mobile objects are allowed, section 2.2.2).
#[derive(Debug, Clone)]
pub struct World {
    static_part: Part,
    mobile_part: Part,
    mobile_mesh: Vec<bool>,
    mesh_of: Vec<MeshId>,
    epsilon: f32,
    /// The static scene with scene-wide ids (mobile triangles collapsed to points), built on first use.
    statics: std::sync::OnceLock<Bvh>,
}

impl World {
    /// Splits `scene` (at its current pose) into the static part and the meshes of the `mobile` objects. Fails on an unknown object or an emitting mobile mesh (lights are static, section 2.2.2).
    pub fn new(scene: &Scene, mobile: &[ObjectId]) -> Result<Self> {
        let mut mobile_mesh = vec![false; scene.meshes().len()];
        for &object in mobile {
            let o = scene.objects().get(object as usize).ok_or_else(|| {
                DensityError::InvalidOption {
                    option: "mobile",
                    message: format!("object #{object} does not exist in scene `{}`", scene.name),
                }
            })?;
            for &m in &o.meshes {
                let material = &scene.materials()[scene.meshes()[m as usize].material as usize];
                if material.emission.max_element() > 0.0 {
                    return Err(DensityError::InvalidOption {
                        option: "mobile",
                        message: format!(
                            "object `{}` emits light; lights must be static (section 2.2.2)",
                            o.name
                        ),
                    });
                }
                mobile_mesh[m as usize] = true;
            }
        }
        let mut mesh_of = Vec::with_capacity(scene.triangle_count());
        for (m, mesh) in scene.meshes().iter().enumerate() {
            mesh_of.extend(std::iter::repeat_n(m as MeshId, mesh.indices.len()));
        }
        let all = scene.world_triangles();
        let epsilon = crate::ray_set::world_epsilon(scene);
        Ok(Self {
            static_part: Part::new(&all, &mesh_of, |m| !mobile_mesh[m as usize]),
            mobile_part: Part::new(&all, &mesh_of, |m| mobile_mesh[m as usize]),
            mobile_mesh,
            mesh_of,
            epsilon,
            statics: std::sync::OnceLock::new(),
        })
    }

    /// Rebuilds the mobile objects' BVH from the scene's current pose (after [`Scene::set_object_transform`]); the static part is kept.
    pub fn move_mobile(&mut self, scene: &Scene) {
        let mut triangles = Vec::with_capacity(self.mobile_part.ids.len());
        for (m, mesh) in scene.meshes().iter().enumerate() {
            if !self.is_mobile_mesh(m as MeshId) {
                continue;
            }
            let positions = scene.world_positions(m as MeshId);
            let normals = scene.world_normals(m as MeshId);
            for (t, idx) in mesh.indices.iter().enumerate() {
                let id = scene.triangle_id(m as MeshId, t as u32);
                triangles.push(WorldTriangle {
                    positions: idx.map(|i| positions[i as usize]),
                    normals: idx.map(|i| normals[i as usize]),
                    uvs: idx.map(|i| mesh.uvs[i as usize]),
                    surface: scene.triangle_surface(id),
                    material: mesh.material,
                });
            }
        }
        self.mobile_part.bounds = Aabb::from_points(triangles.iter().flat_map(|t| t.positions));
        self.mobile_part.bvh = Bvh::from_triangles(triangles);
    }

    /// The first intersection with the static scene or a mobile object (figure 2.1, "First intersection of Ray against the scene").
    pub fn closest_hit(&self, ray: &Ray) -> Option<WorldHit> {
        let fixed = self.static_part.closest_hit(ray);
        let limited = Ray {
            t_max: fixed.map_or(ray.t_max, |h| h.t),
            ..*ray
        };
        match self.mobile_part.closest_hit(&limited) {
            Some(hit) => Some(self.world_hit(hit, true)),
            None => fixed.map(|hit| self.world_hit(hit, false)),
        }
    }

    /// The first intersection with a mobile object in the ray's interval (figure 2.2, "Ray intersects now the mobile object").
    pub fn mobile_hit(&self, ray: &Ray) -> Option<WorldHit> {
        self.mobile_part
            .closest_hit(ray)
            .map(|hit| self.world_hit(hit, true))
    }

    fn world_hit(&self, hit: Hit, mobile: bool) -> WorldHit {
        WorldHit {
            mesh: self.mesh_of[hit.triangle as usize],
            hit,
            mobile,
        }
    }

    /// Calls `f` with the corners of every triangle of the static scene and of the mobile objects at their current pose whose bounding box overlaps the box `min..=max`.
    pub fn triangles_near(&self, min: Vec3, max: Vec3, f: &mut dyn FnMut([Vec3; 3])) {
        for part in [&self.static_part, &self.mobile_part] {
            let b = &part.bounds;
            if part.ids.is_empty() || b.min.cmpgt(max).any() || b.max.cmplt(min).any() {
                continue;
            }
            part.bvh
                .overlapping(min, max, |t| f(part.bvh.triangles()[t as usize].positions));
        }
    }

    /// Whether a mesh belongs to a mobile object.
    pub fn is_mobile_mesh(&self, mesh: MeshId) -> bool {
        self.mobile_mesh
            .get(mesh as usize)
            .copied()
            .unwrap_or(false)
    }

    /// The box of the mobile objects at their current pose (empty without any).
    pub fn mobile_bounds(&self) -> Aabb {
        self.mobile_part.bounds
    }

    /// Whether any mesh is mobile.
    pub fn has_mobile(&self) -> bool {
        !self.mobile_part.ids.is_empty()
    }

    /// Offset that steps a reflected ray off its surface, fixed from the first pose so that a recalculated ray and a full trace agree.
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// A BVH of the static scene answering with scene-wide triangle ids, as artifact control needs (section 1.2.1): every mobile triangle is collapsed to a point, which no ray meets. Built on first use from `scene`, which must be the scene this world was made from.
    pub fn static_scene_bvh(&self, scene: &Scene) -> &Bvh {
        self.statics.get_or_init(|| {
            let mut all = scene.world_triangles();
            for (id, tri) in all.iter_mut().enumerate() {
                if self.mobile_mesh[self.mesh_of[id] as usize] {
                    tri.positions = [tri.positions[0]; 3];
                }
            }
            Bvh::from_triangles(all)
        })
    }
}
