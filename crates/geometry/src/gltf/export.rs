//! glTF 2.0 export: a scene as `.glb`, or as `.gltf` with its buffer in a
//! base64 `data:` URI, that [`super::load_gltf`] loads back as the same
//! scene (the round trip the tests hold every built-in scene to).
//!
//! Each object becomes a node holding one mesh with a primitive per Lustre
//! mesh, its vertices in world space at the scene's current pose (the
//! node's transform is the identity); materials go through
//! [`GltfMaterial::from_material`]; point and spot lights become
//! `KHR_lights_punctual` lights of `683 I` candela; the camera a
//! perspective camera node. Area lights are their emissive meshes. A
//! material's diffuse map becomes its base colour texture, a 16-bit sRGB PNG
//! in the buffer. What glTF
//! cannot hold (cosine point lights, models without a glTF counterpart) is
//! left out or approximated, one warning each.

use std::path::Path;

use base64::Engine as _;
use glam::{Mat3, Quat, Vec3};
use serde_json::{Value, json};

use super::LUMENS_PER_WATT;
use super::material::GltfMaterial;
use crate::error::Result;
use crate::light::Light;
use crate::mitsuba::write_atomically;
use crate::scene::Scene;

/// Writes `scene` to `path`: binary glTF when it ends in `.glb`, else JSON with an embedded buffer. Returns the warnings. The file is written to a temporary name and renamed, so a failure leaves no partial file.
pub fn export_gltf(scene: &Scene, path: &Path) -> Result<Vec<String>> {
    let mut warnings = Vec::new();
    let mut buffer = Buffer::default();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for object in scene.objects() {
        let mut primitives = Vec::new();
        for &m in &object.meshes {
            let mesh = &scene.meshes()[m as usize];
            let positions = scene.world_positions(m);
            let normals = scene.world_normals(m);
            let (min, max) = positions.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            let position = buffer.accessor(
                positions.iter().flat_map(|p| p.to_array()),
                positions.len(),
                "VEC3",
                Some((min.to_array(), max.to_array())),
            );
            let normal = buffer.accessor(
                normals.iter().flat_map(|n| n.to_array()),
                normals.len(),
                "VEC3",
                None,
            );
            let uv = buffer.accessor(
                // Back into glTF's v, which grows downwards.
                mesh.uvs.iter().flat_map(|u| [u.x, 1.0 - u.y]),
                mesh.uvs.len(),
                "VEC2",
                None,
            );
            let indices = buffer.indices(&mesh.indices);
            primitives.push(json!({
                "attributes": {"POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv},
                "indices": indices,
                "material": mesh.material,
            }));
        }
        if primitives.is_empty() {
            continue;
        }
        nodes.push(json!({"name": object.name, "mesh": meshes.len()}));
        meshes.push(json!({"name": object.name, "primitives": primitives}));
    }
    let mut images: Vec<Value> = Vec::new();
    let mut textures: Vec<Value> = Vec::new();
    let mut materials: Vec<Value> = Vec::new();
    for m in scene.materials() {
        let mut material = material_json(&GltfMaterial::from_material(m, &mut warnings));
        if let Some(map) = &m.diffuse_map {
            // The base colour texture: the diffuse map as a 16-bit PNG in the buffer.
            let png = map.encode_png16()?;
            let start = buffer.bytes.len();
            buffer.bytes.extend_from_slice(&png);
            let view = buffer.raw_view(start);
            images.push(json!({"bufferView": view, "mimeType": "image/png"}));
            textures.push(json!({"source": images.len() - 1}));
            material["pbrMetallicRoughness"]["baseColorTexture"] =
                json!({"index": textures.len() - 1});
        }
        materials.push(material);
    }
    let mut lights = Vec::new();
    for (i, light) in scene.lights().iter().enumerate() {
        let (position, direction, intensity, spot) = match light {
            Light::Point(p) => (p.position, None, p.intensity, None),
            Light::Spot(s) => (
                s.position,
                Some(s.direction),
                s.intensity,
                Some(json!({"innerConeAngle": s.beam_width, "outerConeAngle": s.cutoff_angle})),
            ),
            Light::Area(_) => continue,
            Light::OrientedPoint(_) => {
                warnings.push(format!(
                    "light {i}: a cosine point light has no glTF counterpart; left out"
                ));
                continue;
            }
        };
        let peak = intensity.max_element().max(f32::MIN_POSITIVE);
        let mut light = json!({
            "type": if spot.is_some() { "spot" } else { "point" },
            "color": (intensity / peak).to_array(),
            "intensity": peak * LUMENS_PER_WATT,
        });
        if let Some(spot) = spot {
            light["spot"] = spot;
        }
        let mut node = json!({
            "name": format!("light{i}"),
            "translation": position.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": lights.len()}},
        });
        if let Some(direction) = direction {
            node["rotation"] = json!(Quat::from_rotation_arc(Vec3::NEG_Z, direction).to_array());
        }
        nodes.push(node);
        lights.push(light);
    }
    let camera = scene.camera();
    let forward = (camera.target - camera.position).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    // glTF cameras look down −Z with +Y up: the rotation's columns are right, up and −forward.
    let rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -forward));
    nodes.push(json!({
        "name": "camera",
        "translation": camera.position.to_array(),
        "rotation": rotation.to_array(),
        "camera": 0,
    }));
    let mut used = vec![
        "KHR_materials_ior",
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_materials_emissive_strength",
    ];
    if !lights.is_empty() {
        used.push("KHR_lights_punctual");
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "Lustre (lustre-geometry)"},
        "extensionsUsed": used,
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": camera.fov_y_degrees.to_radians(),
            "aspectRatio": camera.aspect,
            "znear": camera.near,
        }}],
        "buffers": [{"byteLength": buffer.bytes.len()}],
        "bufferViews": buffer.views,
        "accessors": buffer.accessors,
    });
    if !lights.is_empty() {
        doc["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    if !images.is_empty() {
        doc["images"] = json!(images);
        doc["textures"] = json!(textures);
    }
    let glb = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let bytes = if glb {
        binary(&doc, &buffer.bytes)
    } else {
        doc["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&buffer.bytes)
        ));
        serde_json::to_vec_pretty(&doc).unwrap_or_default()
    };
    write_atomically(path, &bytes)?;
    Ok(warnings)
}

