//! OBJ/MTL loading: Wavefront files to a validated [`Scene`].
//!
//! [`load_obj`] reads an OBJ file and the MTL libraries it names, and builds a
//! [`Scene`] with [`Scene::new`]: one [`Object`] per OBJ object or group
//! (`o`/`g`), one [`Mesh`] per (object, material) pair, the materials of every
//! library, no explicit lights (meshes with an emissive material become area
//! lights in [`Scene::new`]; a model without any emitter gets a default
//! [`Studio`], a ground plane and an area light sized to its bounds, with a
//! warning) and the camera of [`framing_camera`], a three-quarter view.
//!
//! # Validation before parsing
//!
//! tobj (which does the triangulation and the single-index vertex
//! de-duplication) reports errors without line numbers and can panic or
//! overflow on some malformed input, so every file is first scanned line by
//! line here. The scan reports the first problem as [`GeometryError::Parse`]
//! with the file and the one-based line: a number that does not parse or is
//! not finite (`v`, `vt`, `vn` and every numeric MTL field), a `v` with
//! `w = 0`, a face with fewer than three vertices, a face index that is `0`,
//! beyond the `v`/`vt`/`vn` lines read so far, or (negative, relative) before
//! the first one, an MTL statement before any `newmtl`, and out-of-range
//! material values (at the line that sets them). Only the validated
//! statements reach tobj, rewritten with absolute indices; tobj's own
//! errors, which should not happen any more, and a panic inside tobj are
//! still turned into [`GeometryError::Parse`] naming the OBJ file.
//!
//! A missing OBJ file is [`GeometryError::Io`]; a file without any face is
//! [`GeometryError::EmptyMesh`] naming the file, and so is a mesh whose
//! triangles are all degenerate.
//!
//! # Geometry
//!
//! - Polygons are triangulated with a constrained Delaunay triangulation of
//!   their plane ([`crate::meshing::triangulate_polygon`]), so concave faces
//!   stay inside their outline; a face that is not a simple planar polygon
//!   is triangulated as a fan around its first vertex, with a warning.
//! - Degenerate triangles are dropped and counted in
//!   [`LoadedScene::degenerate_triangles_dropped`]: a triangle is degenerate
//!   when `|(b - a) × (c - a)| <= 1e-6 · (longest edge)²`, which catches zero
//!   area, repeated vertices and (nearly) collinear corners independently of
//!   the scene's scale.
//! - Texture coordinates are taken as written (`v` up, no flip), zero when a
//!   mesh has none. Normals from `vn` are normalised; a mesh without them (or
//!   with a zero-length one) gets area-weighted vertex normals that respect
//!   the crease angle of [`ObjOptions`]: the normal of a triangle's corner is
//!   the sum of the (area-weighted) geometric normals of the triangles around
//!   that position whose normal is within the crease angle of the corner's
//!   own triangle, so a vertex is split between faces whose normals differ by
//!   more than the crease angle. Positions are matched by value, so seams of
//!   the texture layout do not break the smoothing.
//! - A mesh (tobj model) that mixes faces with and without `vt` (or `vn`)
//!   drops them for the whole mesh, with a warning, because single-index
//!   loading cannot align partial attributes.
//! - Ignored statements: `l` and `p` (no area), `s` (smoothing groups: the
//!   crease angle decides instead), vertex colours (`v x y z r g b`),
//!   free-form geometry and any unknown statement; each kind is warned about
//!   once in [`LoadedScene::warnings`], except `s`.
//! - Faces before any `usemtl` use a `default` material, Mitsuba's default
//!   BSDF (diffuse, reflectance 0.5), appended only when needed. Faces
//!   before any `o`/`g` belong to an object named after the file stem.
//! - `mtllib` names one file (which may contain spaces) or, when no such file
//!   exists, several whitespace-separated files, relative to the OBJ file's
//!   folder. A material defined twice (in one library or two) keeps the later
//!   definition, with a warning.
//! - As other viewers do with files as people have them, a missing or
//!   unreadable MTL file, a `usemtl` naming a material no library loaded
//!   before it defines, and a missing texture are warnings (at the line of
//!   the `mtllib`, the `usemtl` and the `map_Kd`/`map_Ks`), not failures:
//!   those faces take the `default` material, the texture is left out.
//!
//! # Materials
//!
//! Standard MTL statements, read by this module's own line scanner (so that
//! every value keeps its line number):
//!
//! | statement | meaning | range | default |
//! |---|---|---|---|
//! | `newmtl name` | starts a material | non-empty | |
//! | `Kd r [g b]` | diffuse reflectance | [0, 1] | 0 (as tinyobjloader) |
//! | `Ks r [g b]` | specular reflectance | [0, 1] | 0 |
//! | `Ke r [g b]` | emitted radiance, W/(m² sr) | >= 0 | 0 |
//! | `Tf r [g b]` | transmittance filter | [0, 1] | 1 |
//! | `Ns e` | Phong exponent | >= 0 | none |
//! | `Ni n` | index of refraction | > 0 | none |
//! | `d a` (`d -halo a`) | opacity, stored in [`Material::opacity`] | [0, 1] | 1 |
//! | `Tr t` | `d = 1 - t` when there is no `d` | [0, 1] | |
//! | `illum n` | illumination model | 0..=10 | none |
//! | `Pr r` | PBR roughness | [0, 1] | 1 when `Pm` is given |
//! | `Pm m` | PBR metallic | [0, 1] | 0 when `Pr` is given |
//! | `map_Kd [options] file` | [`Material::diffuse_texture`], decoded into [`Material::diffuse_map`] (PNG or JPEG, sRGB), which scales `Kd` (1 when `Kd` is absent) | a missing or undecodable file: warning, no texture | |
//! | `map_Ks [options] file` | [`Material::specular_texture`] | a missing file: warning, no texture | |
//! | `Ka` | ambient, ignored (numbers still checked) | | |
//!
//! Texture files are resolved relative to the MTL file's folder (absolute
//! paths are kept; a path that only exists with `\` read as `/` is accepted);
//! texture options (`-s`, `-o`, `-bm`, ...) are skipped with a warning. Other
//! maps and unknown statements are ignored with a warning. Colours take one
//! number (grey) or three; `spectral` and `xyz` colours are an error.
//!
//! Lustre keys for models the standard lacks:
//!
//! | key | meaning | range |
//! |---|---|---|
//! | `lustre_model name` | the model (see the rules below) | one word |
//! | `lustre_alpha a` | isotropic roughness (Beckmann RMS slope, GGX alpha) | > 0 |
//! | `lustre_alpha_x a`, `lustre_alpha_y a` | Ward's slope deviations along tangent and bitangent | > 0 |
//! | `lustre_eta r [g b]` | conductor index of refraction (real part) | > 0 |
//! | `lustre_k r [g b]` | conductor extinction coefficient | >= 0 |
//! | `lustre_fresnel none\|conductor` | `none`: F = 1 ([`ConductorFresnel::None`]); `conductor`: from `lustre_eta`/`lustre_k` | |
//! | `lustre_blend_weight w` | weight of the rough conductor in `blend` | [0, 1] |
//! | `lustre_distribution beckmann\|gaussian\|ggx` | microfacet distribution | |
//! | `lustre_param name v [v v]` | a parameter of a [`MaterialModel::Named`] model (repeatable) | finite |
//!
//! The model is chosen by the first rule that applies ([`Material::emission`]
//! is `Ke` whatever the model, so an emitter of any model is an area light):
//!
//! 1. `lustre_model`:
//!    - `diffuse` → `Diffuse { Kd }`; `phong` → `Phong { Kd, Ks, Ns }` (`Ns`
//!      required); `mirror` → `Mirror { Ks, or 1 without Ks }`; `dielectric` →
//!      `Dielectric { Ni, Tf }` (`Ni` required);
//!    - `ward` → `Ward { Kd, Ks, alpha_x, alpha_y }`, each alpha from
//!      `lustre_alpha_x`/`lustre_alpha_y`, else `lustre_alpha` (required);
//!    - `beckmann`, `rough-conductor` (also `roughconductor`, `conductor`) →
//!      `RoughConductor`: `lustre_alpha` required, distribution
//!      `lustre_distribution` else Beckmann (`beckmann` with another
//!      distribution is an error), Fresnel `Complex { lustre_eta, lustre_k }`
//!      when both are given (one alone is an error), `None` when
//!      `lustre_fresnel none` or neither is given, `specular = Ks`, or 1
//!      without `Ks`;
//!    - `blend` → `Blend { weight: lustre_blend_weight (required), first:
//!      Diffuse { Kd }, second: the rough conductor above }` (the glosbox
//!      floor is `Kd 0.885809 0.698859 0.666422`, `lustre_model blend`,
//!      `lustre_blend_weight 0.3`, `lustre_alpha 0.05`, `lustre_fresnel none`);
//!    - any other name → `Named { model, params }` with every `lustre_param`.
//! 2. `Pr` or `Pm` (the PBR extension, metallic-roughness workflow as written
//!    by Blender): the metal lobe is `RoughConductor { GGX (or
//!    lustre_distribution), alpha = Pr², Fresnel None, specular = Kd }` (the
//!    base colour is the metal's normal-incidence reflectance F0, held
//!    constant over angle), or `Mirror { Kd }` when `Pr = 0`. `Pm = 0` →
//!    `Diffuse { Kd }` (the dielectric's 4 % specular layer is neglected),
//!    `Pm = 1` → the metal lobe, otherwise `Blend { weight: Pm, first:
//!    Diffuse { Kd }, second: metal }`.
//! 3. `Ni` with `d < 1` or `illum` 4, 6 or 7 → `Dielectric { ior: Ni,
//!    transmittance: Tf }` (`illum` 4/6/7 without `Ni` is warned about and
//!    falls through; `d < 1` alone only sets the opacity).
//! 4. `illum` 3, 5 or 8 (reflection on) with `Ks > 0` → `Mirror { Ks }`.
//! 5. `Ks > 0` with `Ns`, unless `illum` is 0 or 1 → `Phong { Kd, Ks, Ns }`
//!    (a warning when `Kd + Ks > 1`); `Ks > 0` otherwise is ignored with a
//!    warning.
//! 6. Otherwise `Diffuse { Kd }`.
//!
//! `lustre_*` keys without `lustre_model` (except `lustre_distribution`
//! with `Pr`/`Pm`) and `lustre_param` with a built-in model are ignored with
//! a warning.
//!
//! [`ConductorFresnel::None`]: crate::material::ConductorFresnel::None
//! [`MaterialModel::Named`]: crate::MaterialModel::Named

