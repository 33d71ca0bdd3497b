//! # lustre-geometry
//!
//! The scene model every Lustre technique stands on: triangle meshes with
//! per-vertex normals and UVs, plain-data materials, objects with rigid
//! transforms, surfaces in the papers' sense, lights with emission and
//! direct-lighting sampling, a pinhole camera with a mirror transform,
//! OBJ/MTL and glTF 2.0 loading, BVH ray queries (obvhs PLOC build, eight-wide
//! traversal), sampling, mesh utilities, the built-in scenes and the
//! Mitsuba 3 export.
//!
//! Conventions (DESIGN.md): right-handed, +Y up, metres; radiometric units
//! W, W/m², W/(m² sr); colour is linear Rec.709 RGB in `f32`.
//!
//! ```
//! use lustre_geometry::{builtin, Bvh, Camera, Ray};
//! use glam::Vec2;
//!
//! let scene = builtin("cornell").unwrap();
//! let bvh = Bvh::build(&scene);
//! let ray = scene.camera().primary_ray(Vec2::ZERO);
//! let hit = bvh.closest_hit(&ray).expect("the camera looks into the box");
//! let surface = &scene.surfaces()[hit.surface as usize];
//! println!("hit {} at {}", scene.meshes()[surface.mesh as usize].name, hit.position);
//! ```

mod aabb;
pub mod animation;
pub mod builtin;
mod bvh;
mod camera;
pub mod camera_path;
mod error;
pub mod gltf;
pub mod light;
pub mod material;
mod mesh;
pub mod meshing;
pub mod mitsuba;
pub mod obj;
mod plane;
mod ray;
pub mod sampling;
mod scene;
mod scene_file;
pub mod shadow_volume;
pub mod slab;
pub mod texture;
mod wide_bvh;

pub use aabb::Aabb;
pub use animation::{Keyframe, MobileObject, ObjectPath, PathEnd};
pub use builtin::builtin;
pub use bvh::Bvh;
pub use camera::Camera;
pub use error::{GeometryError, Location, Result};
pub use light::Light;
pub use material::{Material, MaterialId, MaterialModel};
pub use mesh::{Mesh, MeshId, triangle_area};
pub use obj::{LoadedScene, ObjOptions, load_obj, load_obj_with};
pub use plane::Plane;
pub use ray::{Hit, LeanHit, Ray, TriangleHit, intersect_triangle};
pub use scene::{
    Object, ObjectId, Scene, Surface, SurfaceId, SurfaceKind, TriangleId, WorldTriangle,
};
pub use scene_file::{is_gltf, load_scene_arg, load_scene_file};
pub use texture::Texture;

/// Linear Rec.709 RGB.
pub type Rgb = glam::Vec3;
