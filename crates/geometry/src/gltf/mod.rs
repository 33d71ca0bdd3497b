//! glTF 2.0 loading (`.gltf` with external or embedded buffers, and `.glb`):
//! the default scene's node tree with each node's world transform baked into
//! its meshes, metallic-roughness materials mapped to Lustre's models
//! ([`material`]), `KHR_lights_punctual` lights, the first perspective
//! camera, and base colour textures decoded (files, `data:` URIs and buffer
//! views) into [`crate::Material::diffuse_map`], their `v` flipped into the
//! scene model's convention (OBJ's, `v` up).
//!
//! Parsing and validation of the JSON and GLB container are the `gltf`
//! crate's; buffers are read here (GLB chunk, base64 `data:` URI or a file
//! beside the asset) and every accessor is checked against its buffer's
//! length and its element type before it is read, so a malformed file is an
//! error naming the file and the part at fault, never a panic.
//!
//! Units: glTF is in metres, +Y up, right-handed, as Lustre. Punctual lights
//! are photometric; Lustre is radiometric: a point or spot light of `I`
//! candela becomes `I / 683` W/sr (683 lm/W, the luminous efficacy at 555
//! nm, which Blender's exporter also uses). Directional lights have no
//! counterpart (no light at infinity) and are left out with a warning; a
//! model left without any light gets the OBJ loader's default studio.

pub mod export;
pub mod material;

pub use export::export_gltf;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::camera::Projection;
use ::gltf::khr_lights_punctual::Kind;
use ::gltf::mesh::Mode;
use base64::Engine as _;
use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::{GeometryError, Location, Result};
use crate::light::{Light, PointLight, SpotLight};
use crate::material::{Material, MaterialId};
use crate::mesh::{Mesh, MeshId};
use crate::obj::{LoadedScene, Parts, finish};
use crate::scene::Object;
use crate::{Camera, Rgb, Texture};

use material::GltfMaterial;

/// Lumens per watt at 555 nm: candela to W/sr for punctual lights.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Loads a `.gltf` or `.glb` file: its default scene (or its first).
pub fn load_gltf(path: &Path) -> Result<LoadedScene> {
    let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
        path: path.to_owned(),
        source,
    })?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.trim().is_empty())
        .unwrap_or_else(|| "scene".to_owned());
    let fail = |message: String| GeometryError::Parse {
        location: Location {
            file: path.to_owned(),
            line: None,
        },
        message,
    };
    let gltf =
        ::gltf::Gltf::from_slice(&bytes).map_err(|e| fail(format!("not valid glTF 2.0: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = read_buffers(&gltf, base).map_err(&fail)?;
    let mut warnings = Vec::new();
    let mut loader = Loader {
        buffers: &buffers,
        base,
        meshes: Vec::new(),
        objects: Vec::new(),
        lights: Vec::new(),
        camera: None,
        material_of: vec![None; gltf.document.materials().len()],
        default_material: None,
        materials: Vec::new(),
        images: HashMap::new(),
        file: path,
        warnings: &mut warnings,
    };
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| fail("the file holds no scene".into()))?;
    for node in scene.nodes() {
        loader.node(&node, Mat4::IDENTITY, 0).map_err(&fail)?;
    }
    let Loader {
        meshes,
        objects,
        lights,
        camera,
        materials,
        ..
    } = loader;
    finish(
        Parts {
            name: stem,
            meshes,
            materials,
            objects,
            lights,
            camera,
            degenerate_triangles_dropped: 0,
            warnings,
        },
        path,
    )
}

/// Every buffer's bytes: the GLB chunk, a base64 `data:` URI or a file relative to `base`.
fn read_buffers(gltf: &::gltf::Gltf, base: &Path) -> std::result::Result<Vec<Vec<u8>>, String> {
    gltf.document
        .buffers()
        .map(|buffer| {
            let what = format!("buffer {}", buffer.index());
            let data = match buffer.source() {
                ::gltf::buffer::Source::Bin => gltf
                    .blob
                    .clone()
                    .ok_or_else(|| format!("{what} is the GLB binary chunk, which is missing"))?,
                ::gltf::buffer::Source::Uri(uri) => {
                    read_uri(uri, base).map_err(|e| format!("{what}: {e}"))?
                }
            };
            if data.len() < buffer.length() {
                return Err(format!(
                    "{what} holds {} bytes, less than its declared {}",
                    data.len(),
                    buffer.length()
                ));
            }
            Ok(data)
        })
        .collect()
}

/// The bytes a buffer URI names: a base64 `data:` URI or a relative file.
fn read_uri(uri: &str, base: &Path) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("a data URI that is not base64")?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("bad base64 data: {e}"));
    }
    let file = resolve(uri, base);
    std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// A relative URI as a path beside the asset (percent-escapes for spaces decoded).