mod mtl;
mod normals;
mod scan;

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::{
    Aabb, Camera, GeometryError, Location, Material, MaterialId, Mesh, MeshId, Object, Result, Rgb,
    Scene,
};

pub use mtl::{MtlLibrary, load_mtl};

/// Default crease angle of generated normals, in degrees.
pub const DEFAULT_CREASE_ANGLE_DEGREES: f32 = 60.0;
/// Vertical field of view of the camera [`framing_camera`] places, in degrees.
pub const FRAMING_FOV_Y_DEGREES: f32 = 40.0;
/// Name of the material given to faces that precede every `usemtl`.
pub const DEFAULT_MATERIAL_NAME: &str = "default";
/// Relative threshold of the degenerate-triangle test: `|cross| <= this · longest edge²`.
const DEGENERATE_RELATIVE: f32 = 1e-6;

/// Settings of [`load_obj_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjOptions {
    /// Largest angle, in degrees, between two faces' normals that is still
    /// smoothed over when normals are generated; clamped to [0, 180] (NaN means the default).
    pub crease_angle_degrees: f32,
}

impl Default for ObjOptions {
    fn default() -> Self {
        Self {
            crease_angle_degrees: DEFAULT_CREASE_ANGLE_DEGREES,
        }
    }
}

/// A scene loaded from an OBJ file, with what the loader had to change.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The scene, named after the file stem.
    pub scene: Scene,
    /// Number of degenerate triangles (zero area, collinear corners) dropped.
    pub degenerate_triangles_dropped: usize,
    /// Things ignored or repaired, one message each (with file and line where one applies).
    pub warnings: Vec<String>,
    /// The default studio added round a model without a light, if any.
    pub studio: Option<Studio>,
}

