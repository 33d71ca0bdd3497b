//! The scene: meshes, materials, objects with rigid transforms, surfaces,
//! lights and a camera.

use std::collections::HashMap;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::animation::{MobileObject, ObjectPath};
use crate::light::{AreaLight, AreaShape, Light};
use crate::material::{Material, MaterialId};
use crate::mesh::{Mesh, MeshId, triangle_area};
use crate::{Aabb, Camera, GeometryError, Plane, Result};

/// Index of an object in [`Scene::objects`].
pub type ObjectId = u32;
/// Index of a surface in [`Scene::surfaces`].
pub type SurfaceId = u32;
/// Scene-wide triangle index: triangles of mesh 0 first, then mesh 1, and so on.
pub type TriangleId = u32;

/// A named group of meshes that moves as one (the papers' mobile object).
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// The object's name.
    pub name: String,
    /// The meshes that belong to it.
    pub meshes: Vec<MeshId>,
    /// Transform applied to the meshes' rest-pose vertices (identity at rest).
    pub transform: Affine3A,
}

impl Object {
    /// One object per mesh, named as the mesh, at rest.
    pub fn one_per_mesh(meshes: &[Mesh]) -> Vec<Self> {
        meshes
            .iter()
            .enumerate()
            .map(|(i, m)| Self {
                name: m.name.clone(),
                meshes: vec![i as u32],
                transform: Affine3A::IDENTITY,
            })
            .collect()
    }
}

/// The shape of a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceKind {
    /// A planar polygon: connected coplanar flat-shaded triangles.
    Planar(Plane),
    /// A smooth-shaded, curved part of a mesh.
    Curved,
}

/// A surface in the papers' sense: a planar polygon, or the curved part of a
/// mesh, with one material.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// The mesh it belongs to.
    pub mesh: MeshId,
    /// Its triangles, as indices into the mesh's `indices`.
    pub triangles: Vec<u32>,
    /// Planar (with its world plane) or curved.
    pub kind: SurfaceKind,
    /// World-space area in m².
    pub area: f32,
    /// The material.
    pub material: MaterialId,
}

/// A scene-wide triangle in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldTriangle {
    /// Corner positions.
    pub positions: [Vec3; 3],
    /// Corner shading normals (unit length).
    pub normals: [Vec3; 3],
    /// Corner texture coordinates.
    pub uvs: [Vec2; 3],
    /// The surface.
    pub surface: SurfaceId,
    /// The material.
    pub material: MaterialId,
}

/// A scene ready to render: validated, with surfaces and area lights derived.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene's name (built-in name or file stem).
    pub name: String,
    meshes: Vec<Mesh>,
    materials: Vec<Material>,
    objects: Vec<Object>,
    /// Lights given explicitly (point, oriented point, spot, explicit area lights).
    explicit_lights: Vec<Light>,
    camera: Camera,
    /// The objects that move along paths (García et al. 2003, section 2.2.2).
    mobile: Vec<MobileObject>,
    // Derived.
    mesh_object: Vec<ObjectId>,
    triangle_offsets: Vec<u32>,
    surfaces: Vec<Surface>,
    triangle_surface: Vec<SurfaceId>,
    lights: Vec<Light>,
    /// World bounds of each mesh.
    mesh_bounds: Vec<Aabb>,
    /// The surfaces of mesh `m` are `mesh_surfaces[m]..mesh_surfaces[m + 1]`.
    mesh_surfaces: Vec<SurfaceId>,
    /// Whether area lights are replaced by cosine point lights of equal power.
    area_lights_as_points: bool,
}

/// Cosine of the largest angle between a flat triangle's vertex normals and its
/// geometric normal (about 0.8°).
const FLAT_COS: f32 = 0.9999;
/// Largest distance, relative to the scene size, of a coplanar triangle from its neighbour's plane.
const COPLANAR_RELATIVE: f32 = 1e-5;