/// The glTF JSON of a material.
fn material_json(m: &GltfMaterial) -> Value {
    let strength = m.emission.max_element();
    let mut material = json!({
        "name": m.name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [m.base_color.x, m.base_color.y, m.base_color.z, 1.0],
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness,
        },
        "extensions": {"KHR_materials_ior": {"ior": m.ior}},
    });
    if m.transmission > 0.0 {
        material["extensions"]["KHR_materials_transmission"] =
            json!({"transmissionFactor": m.transmission});
    }
    if let Some((thickness, distance, colour)) = m.volume {
        let mut volume =
            json!({"thicknessFactor": thickness, "attenuationColor": colour.to_array()});
        if distance.is_finite() {
            volume["attenuationDistance"] = json!(distance);
        }
        material["extensions"]["KHR_materials_volume"] = volume;
    }
    if strength > 0.0 {
        material["emissiveFactor"] = json!((m.emission / strength).to_array());
        material["extensions"]["KHR_materials_emissive_strength"] =
            json!({"emissiveStrength": strength});
    }
    material
}

/// The one buffer of an export, with its views and accessors.
#[derive(Default)]
struct Buffer {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffer {
    /// Appends `count` float elements of `kind` (VEC2, VEC3) as a view and an accessor; returns the accessor's index.
    fn accessor(
        &mut self,
        values: impl Iterator<Item = f32>,
        count: usize,
        kind: &str,
        bounds: Option<([f32; 3], [f32; 3])>,
    ) -> usize {
        let start = self.bytes.len();
        values.for_each(|v| self.bytes.extend_from_slice(&v.to_le_bytes()));
        let mut accessor = json!({
            "bufferView": self.view(start, 34962),
            "componentType": 5126,
            "count": count,
            "type": kind,
        });
        if let Some((min, max)) = bounds {
            (accessor["min"], accessor["max"]) = (json!(min), json!(max));
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Appends triangle indices as u32; returns the accessor's index.
    fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let start = self.bytes.len();
        triangles
            .iter()
            .flatten()
            .for_each(|i| self.bytes.extend_from_slice(&i.to_le_bytes()));
        let view = self.view(start, 34963);
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": 5125,
            "count": 3 * triangles.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// A view without a target of the bytes from `start` to the end (an image), the buffer then padded to 4 bytes for the views after it.
    fn raw_view(&mut self, start: usize) -> usize {
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": start,
            "byteLength": self.bytes.len() - start,
        }));
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views.len() - 1
    }

    /// A view of the bytes from `start` to the end (4-byte aligned: every element here is 4 bytes).
    fn view(&mut self, start: usize, target: u32) -> usize {
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": start,
            "byteLength": self.bytes.len() - start,
            "target": target,
        }));
        self.views.len() - 1
    }
}

/// A GLB container (glTF 2.0, section 4.4): the JSON chunk padded with spaces, the binary chunk with zeros.
fn binary(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap_or_default();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}