/// The material of faces without a known one: Mitsuba's default BSDF,
/// diffuse with reflectance 0.5, named [`DEFAULT_MATERIAL_NAME`].
fn fallback_material() -> Material {
    Material::diffuse(DEFAULT_MATERIAL_NAME, Rgb::splat(0.5))
}

/// Loads an OBJ file and its MTL libraries with the default [`ObjOptions`].
pub fn load_obj(path: &Path) -> Result<LoadedScene> {
    load_obj_with(path, &ObjOptions::default())
}

/// Loads an OBJ file and its MTL libraries.
pub fn load_obj_with(path: &Path, options: &ObjOptions) -> Result<LoadedScene> {
    let text = read_text(path)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.trim().is_empty())
        .unwrap_or_else(|| "scene".to_owned());
    let mut warnings = Vec::new();
    let scanned = scan::scan_obj(path, &text, &stem, &mut warnings)?;
    if scanned.faces == 0 {
        return Err(GeometryError::EmptyMesh {
            mesh: stem,
            file: Some(path.to_owned()),
        });
    }
    let mut materials = scanned.materials;
    let models = run_tobj(path, &scanned.text, materials.len())?;

    let crease = if options.crease_angle_degrees.is_nan() {
        DEFAULT_CREASE_ANGLE_DEGREES
    } else {
        options.crease_angle_degrees.clamp(0.0, 180.0)
    };
    let mut dropped = 0;
    let mut default_material = None;
    // (object name, material) -> index into `parts`, in order of first appearance.
    let mut part_of: HashMap<(String, MaterialId), usize> = HashMap::new();
    let mut parts: Vec<(String, MaterialId, Part)> = Vec::new();
    for model in &models {
        if model.mesh.indices.is_empty() {
            continue;
        }
        let material = match model.mesh.material_id {
            Some(id) if id < materials.len() => id as MaterialId,
            _ => *default_material.get_or_insert_with(|| {
                // The scan's fallback for unknown materials, if it made one.
                if let Some(d) = materials
                    .iter()
                    .position(|m| m.name == DEFAULT_MATERIAL_NAME)
                {
                    return d as MaterialId;
                }
                materials.push(fallback_material());
                (materials.len() - 1) as MaterialId
            }),
        };
        let part = convert_model(path, model, crease, &mut dropped, &mut warnings);
        let slot = *part_of
            .entry((model.name.clone(), material))
            .or_insert_with(|| {
                parts.push((model.name.clone(), material, Part::default()));
                parts.len() - 1
            });
        parts[slot].2.append(part);
    }

    let mut objects: Vec<Object> = Vec::new();
    let mut object_of: HashMap<&str, usize> = HashMap::new();
    for (m, (object, _, _)) in parts.iter().enumerate() {
        let o = *object_of.entry(object.as_str()).or_insert_with(|| {
            objects.push(Object {
                name: object.clone(),
                meshes: Vec::new(),
                transform: glam::Affine3A::IDENTITY,
            });
            objects.len() - 1
        });
        objects[o].meshes.push(m as MeshId);
    }
    let mut meshes = Vec::with_capacity(parts.len());
    for (object, material, part) in parts.iter() {
        let name = if objects[object_of[object.as_str()]].meshes.len() == 1 {
            object.clone()
        } else {
            format!("{object}:{}", materials[*material as usize].name)
        };
        if part.indices.is_empty() {
            return Err(GeometryError::EmptyMesh {
                mesh: name,
                file: Some(path.to_owned()),
            });
        }
        meshes.push(Mesh {
            name,
            positions: part.positions.clone(),
            normals: part.normals.clone(),
            uvs: part.uvs.clone(),
            indices: part.indices.clone(),
            material: *material,
        });
    }
    finish(
        Parts {
            name: stem,
            meshes,
            materials,
            objects,
            lights: Vec::new(),
            camera: None,
            degenerate_triangles_dropped: dropped,
            warnings,
        },
        path,
    )
}