impl Scene {
    /// Builds a scene. Every mesh must belong to exactly one object; meshes with an
    /// emissive material become area lights. Fails on invalid meshes, bad indices,
    /// invalid lights, or a scene without any light.
    pub fn new(
        name: impl Into<String>,
        meshes: Vec<Mesh>,
        materials: Vec<Material>,
        objects: Vec<Object>,
        lights: Vec<Light>,
        camera: Camera,
    ) -> Result<Self> {
        let name = name.into();
        let mut mesh_object = vec![u32::MAX; meshes.len()];
        for (o, object) in objects.iter().enumerate() {
            for &m in &object.meshes {
                let slot =
                    mesh_object
                        .get_mut(m as usize)
                        .ok_or_else(|| GeometryError::InvalidMesh {
                            mesh: format!("#{m}"),
                            message: format!(
                                "object `{}` names a mesh that does not exist",
                                object.name
                            ),
                        })?;
                if *slot != u32::MAX {
                    return Err(GeometryError::InvalidMesh {
                        mesh: meshes[m as usize].name.clone(),
                        message: "belongs to more than one object".into(),
                    });
                }
                *slot = o as u32;
            }
        }
        for (m, mesh) in meshes.iter().enumerate() {
            mesh.validate()?;
            if mesh_object[m] == u32::MAX {
                return Err(GeometryError::InvalidMesh {
                    mesh: mesh.name.clone(),
                    message: "belongs to no object".into(),
                });
            }
            if mesh.material as usize >= materials.len() {
                return Err(GeometryError::InvalidMesh {
                    mesh: mesh.name.clone(),
                    message: format!("material #{} does not exist", mesh.material),
                });
            }
        }
        for (i, light) in lights.iter().enumerate() {
            light.validate(&format!("#{i}"))?;
        }
        let mut triangle_offsets = Vec::with_capacity(meshes.len() + 1);
        let mut total = 0u32;
        for mesh in &meshes {
            triangle_offsets.push(total);
            total = total
                .checked_add(mesh.indices.len() as u32)
                .ok_or_else(|| GeometryError::InvalidMesh {
                    mesh: mesh.name.clone(),
                    message: "more than 2^32 triangles in the scene".into(),
                })?;
        }
        triangle_offsets.push(total);
        let mut scene = Self {
            name,
            meshes,
            materials,
            objects,
            explicit_lights: lights,
            camera,
            mobile: Vec::new(),
            mesh_object,
            triangle_offsets,
            surfaces: Vec::new(),
            triangle_surface: Vec::new(),
            lights: Vec::new(),
            mesh_bounds: Vec::new(),
            mesh_surfaces: Vec::new(),
            area_lights_as_points: false,
        };
        scene.derive()?;
        if scene.lights.is_empty() {
            return Err(GeometryError::NoLight(scene.name.clone()));
        }
        Ok(scene)
    }

    /// The same geometry, objects (and their poses), mobile objects, explicit
    /// lights and camera with other materials (same count and order);
    /// emissive materials become area lights.
    pub fn with_materials(&self, materials: Vec<Material>) -> Result<Self> {
        let mut scene = Self::new(
            self.name.clone(),
            self.meshes.clone(),
            materials,
            self.objects.clone(),
            self.explicit_lights.clone(),
            self.camera,
        )?;
        scene.mobile = self.mobile.clone();
        Ok(scene)
    }

    /// The same materials, objects (and their poses), mobile objects, explicit
    /// lights, camera and point-light setting with other meshes (same count
    /// and order, e.g. each one subdivided for per-vertex lighting); surfaces
    /// and area lights are derived again.
    pub fn with_meshes(&self, meshes: Vec<Mesh>) -> Result<Self> {
        if meshes.len() != self.meshes.len() {
            return Err(GeometryError::InvalidMesh {
                mesh: self.name.clone(),
                message: format!(
                    "{} meshes given to replace {}",
                    meshes.len(),
                    self.meshes.len()
                ),
            });
        }
        let mut scene = Self::new(
            self.name.clone(),
            meshes,
            self.materials.clone(),
            self.objects.clone(),
            self.explicit_lights.clone(),
            self.camera,
        )?;
        scene.mobile = self.mobile.clone();
        if self.area_lights_as_points {
            scene.with_area_lights_as_points()
        } else {
            Ok(scene)
        }
    }