fn resolve(uri: &str, base: &Path) -> PathBuf {
    base.join(uri.replace("%20", " "))
}

/// The state of one load: what the nodes made so far.
struct Loader<'a> {
    buffers: &'a [Vec<u8>],
    base: &'a Path,
    meshes: Vec<Mesh>,
    objects: Vec<Object>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    /// The Lustre material of each glTF material, made when first used.
    material_of: Vec<Option<MaterialId>>,
    default_material: Option<MaterialId>,
    materials: Vec<Material>,
    /// Each glTF image decoded so far (`None`: it could not be, and was warned about).
    images: HashMap<usize, Option<Arc<Texture>>>,
    /// The asset, for messages.
    file: &'a Path,
    warnings: &'a mut Vec<String>,
}

/// Deepest node tree followed (the `gltf` crate's validation rejects cycles; this bounds the recursion).
const MAX_NODE_DEPTH: usize = 256;

impl Loader<'_> {
    /// A node and its subtree under the parent's world transform.
    fn node(
        &mut self,
        node: &::gltf::Node,
        parent: Mat4,
        depth: usize,
    ) -> std::result::Result<(), String> {
        if depth > MAX_NODE_DEPTH {
            return Err(format!(
                "node {}: the node tree is deeper than {MAX_NODE_DEPTH}",
                node.index()
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(format!(
                "node {}: its transform is not finite",
                node.index()
            ));
        }
        let name = node
            .name()
            .map_or_else(|| format!("node{}", node.index()), str::to_owned);
        if let Some(mesh) = node.mesh() {
            self.mesh(&mesh, &name, world)?;
        }
        if let Some(light) = node.light() {
            self.light(&light, &name, world);
        }
        if let (Some(camera), None) = (node.camera(), &self.camera) {
            self.camera = self.camera(&camera, &name, world);
        }
        for child in node.children() {
            self.node(&child, world, depth + 1)?;
        }
        Ok(())
    }

    /// A mesh's triangle primitives as one object.
    fn mesh(
        &mut self,
        mesh: &::gltf::Mesh,
        node: &str,
        world: Mat4,
    ) -> std::result::Result<(), String> {
        let linear = Mat3::from_mat4(world);
        let normal_matrix = linear.inverse().transpose();
        // A mirroring transform turns counter-clockwise triangles clockwise.
        let flip = linear.determinant() < 0.0;
        let mut ids = Vec::new();
        let count = mesh.primitives().len();
        for primitive in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), primitive.index());
            let Some(triangles) = self.triangles(&primitive, &what) else {
                continue;
            };
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
            let positions: Vec<Vec3> = checked(
                self.buffers,
                primitive.get(&::gltf::Semantic::Positions),
                &what,
                "POSITION",
                &[DataType::F32],
                Dimensions::Vec3,
            )?
            .and(reader.read_positions())
            .ok_or_else(|| format!("{what}: no readable POSITION"))?
            .map(|p| world.transform_point3(Vec3::from(p)))
            .collect();
            if positions.iter().any(|p| !p.is_finite()) {
                return Err(format!("{what}: a position is not finite"));
            }
            let list = match checked(
                self.buffers,
                primitive.indices(),
                &what,
                "indices",
                &[DataType::U8, DataType::U16, DataType::U32],
                Dimensions::Scalar,
            )? {
                Some(()) => Some(
                    reader
                        .read_indices()
                        .ok_or_else(|| format!("{what}: unreadable indices"))?
                        .into_u32()
                        .collect(),
                ),
                None => None,
            };
            let mut indices = triangle_list(list, positions.len(), triangles, &what)?;
            if flip {
                indices.iter_mut().for_each(|t| t.swap(1, 2));
            }
            if indices.is_empty() {
                self.warnings
                    .push(format!("{what}: no triangles, left out"));
                continue;
            }
            let material = self.material(primitive.material());
            let name = if count == 1 {
                node.to_owned()
            } else {
                format!("{node}:{}", primitive.index())
            };
            let normals = match checked(
                self.buffers,
                primitive.get(&::gltf::Semantic::Normals),
                &what,
                "NORMAL",
                &[DataType::F32],
                Dimensions::Vec3,
            )?
            .and(reader.read_normals())
            {
                Some(normals) => {
                    let normals: Vec<Vec3> = normals
                        .map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero())
                        .collect();
                    (normals.len() == positions.len() && normals.iter().all(|n| *n != Vec3::ZERO))
                        .then_some(normals)
                }
                None => None,
            };
            let uvs = match checked(
                self.buffers,
                primitive.get(&::gltf::Semantic::TexCoords(0)),
                &what,
                "TEXCOORD_0",
                &[DataType::F32, DataType::U8, DataType::U16],
                Dimensions::Vec2,
            )?
            .and(reader.read_tex_coords(0))
            {
                // glTF's v grows downwards from the image's top; the scene model's (OBJ's) upwards.
                Some(uvs) => uvs.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect(),
                None => vec![Vec2::ZERO; positions.len()],
            };
            let mesh = match normals {
                Some(normals) if uvs.len() == positions.len() => Mesh {
                    name,
                    positions,
                    normals,
                    uvs,
                    indices,
                    material,
                },
                // glTF: without normals, flat shading (the UVs kept).
                _ => Mesh::flat_with_uvs(name, &positions, &uvs, &indices, material),
            };
            ids.push(self.meshes.len() as MeshId);
            self.meshes.push(mesh);
        }
        if !ids.is_empty() {
            self.objects.push(Object {
                name: node.to_owned(),
                meshes: ids,
                transform: glam::Affine3A::IDENTITY,
            });
        }
        Ok(())
    }

    /// The primitive's mode as triangles, or `None` (with a warning) for points and lines.
    fn triangles(&mut self, primitive: &::gltf::Primitive, what: &str) -> Option<Mode> {
        match primitive.mode() {
            mode @ (Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) => Some(mode),
            other => {
                self.warnings
                    .push(format!("{what}: {other:?} are not surfaces, left out"));
                None
            }
        }
    }

    /// The Lustre material of a primitive's glTF material, made on first use.
    fn material(&mut self, material: ::gltf::Material) -> MaterialId {
        let slot = match material.index() {
            Some(i) => &mut self.material_of[i],
            None => &mut self.default_material,
        };
        if let Some(id) = *slot {
            return id;
        }
        let id = self.materials.len() as MaterialId;
        *slot = Some(id);
        let parameters = match material.index() {
            None => GltfMaterial::default_material(),
            Some(i) => {
                let pbr = material.pbr_metallic_roughness();
                let [r, g, b, _] = pbr.base_color_factor();
                GltfMaterial {
                    name: material
                        .name()
                        .map_or_else(|| format!("material{i}"), str::to_owned),
                    base_color: Rgb::new(r, g, b),
                    metallic: pbr.metallic_factor(),
                    roughness: pbr.roughness_factor(),
                    emission: Rgb::from(material.emissive_factor())
                        * material.emissive_strength().unwrap_or(1.0),
                    ior: material.ior().unwrap_or(1.5),
                    transmission: material
                        .transmission()
                        .map_or(0.0, |t| t.transmission_factor()),
                    volume: material.volume().map(|v| {
                        (
                            v.thickness_factor(),
                            v.attenuation_distance(),
                            Rgb::from(v.attenuation_color()),
                        )
                    }),
                }
            }
        };
        let mut lustre = parameters.to_material(self.warnings);
        if let Some(info) = material.pbr_metallic_roughness().base_color_texture() {
            self.base_colour_texture(&info, &mut lustre, parameters.metallic);
        }
        let ignored: Vec<&str> = [
            (
                material
                    .pbr_metallic_roughness()
                    .metallic_roughness_texture()
                    .is_some(),
                "metallic-roughness",
            ),
            (material.normal_texture().is_some(), "normal"),
            (material.occlusion_texture().is_some(), "occlusion"),
            (material.emissive_texture().is_some(), "emissive"),
        ]
        .into_iter()
        .filter_map(|(present, what)| present.then_some(what))
        .collect();
        if !ignored.is_empty() {
            self.warnings.push(format!(
                "material `{}`: its {} texture{} not used (Lustre draws base colour textures only)",
                lustre.name,
                ignored.join(", "),
                if ignored.len() == 1 { " is" } else { "s are" }
            ));
        }
        self.materials.push(lustre);
        id
    }

    /// Decodes a material's base colour texture into [`Material::diffuse_map`] (a file beside the asset, a `data:` URI or a buffer view), once per image; a texture that cannot be read is a warning and the material is drawn without it.
    fn base_colour_texture(
        &mut self,
        info: &::gltf::texture::Info,
        lustre: &mut Material,
        metallic: f32,
    ) {
        if info.tex_coord() != 0 {
            self.warnings.push(format!(
                "material `{}`: its base colour texture reads TEXCOORD_{}, Lustre reads only TEXCOORD_0",
                lustre.name,
                info.tex_coord()
            ));
        }
        if metallic > 0.0 {
            self.warnings.push(format!(
                "material `{}`: its base colour texture tints only the diffuse part (metallic {metallic}), not the metal's reflectance",
                lustre.name
            ));
        }
        let image = info.texture().source();
        let slot = image.index();
        if let Some(decoded) = self.images.get(&slot) {
            lustre.diffuse_map = decoded.clone();
            if let ::gltf::image::Source::Uri { uri, .. } = image.source()
                && !uri.starts_with("data:")
            {
                lustre.diffuse_texture = Some(resolve(uri, self.base));
            }
            return;
        }
        let name = format!("image {slot}");
        let bytes = match image.source() {
            ::gltf::image::Source::Uri { uri, .. } => {
                if !uri.starts_with("data:") {
                    lustre.diffuse_texture = Some(resolve(uri, self.base));
                }
                read_uri(uri, self.base)
            }
            ::gltf::image::Source::View { view, .. } => self
                .buffers
                .get(view.buffer().index())
                .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
                .map(<[u8]>::to_vec)
                .ok_or_else(|| format!("its buffer view {} lies outside its buffer", view.index())),
        };
        let decoded = bytes
            .and_then(|bytes| {
                let label = lustre.diffuse_texture.as_ref().map_or_else(
                    || format!("{}: {name}", self.file.display()),
                    |f| f.display().to_string(),
                );
                Texture::decode(&bytes, &label).map_err(|e| e.to_string())
            })
            .map(Arc::new)
            .map_err(|e| {
                self.warnings.push(format!(
                    "material `{}`: base colour texture ({name}) not used: {e}",
                    lustre.name
                ))
            })
            .ok();
        self.images.insert(slot, decoded.clone());
        lustre.diffuse_map = decoded;
    }

    /// A `KHR_lights_punctual` light at the node's pose (glTF lights shine down their node's −Z).
    fn light(&mut self, light: &::gltf::khr_lights_punctual::Light, node: &str, world: Mat4) {
        let colour = Rgb::from(light.color()).max(Rgb::ZERO);
        let intensity = colour * (light.intensity().max(0.0) / LUMENS_PER_WATT);
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if light.range().is_some() {
            self.warnings.push(format!(
                "light at node `{node}`: its range is ignored (Lustre's lights fall off with the square of the distance everywhere)"
            ));
        }
        match light.kind() {
            Kind::Point => self.lights.push(Light::Point(PointLight {
                position,
                intensity,
            })),
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } if direction != Vec3::ZERO => self.lights.push(Light::Spot(SpotLight {
                position,
                direction,
                intensity,
                cutoff_angle: outer_cone_angle,
                beam_width: inner_cone_angle.min(outer_cone_angle),
            })),
            Kind::Spot { .. } => self.warnings.push(format!(
                "spot light at node `{node}`: its node's transform has no direction, left out"
            )),
            Kind::Directional => self.warnings.push(format!(
                "directional light at node `{node}`: Lustre has no light at infinity, left out"
            )),
        }
    }

    /// A perspective camera at the node's pose (glTF cameras look down −Z with +Y up); `None` with a warning for an orthographic one.
    fn camera(&mut self, camera: &::gltf::Camera, node: &str, world: Mat4) -> Option<Camera> {
        match camera.projection() {
            Projection::Perspective(p) => {
                let position = world.transform_point3(Vec3::ZERO);
                let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
                let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
                let fov = p.yfov().to_degrees();
                if forward == Vec3::ZERO || up == Vec3::ZERO || !(fov > 0.0 && fov < 180.0) {
                    self.warnings.push(format!(
                        "camera at node `{node}`: degenerate, the model is framed instead"
                    ));
                    return None;
                }
                let mut camera = Camera::look_at(position, position + forward, up, fov);
                if let Some(aspect) = p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0) {
                    camera = camera.with_aspect(aspect);
                }
                if p.znear().is_finite() && p.znear() > 0.0 {
                    camera.near = p.znear();
                }
                Some(camera)
            }
            Projection::Orthographic(_) => {
                self.warnings.push(format!(
                    "camera at node `{node}`: orthographic cameras are not supported, the model is framed instead"
                ));
                None
            }
        }
    }
}