/// What a loader made of a file, before the scene is put together.
pub(crate) struct Parts {
    /// The scene's name (the file stem).
    pub name: String,
    /// Its meshes.
    pub meshes: Vec<Mesh>,
    /// Its materials.
    pub materials: Vec<Material>,
    /// Its objects.
    pub objects: Vec<Object>,
    /// Its lights other than emissive meshes.
    pub lights: Vec<crate::Light>,
    /// The file's camera, if it has one.
    pub camera: Option<Camera>,
    /// Degenerate triangles dropped.
    pub degenerate_triangles_dropped: usize,
    /// Warnings so far.
    pub warnings: Vec<String>,
}

/// The scene of a loaded file (OBJ or glTF): refused without a mesh, the
/// default studio added when nothing emits, framed by [`framing_camera`]
/// when the file has no camera.
pub(crate) fn finish(parts: Parts, path: &Path) -> Result<LoadedScene> {
    let Parts {
        name,
        mut meshes,
        mut materials,
        mut objects,
        lights,
        camera,
        degenerate_triangles_dropped,
        mut warnings,
    } = parts;
    if meshes.is_empty() {
        return Err(GeometryError::EmptyMesh {
            mesh: name,
            file: Some(path.to_owned()),
        });
    }
    let bounds = meshes
        .iter()
        .map(Mesh::bounds)
        .fold(Aabb::EMPTY, Aabb::union);
    // No emitter at all: a default studio round the model.
    let lit = !lights.is_empty()
        || meshes
            .iter()
            .any(|m| materials[m.material as usize].is_emissive());
    let studio = (!lit).then(|| {
        Studio::add(
            bounds,
            &mut meshes,
            &mut materials,
            &mut objects,
            path,
            &mut warnings,
        )
    });
    let camera = camera.unwrap_or_else(|| framing_camera(bounds));
    let scene = Scene::new(name, meshes, materials, objects, lights, camera)?;
    Ok(LoadedScene {
        scene,
        degenerate_triangles_dropped,
        warnings,
        studio,
    })
}