    /// The meshes (rest pose).
    pub fn meshes(&self) -> &[Mesh] {
        &self.meshes
    }

    /// The materials.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The objects.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The surfaces.
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }

    /// All lights: the explicit ones, then one area light per emissive mesh.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Replaces the camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// The object a mesh belongs to.
    pub fn mesh_object(&self, mesh: MeshId) -> ObjectId {
        self.mesh_object[mesh as usize]
    }

    /// The object with the given name.
    pub fn object_by_name(&self, name: &str) -> Result<ObjectId> {
        self.objects
            .iter()
            .position(|o| o.name == name)
            .map(|i| i as ObjectId)
            .ok_or_else(|| GeometryError::UnknownObject(name.to_owned()))
    }

    /// Moves an object: sets its transform relative to its rest pose, and
    /// updates its meshes' surfaces and the area lights (the other meshes'
    /// are kept). A BVH must be rebuilt or refitted after.
    pub fn set_object_transform(&mut self, object: ObjectId, transform: Affine3A) -> Result<()> {
        let o = self
            .objects
            .get_mut(object as usize)
            .ok_or_else(|| GeometryError::UnknownObject(format!("#{object}")))?;
        if !transform.is_finite() {
            return Err(GeometryError::InvalidMesh {
                mesh: o.name.clone(),
                message: "object transform is not finite".into(),
            });
        }
        o.transform = transform;
        let meshes = o.meshes.clone();
        self.derive_meshes(&meshes)
    }

    /// The scene with the object named `object_name` made mobile along `path`
    /// and posed at the path's start; a second path for the same object
    /// replaces the first. Fails when no object has that name (García et al. 2003, section 2.2.2).
    pub fn with_mobile(mut self, object_name: &str, path: ObjectPath) -> Result<Self> {
        let object = self.object_by_name(object_name)?;
        let start = path.at(path.start());
        match self.mobile.iter_mut().find(|m| m.object == object) {
            Some(mobile) => mobile.path = path,
            None => self.mobile.push(MobileObject { object, path }),
        }
        self.set_object_transform(object, start)?;
        Ok(self)
    }

    /// The objects that move along paths, in the order they were made mobile (García et al. 2003, section 2.2.2).
    pub fn mobile_objects(&self) -> &[MobileObject] {
        &self.mobile
    }

    /// Poses every mobile object where its path is at time `t` (seconds) and
    /// updates the moved meshes' surfaces and the area lights; a BVH must be
    /// rebuilt or refitted after (García et al. 2003, section 2.2.2).
    pub fn pose_at(&mut self, t: f32) -> Result<()> {
        if self.mobile.is_empty() {
            return Ok(());
        }
        let mut moved = Vec::new();
        for mobile in &self.mobile {
            let object = &mut self.objects[mobile.object as usize];
            object.transform = mobile.path.at(t);
            moved.extend_from_slice(&object.meshes);
        }
        self.derive_meshes(&moved)
    }

    /// Number of triangles in the scene.
    pub fn triangle_count(&self) -> usize {
        *self.triangle_offsets.last().unwrap() as usize
    }

    /// The scene-wide id of triangle `t` of `mesh`.
    pub fn triangle_id(&self, mesh: MeshId, t: u32) -> TriangleId {
        self.triangle_offsets[mesh as usize] + t
    }

    /// The mesh and mesh-local index of a scene-wide triangle.
    pub fn triangle_source(&self, id: TriangleId) -> (MeshId, u32) {
        let mesh = self.triangle_offsets.partition_point(|&o| o <= id) - 1;
        (mesh as MeshId, id - self.triangle_offsets[mesh])
    }

    /// The surface a scene-wide triangle belongs to.
    pub fn triangle_surface(&self, id: TriangleId) -> SurfaceId {
        self.triangle_surface[id as usize]
    }

    /// The transform of a mesh's object.
    pub fn mesh_transform(&self, mesh: MeshId) -> Affine3A {
        self.objects[self.mesh_object[mesh as usize] as usize].transform
    }

    /// World positions of a mesh's vertices.
    pub fn world_positions(&self, mesh: MeshId) -> Vec<Vec3> {
        let xf = self.mesh_transform(mesh);
        self.meshes[mesh as usize]
            .positions
            .iter()
            .map(|&p| xf.transform_point3(p))
            .collect()
    }

    /// World shading normals of a mesh's vertices (inverse transpose, renormalised).
    pub fn world_normals(&self, mesh: MeshId) -> Vec<Vec3> {
        let normal_matrix = normal_matrix(&self.mesh_transform(mesh));
        self.meshes[mesh as usize]
            .normals
            .iter()
            .map(|&n| (normal_matrix * n).normalize())
            .collect()
    }

    /// Every triangle of the scene in world space, in scene-wide id order.
    pub fn world_triangles(&self) -> Vec<WorldTriangle> {
        let mut out = Vec::with_capacity(self.triangle_count());
        for (m, mesh) in self.meshes.iter().enumerate() {
            let positions = self.world_positions(m as MeshId);
            let normals = self.world_normals(m as MeshId);
            for (t, tri) in mesh.indices.iter().enumerate() {
                let id = self.triangle_offsets[m] + t as u32;
                out.push(WorldTriangle {
                    positions: tri.map(|i| positions[i as usize]),
                    normals: tri.map(|i| normals[i as usize]),
                    uvs: tri.map(|i| mesh.uvs[i as usize]),
                    surface: self.triangle_surface[id as usize],
                    material: mesh.material,
                });
            }
        }
        out
    }

    /// World-space bounding box of the scene.
    pub fn bounds(&self) -> Aabb {
        self.mesh_bounds
            .iter()
            .copied()
            .fold(Aabb::EMPTY, Aabb::union)
    }

    /// Total power of all lights, in W.
    pub fn total_power(&self) -> crate::Rgb {
        self.lights.iter().map(Light::power).sum()
    }

    /// The length coplanarity tolerances are relative to: the scene's largest extent.
    fn scale(&self) -> f32 {
        self.bounds().extent().max_element().max(1e-6)
    }

    /// Recomputes every mesh's world bounds and surfaces (with world areas
    /// and planes), then the area lights.
    fn derive(&mut self) -> Result<()> {
        self.mesh_bounds = (0..self.meshes.len() as MeshId)
            .map(|m| Aabb::from_points(self.world_positions(m)))
            .collect();
        let scale = self.scale();
        self.surfaces.clear();
        self.mesh_surfaces = vec![0];
        self.triangle_surface = vec![0; self.triangle_count()];
        for m in 0..self.meshes.len() {
            let positions = self.world_positions(m as MeshId);
            let normals = self.world_normals(m as MeshId);
            let groups = group_surfaces(
                &self.meshes[m],
                &positions,
                &normals,
                scale * COPLANAR_RELATIVE,
            );
            let first = self.surfaces.len() as SurfaceId;
            self.surfaces.reserve(groups.len());
            for (g, group) in groups.into_iter().enumerate() {
                let surface = self.surface_of(m as MeshId, group, &positions, first + g as u32);
                self.surfaces.push(surface);
            }
            self.mesh_surfaces.push(self.surfaces.len() as SurfaceId);
        }
        self.derive_lights()
    }

    /// Recomputes the bounds and surfaces of the given meshes only, after
    /// their objects moved (a quasi-static scene: García et al. 2003, section
    /// 2.2.2), then the area lights; falls back to [`Scene::derive`] when the
    /// scene's size or a moved mesh's surface count changes, so the result
    /// always equals a full derivation.
    fn derive_meshes(&mut self, meshes: &[MeshId]) -> Result<()> {
        let scale = self.scale();
        for &m in meshes {
            self.mesh_bounds[m as usize] = Aabb::from_points(self.world_positions(m));
        }
        if self.scale().to_bits() != scale.to_bits() {
            return self.derive();
        }
        let mut updates = Vec::with_capacity(meshes.len());
        for &m in meshes {
            let positions = self.world_positions(m);
            let normals = self.world_normals(m);
            let groups = group_surfaces(
                &self.meshes[m as usize],
                &positions,
                &normals,
                scale * COPLANAR_RELATIVE,
            );
            let (first, end) = (
                self.mesh_surfaces[m as usize],
                self.mesh_surfaces[m as usize + 1],
            );
            if groups.len() != (end - first) as usize {
                return self.derive();
            }
            updates.push((m, groups, positions));
        }
        for (m, groups, positions) in updates {
            let first = self.mesh_surfaces[m as usize];
            for (g, group) in groups.into_iter().enumerate() {
                let id = first + g as SurfaceId;
                self.surfaces[id as usize] = self.surface_of(m, group, &positions, id);
            }
        }
        self.derive_lights()
    }

    /// The surface `id` of mesh `m` made of `group` (world `positions`), its
    /// triangles recorded as belonging to it.
    fn surface_of(
        &mut self,
        m: MeshId,
        group: SurfaceGroup,
        positions: &[Vec3],
        id: SurfaceId,
    ) -> Surface {
        let mesh = &self.meshes[m as usize];
        let area = group
            .triangles
            .iter()
            .map(|&t| triangle_area(mesh.indices[t as usize].map(|i| positions[i as usize])))
            .sum();
        let offset = self.triangle_offsets[m as usize];
        for &t in &group.triangles {
            self.triangle_surface[(offset + t) as usize] = id;
        }
        Surface {
            mesh: m,
            triangles: group.triangles,
            kind: group.kind,
            area,
            material: mesh.material,
        }
    }

    /// Recomputes the lights: the explicit ones, then one area light per
    /// emissive mesh (as cosine point lights when so asked).
    fn derive_lights(&mut self) -> Result<()> {
        self.lights = self.explicit_lights.clone();
        for m in 0..self.meshes.len() {
            let mesh = &self.meshes[m];
            let material = &self.materials[mesh.material as usize];
            if !material.is_emissive() {
                continue;
            }
            let positions = self.world_positions(m as MeshId);
            let triangles: Vec<[Vec3; 3]> = mesh
                .indices
                .iter()
                .map(|tri| tri.map(|i| positions[i as usize]))
                .collect();
            let shape = rectangle_of(&triangles).unwrap_or_else(|| AreaShape::triangles(triangles));
            let light = Light::Area(AreaLight {
                mesh: Some(m as MeshId),
                shape,
                radiance: material.emission,
            });
            light.validate(&mesh.name)?;
            self.lights.push(light);
        }
        if self.area_lights_as_points {
            for light in &mut self.lights {
                if let Light::Area(area) = light {
                    *light = Light::OrientedPoint(area.to_oriented_point());
                }
            }
        }
        Ok(())
    }

    /// The scene with every area light (emissive meshes included, which stay
    /// as visible geometry) replaced by the cosine point light of equal power
    /// at its centroid ([`AreaLight::to_oriented_point`]); the replacement
    /// persists through later object moves. Point-light techniques use it
    /// (DESIGN.md, "Built-in scenes"; Stürzlinger & Bastos 1997, section 3).
    pub fn with_area_lights_as_points(&self) -> Result<Self> {
        let mut scene = self.clone();
        scene.area_lights_as_points = true;
        scene.derive()?;
        Ok(scene)
    }

    /// Whether [`Scene::with_area_lights_as_points`] made this scene.
    pub fn area_lights_as_points(&self) -> bool {
        self.area_lights_as_points
    }
}