/// Counter-clockwise triangles from a primitive's index list (or its vertices in order when it has none), strips and fans unrolled, degenerate ones dropped; an error for an index out of range.
fn triangle_list(
    list: Option<Vec<u32>>,
    vertices: usize,
    mode: Mode,
    what: &str,
) -> std::result::Result<Vec<[u32; 3]>, String> {
    let list = list.unwrap_or_else(|| (0..vertices as u32).collect());
    if let Some(&bad) = list.iter().find(|&&i| i as usize >= vertices) {
        return Err(format!(
            "{what}: index {bad} is out of range of its {vertices} vertices"
        ));
    }
    let triangles: Vec<[u32; 3]> = match mode {
        // Every other triangle of a strip is wound the other way.
        Mode::TriangleStrip => list
            .windows(3)
            .enumerate()
            .map(|(i, w)| {
                if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                }
            })
            .collect(),
        Mode::TriangleFan => list
            .windows(2)
            .skip(1)
            .map(|w| [list[0], w[0], w[1]])
            .collect(),
        _ => list.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    Ok(triangles
        .into_iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect())
}

/// `Some(())` when the accessor exists and has the expected element type and dimensions; an error when it has another, `None` when absent.
fn checked(
    buffers: &[Vec<u8>],
    accessor: Option<::gltf::Accessor>,
    what: &str,
    semantic: &str,
    types: &[DataType],
    dimensions: Dimensions,
) -> std::result::Result<Option<()>, String> {
    let Some(accessor) = accessor else {
        return Ok(None);
    };
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dimensions {
        return Err(format!(
            "{what}: {semantic} is {:?} {:?}, not {dimensions:?} of {types:?}",
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    if accessor.count() == 0 {
        return Err(format!("{what}: {semantic} is empty"));
    }
    if accessor.sparse().is_some() {
        return Err(format!(
            "{what}: {semantic} is a sparse accessor, which is not supported"
        ));
    }
    let view = accessor
        .view()
        .ok_or_else(|| format!("{what}: {semantic} has no buffer view"))?;
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "{what}: {semantic}'s stride {stride} is shorter than its {size}-byte elements"
        ));
    }
    let buffer = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view.offset() + view.length() > buffer {
        return Err(format!(
            "{what}: {semantic}'s buffer view ends at byte {} of a {buffer}-byte buffer",
            view.offset() + view.length()
        ));
    }
    let end = accessor.offset() + stride * (accessor.count() - 1) + size;
    if end > view.length() {
        return Err(format!(
            "{what}: {semantic} reaches byte {end} of its buffer view of {} bytes",
            view.length()
        ));
    }
    Ok(Some(()))
}