/// The direction from a framed box's centre to the camera of
/// [`framing_camera`]: a three-quarter view, 30° round from +Z towards +X
/// and 25° above the horizon, so that a model shows three of its sides
/// rather than one face straight down an axis.
pub fn framing_direction() -> Vec3 {
    let (azimuth, elevation) = (30f32.to_radians(), 25f32.to_radians());
    Vec3::new(
        azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    )
}

/// The default camera of a loaded scene: a pinhole with a 40° vertical field
/// of view and a square image, looking at the box's centre from `centre +
/// framing_direction() · r / sin 20°` (`r` the radius of the box's bounding
/// sphere), up +Y, so that the whole box is in view.
pub fn framing_camera(bounds: Aabb) -> Camera {
    let (center, radius) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), (0.5 * bounds.extent().length()).max(1e-3))
    };
    let distance = radius / (0.5 * FRAMING_FOV_Y_DEGREES).to_radians().sin();
    Camera::look_at(
        center + framing_direction() * distance,
        center,
        Vec3::Y,
        FRAMING_FOV_Y_DEGREES,
    )
}

/// What [`load_obj`] adds round a model that has no light, so that it shows
/// as other viewers show it: a ground plane under it and a square area
/// light above it, sized to its bounds (each a material of its own,
/// `studio-ground` and `studio-light`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Studio {
    /// Height of the ground plane: a thousandth of the model's largest extent below the bottom of its box, so that a flat base does not lie in the ground's plane (coplanar faces z-fight, differently at every scale, and photons land on either).
    pub ground_height: f32,
    /// Half the side of the square ground, centred under the model: 2.5 times its largest extent.
    pub ground_half_side: f32,
    /// Centre of the light: one largest extent above the top of the box.
    pub light_centre: Vec3,
    /// Side of the square light: half the largest extent.
    pub light_side: f32,
    /// Its radiance, W/(m² sr): `π d² / A` for the light's distance `d` to
    /// the ground and area `A`, so the irradiance under it is about π W/m²
    /// whatever the model's units.
    pub radiance: f32,
    /// The model's largest extent: the scene's size for lengths relative to it (the studio around it is five times as wide).
    pub model_size: f32,
}

/// The gap between a model's box and the studio's ground, in the model's largest extents.
const GROUND_GAP: f32 = 1e-3;

impl Studio {
    /// The studio for a model's box.
    pub fn for_bounds(bounds: Aabb) -> Self {
        let extent = bounds.extent().max_element().max(1e-3);
        let centre = bounds.center();
        let light_centre = Vec3::new(centre.x, bounds.max.y + extent, centre.z);
        let light_side = 0.5 * extent;
        let ground_height = bounds.min.y - GROUND_GAP * extent;
        let distance = light_centre.y - ground_height;
        Self {
            ground_height,
            ground_half_side: 2.5 * extent,
            light_centre,
            light_side,
            radiance: std::f32::consts::PI * distance * distance / (light_side * light_side),
            model_size: extent,
        }
    }