/// The inverse transpose of an affine transform's linear part.
fn normal_matrix(xf: &Affine3A) -> Mat3 {
    Mat3::from(xf.matrix3).inverse().transpose()
}

struct SurfaceGroup {
    triangles: Vec<u32>,
    kind: SurfaceKind,
}

/// Splits a mesh into surfaces: flat-shaded triangles joined across shared
/// edges when coplanar become planar polygons; smooth-shaded ones form one
/// curved surface.
fn group_surfaces(
    mesh: &Mesh,
    positions: &[Vec3],
    normals: &[Vec3],
    tolerance: f32,
) -> Vec<SurfaceGroup> {
    let n = mesh.indices.len();
    let geometric: Vec<Vec3> = mesh
        .indices
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|i| positions[i as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    let flat: Vec<bool> = (0..n)
        .map(|t| {
            mesh.indices[t]
                .iter()
                .all(|&i| normals[i as usize].dot(geometric[t]) >= FLAT_COS)
        })
        .collect();
    // Union-find over flat triangles sharing an edge (by exact position) and a plane.
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in 0..n {
        if !flat[t] {
            continue;
        }
        let tri = mesh.indices[t];
        for e in 0..3 {
            let (a, b) = (
                key(positions[tri[e] as usize]),
                key(positions[tri[(e + 1) % 3] as usize]),
            );
            let edge = if a < b { (a, b) } else { (b, a) };
            match edges.get(&edge) {
                Some(&other) => {
                    let p = positions[mesh.indices[other as usize][0] as usize];
                    let coplanar = geometric[t].dot(geometric[other as usize]) >= FLAT_COS
                        && geometric[t].dot(positions[tri[0] as usize] - p).abs() <= tolerance
                        && geometric[t].dot(positions[tri[2] as usize] - p).abs() <= tolerance;
                    if coplanar {
                        let (ra, rb) = (find(&mut parent, t as u32), find(&mut parent, other));
                        parent[ra.max(rb) as usize] = ra.min(rb);
                    }
                }
                None => {
                    edges.insert(edge, t as u32);
                }
            }
        }
    }
    let mut groups: Vec<SurfaceGroup> = Vec::new();
    let mut root_group: HashMap<u32, usize> = HashMap::new();
    let mut curved: Option<usize> = None;
    for t in 0..n as u32 {
        let slot = if flat[t as usize] {
            let root = find(&mut parent, t);
            *root_group.entry(root).or_insert_with(|| {
                let p = positions[mesh.indices[root as usize][0] as usize];
                groups.push(SurfaceGroup {
                    triangles: Vec::new(),
                    kind: SurfaceKind::Planar(Plane::from_point_normal(
                        p,
                        geometric[root as usize],
                    )),
                });
                groups.len() - 1
            })
        } else {
            *curved.get_or_insert_with(|| {
                groups.push(SurfaceGroup {
                    triangles: Vec::new(),
                    kind: SurfaceKind::Curved,
                });
                groups.len() - 1
            })
        };
        groups[slot].triangles.push(t);
    }
    groups
}

/// The rectangle two triangles form, when they form one (a quad light).
fn rectangle_of(triangles: &[[Vec3; 3]]) -> Option<AreaShape> {
    let [t0, t1] = triangles else { return None };
    let area = triangle_area(*t0) + triangle_area(*t1);
    // Try each corner of t0 as the rectangle's corner with its two edges.
    for k in 0..3 {
        let origin = t0[k];
        let (eu, ev) = (t0[(k + 1) % 3] - origin, t0[(k + 2) % 3] - origin);
        let cross = eu.cross(ev);
        if eu.dot(ev).abs() > 1e-5 * eu.length() * ev.length() || cross.length() <= 0.0 {
            continue;
        }
        let opposite = origin + eu + ev;
        let tol = 1e-5 * (eu.length() + ev.length());
        let on_corner = |p: Vec3| {
            [origin, origin + eu, origin + ev, opposite]
                .iter()
                .any(|q| q.distance(p) <= tol)
        };
        let same_side = (t1[1] - t1[0]).cross(t1[2] - t1[0]).dot(cross) > 0.0;
        if t1.iter().all(|&p| on_corner(p))
            && t1.iter().any(|p| p.distance(opposite) <= tol)
            && same_side
            && (cross.length() - area).abs() <= 1e-4 * area
        {
            return Some(AreaShape::Rectangle {
                origin,
                edge_u: eu,
                edge_v: ev,
            });
        }
    }
    None
}