    /// Adds the studio of `bounds` to a model's meshes, materials and
    /// objects (one object per part), and says so in `warnings` for `file`.
    pub(crate) fn add(
        bounds: Aabb,
        meshes: &mut Vec<Mesh>,
        materials: &mut Vec<Material>,
        objects: &mut Vec<Object>,
        file: &Path,
        warnings: &mut Vec<String>,
    ) -> Self {
        let studio = Self::for_bounds(bounds);
        let (extra_materials, extra_meshes) = studio.parts(bounds, materials.len() as MaterialId);
        materials.extend(extra_materials);
        for mesh in extra_meshes {
            objects.push(Object {
                name: mesh.name.clone(),
                meshes: vec![meshes.len() as MeshId],
                transform: glam::Affine3A::IDENTITY,
            });
            meshes.push(mesh);
        }
        warnings.push(format!(
            "{}: no light: added a default studio (a ground plane at height {} and a {} m square area light of radiance {:.4} W/(m² sr) above the model)",
            file.display(),
            studio.ground_height,
            studio.light_side,
            studio.radiance
        ));
        studio
    }

    /// Its two materials and two meshes (ground facing up, light facing
    /// down), the materials numbered from `first_material`.
    fn parts(&self, bounds: Aabb, first_material: MaterialId) -> (Vec<Material>, Vec<Mesh>) {
        use crate::builtin::parts::quad;
        let c = bounds.center();
        let (g, h) = (self.ground_half_side, self.ground_height);
        // Facing z × x = +y.
        let ground = quad(
            "studio-ground",
            Vec3::new(c.x - g, h, c.z - g),
            2.0 * g * Vec3::Z,
            2.0 * g * Vec3::X,
            first_material,
        );
        let (l, s) = (self.light_centre, self.light_side);
        // Facing x × z = -y.
        let light = quad(
            "studio-light",
            Vec3::new(l.x - 0.5 * s, l.y, l.z - 0.5 * s),
            s * Vec3::X,
            s * Vec3::Z,
            first_material + 1,
        );
        let materials = vec![
            Material::diffuse("studio-ground", Rgb::splat(0.5)),
            Material::diffuse("studio-light", Rgb::ZERO).with_emission(Rgb::splat(self.radiance)),
        ];
        (materials, vec![ground, light])
    }
}

/// Vertex arrays of one tobj model, converted.
#[derive(Debug, Default)]
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<[u32; 3]>,
}

impl Part {
    fn append(&mut self, other: Part) {
        let base = self.positions.len() as u32;
        self.positions.extend(other.positions);
        self.normals.extend(other.normals);
        self.uvs.extend(other.uvs);
        self.indices
            .extend(other.indices.into_iter().map(|t| t.map(|i| i + base)));
    }
}

/// Runs tobj on the validated, rewritten OBJ text; `materials` names are their indices.
fn run_tobj(path: &Path, text: &str, materials: usize) -> Result<Vec<tobj::Model>> {
    // The struct update keeps this compiling if another crate turns on tobj's
    // `merging` or `reordering` features, which add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let loader = |_: &Path| -> tobj::MTLLoadResult {
        let list = (0..materials)
            .map(|i| tobj::Material {
                name: i.to_string(),
                ..Default::default()
            })
            .collect();
        Ok((list, (0..materials).map(|i| (i.to_string(), i)).collect()))
    };
    let result = catch_unwind(AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut std::io::Cursor::new(text.as_bytes()), &options, loader)
    }));
    match result {
        Ok(Ok((models, _))) => Ok(models),
        Ok(Err(e)) => Err(parse_error(
            path,
            None,
            format!("tobj failed after validation: {e}"),
        )),
        Err(_) => Err(parse_error(path, None, "tobj panicked after validation")),
    }
}

/// Converts a tobj model: drops degenerate triangles, normalises or generates normals.
fn convert_model(
    path: &Path,
    model: &tobj::Model,
    crease_degrees: f32,
    dropped: &mut usize,
    warnings: &mut Vec<String>,
) -> Part {
    let mesh = &model.mesh;
    let positions: Vec<Vec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let n = positions.len();
    let uvs: Vec<Vec2> = if mesh.texcoords.len() == 2 * n {
        mesh.texcoords
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0], t[1]))
            .collect()
    } else {
        if !mesh.texcoords.is_empty() {
            warnings.push(format!(
                "{}: object `{}`: texture coordinates do not match the vertices; using zero",
                path.display(),
                model.name
            ));
        }
        vec![Vec2::ZERO; n]
    };
    let before = mesh.indices.len() / 3;
    let indices: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t.iter().all(|&i| (i as usize) < n))
        .filter(|t| !is_degenerate(t.map(|i| positions[i as usize])))
        .collect();
    *dropped += before - indices.len();

    let file_normals: Option<Vec<Vec3>> = (mesh.normals.len() == 3 * n && n > 0)
        .then(|| {
            mesh.normals
                .chunks_exact(3)
                .map(|v| Vec3::new(v[0], v[1], v[2]).normalize_or_zero())
                .collect::<Vec<_>>()
        })
        .filter(|normals| {
            let ok = indices
                .iter()
                .flatten()
                .all(|&i| normals[i as usize] != Vec3::ZERO);
            if !ok {
                warnings.push(format!(
                    "{}: object `{}`: a `vn` normal has zero length; generating normals instead",
                    path.display(),
                    model.name
                ));
            }
            ok
        });
    match file_normals {
        Some(normals) => compact(&positions, &normals, &uvs, &indices),
        None => normals::crease_normals(&positions, &uvs, &indices, crease_degrees),
    }
}

/// Keeps only the vertices the triangles use, in order of first use.
fn compact(positions: &[Vec3], normals: &[Vec3], uvs: &[Vec2], indices: &[[u32; 3]]) -> Part {
    let mut remap = vec![u32::MAX; positions.len()];
    let mut part = Part::default();
    for tri in indices {
        let tri = tri.map(|i| {
            let slot = &mut remap[i as usize];
            if *slot == u32::MAX {
                *slot = part.positions.len() as u32;
                part.positions.push(positions[i as usize]);
                part.normals.push(normals[i as usize]);
                part.uvs.push(uvs[i as usize]);
            }
            *slot
        });
        part.indices.push(tri);
    }
    part
}

/// Whether a triangle has (nearly) zero area relative to its size: zero
/// area, repeated or collinear corners, or non-finite corners.
fn is_degenerate([a, b, c]: [Vec3; 3]) -> bool {
    let cross = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    !(cross > DEGENERATE_RELATIVE * longest)
}

/// Reads a text file (UTF-8, an initial byte-order mark skipped).
fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
        path: path.to_owned(),
        source,
    })?;
    decode_text(path, bytes)
}

/// Decodes UTF-8, naming the line of the first invalid byte.
fn decode_text(path: &Path, bytes: Vec<u8>) -> Result<String> {
    match String::from_utf8(bytes) {
        Ok(mut text) => {
            if text.starts_with('\u{feff}') {
                text.drain(..'\u{feff}'.len_utf8());
            }
            Ok(text)
        }
        Err(e) => {
            let valid = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..valid]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            Err(parse_error(path, Some(line), "the line is not valid UTF-8"))
        }
    }
}

/// A [`GeometryError::Parse`] at a file and line.
fn parse_error(file: &Path, line: Option<usize>, message: impl Into<String>) -> GeometryError {
    GeometryError::Parse {
        location: Location {
            file: file.to_owned(),
            line,
        },
        message: message.into(),
    }
}

/// Parses a finite `f32`; `what` names the value in the message.
fn parse_number(token: &str, file: &Path, line: usize, what: &str) -> Result<f32> {
    match token.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(parse_error(
            file,
            Some(line),
            format!("{what}: `{token}` is not a finite number"),
        )),
        Err(_) => Err(parse_error(
            file,
            Some(line),
            format!("{what}: `{token}` is not a number"),
        )),
    }
}

/// The first whitespace-separated word of a trimmed line and the trimmed rest.
fn split_keyword(line: &str) -> (&str, &str) {
    match line.find(char::is_whitespace) {
        Some(i) => (&line[..i], line[i..].trim()),
        None => (line, ""),
    }
}
