//! Diffuse texture maps as the loaders read them: MTL `map_Kd` and glTF
//! `baseColorTexture` (a file, a `data:` URI, a GLB buffer view) decoded into
//! `Material::diffuse_map`, glTF's `v` flipped into OBJ's convention, and
//! what a hit reads from them; against images these tests write themselves.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use base64::Engine as _;
use glam::{Vec2, Vec3};
use lustre_geometry::gltf::{export_gltf, load_gltf};
use lustre_geometry::texture::srgb_to_linear;
use lustre_geometry::{Bvh, Ray, Rgb, load_obj};
use serde_json::json;

mod support;

use support::{Dir, glb};

/// A 2 × 2 PNG: top row red (255, 0, 0) and green (0, 255, 0), bottom row blue (0, 0, 255) and grey (128, 128, 128).
fn quadrants_png() -> Vec<u8> {
    let colours = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]];
    let img = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(colours[(2 * y + x) as usize]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

const GREY: f32 = 128.0 / 255.0;

/// The linear colour of each quadrant of [`quadrants_png`]: top left, top right, bottom left, bottom right.
fn quadrant_colours() -> [Rgb; 4] {
    [Rgb::X, Rgb::Y, Rgb::Z, Rgb::splat(srgb_to_linear(GREY))]
}

fn close(a: Rgb, b: Rgb) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// A unit floor quad at y = 0 with UVs 0..1 (v up: the far edge z = −1 is v = 1), a light above it, and its MTL.
fn write_obj(dir: &Path, mtl: &str) -> PathBuf {
    std::fs::write(dir.join("floor.mtl"), mtl).unwrap();
    let obj = "mtllib floor.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
        usemtl floor\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n\
        v 0.4 2 -0.4\nv 0.6 2 -0.4\nv 0.6 2 -0.6\nv 0.4 2 -0.6\n\
        usemtl light\nf 5 8 7\nf 5 7 6\n";
    let path = dir.join("floor.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// The diffuse tint where a ray straight down meets the floor at `(x, z)`.
fn tint_at(scene: &lustre_geometry::Scene, x: f32, z: f32) -> Rgb {
    let bvh = Bvh::build(scene);
    let hit = bvh
        .closest_hit(&Ray::new(Vec3::new(x, 1.0, z), Vec3::NEG_Y))
        .expect("the ray meets the floor");
    scene.materials()[hit.material as usize].diffuse_tint(hit.uv)
}

#[test]
fn map_kd_is_decoded_and_hits_read_it_the_right_way_up() {
    let dir = Dir::new("obj");
    std::fs::write(dir.0.join("quadrants.png"), quadrants_png()).unwrap();
    let path = write_obj(
        &dir.0,
        "newmtl floor\nKd 0.5 0.5 0.5\nmap_Kd quadrants.png\n\
         newmtl other\nKd 0.8 0.8 0.8\nmap_Kd quadrants.png\n\
         newmtl light\nKd 0 0 0\nKe 10 10 10\n",
    );
    let loaded = load_obj(&path).unwrap();
    let scene = &loaded.scene;
    let floor = scene
        .materials()
        .iter()
        .find(|m| m.name == "floor")
        .unwrap();
    let map = floor.diffuse_map.as_ref().expect("map_Kd decoded");
    assert_eq!((map.width(), map.height()), (2, 2));
    assert_eq!(
        floor.diffuse_texture.as_deref(),
        Some(dir.0.join("quadrants.png").as_path())
    );
    // The far edge of the floor (z = −1) is v = 1, the image's top row.
    let [top_left, top_right, bottom_left, bottom_right] = quadrant_colours();
    assert!(close(tint_at(scene, 0.25, -0.75), top_left));
    assert!(close(tint_at(scene, 0.75, -0.75), top_right));
    assert!(close(tint_at(scene, 0.25, -0.25), bottom_left));
    assert!(close(tint_at(scene, 0.75, -0.25), bottom_right));
    // Kd is kept; the map scales it.
    assert_eq!(floor.model.diffuse_reflectance(), Rgb::splat(0.5));
    // Exported as glTF (the map as a 16-bit PNG in the buffer) and read back, the hits read the same.
    for ext in ["glb", "gltf"] {
        let out = dir.0.join(format!("floor.{ext}"));
        export_gltf(scene, &out).unwrap();
        let back = load_gltf(&out).unwrap();
        for (x, z) in [
            (0.25, -0.75),
            (0.75, -0.75),
            (0.3, -0.2),
            (0.5, -0.5),
            (0.9, -0.6),
        ] {
            let (a, b) = (tint_at(scene, x, z), tint_at(&back.scene, x, z));
            assert!(
                (a - b).abs().max_element() < 1e-4,
                "{ext} at ({x}, {z}): {a} {b}"
            );
        }
    }
    // The light is untextured: a tint of one.
    let light = scene
        .materials()
        .iter()
        .find(|m| m.name == "light")
        .unwrap();
    assert!(light.diffuse_map.is_none());
    assert_eq!(light.diffuse_tint(Vec2::splat(0.3)), Rgb::ONE);
}

#[test]
fn one_file_is_decoded_once_and_kd_defaults_to_one_under_a_map() {
    let dir = Dir::new("shared");
    std::fs::write(dir.0.join("quadrants.png"), quadrants_png()).unwrap();
    let mtl = "newmtl floor\nmap_Kd quadrants.png\n\
         newmtl other\nKd 0.8 0.8 0.8\nmap_Kd quadrants.png\n\
         newmtl light\nKd 0 0 0\nKe 10 10 10\n";
    let path = write_obj(&dir.0, mtl);
    // `other` is defined but unused by faces; load the library itself to see both.
    let library = lustre_geometry::obj::load_mtl(&dir.0.join("floor.mtl")).unwrap();
    let maps: Vec<_> = library
        .materials
        .iter()
        .filter_map(|m| m.diffuse_map.clone())
        .collect();
    assert_eq!(maps.len(), 2);
    assert!(Arc::ptr_eq(&maps[0], &maps[1]), "decoded once, shared");
    let floor = &library.materials[0];
    assert_eq!(
        floor.model.diffuse_reflectance(),
        Rgb::ONE,
        "map_Kd without Kd"
    );
    assert!(load_obj(&path).is_ok());
}

#[test]
fn an_undecodable_or_missing_map_is_a_warning_not_a_failure() {
    let dir = Dir::new("bad");
    std::fs::write(dir.0.join("broken.png"), b"this is no PNG").unwrap();
    let path = write_obj(
        &dir.0,
        "newmtl floor\nKd 0.5 0.5 0.5\nmap_Kd broken.png\n\
         newmtl light\nKd 0 0 0\nKe 10 10 10\n",
    );
    let loaded = load_obj(&path).unwrap();
    let floor = loaded
        .scene
        .materials()
        .iter()
        .find(|m| m.name == "floor")
        .unwrap();
    assert!(floor.diffuse_map.is_none());
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("floor") && w.contains("broken.png")),
        "{:?}",
        loaded.warnings
    );
    assert_eq!(tint_at(&loaded.scene, 0.5, -0.5), Rgb::ONE);
}

/// A glTF document of one unit quad at y = 0 (corners as [`write_obj`]'s floor, UVs in glTF's convention: v = 0 at the far edge) and a point light, its base colour texture from `image`.
fn gltf_document(
    buffer_uri: Option<String>,
    image: serde_json::Value,
) -> (serde_json::Value, Vec<u8>) {
    let mut bin = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, -1.0],
        [0.0, 0.0, -1.0],
    ] {
        p.iter()
            .for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
    }
    for _ in 0..4 {
        [0.0f32, 1.0, 0.0]
            .iter()
            .for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
    }
    // glTF's v grows downwards: the far edge (z = −1) is the image's top, v = 0.
    for uv in [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        uv.iter()
            .for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let png = quadrants_png();
    let png_offset = bin.len();
    bin.extend_from_slice(&png);
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.5, 2.0, -0.5]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
        "materials": [{"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0, "baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [image],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32},
            {"buffer": 0, "byteOffset": 128, "byteLength": 12},
            {"buffer": 0, "byteOffset": png_offset, "byteLength": png.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, -1], "max": [1, 0, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    if let Some(uri) = buffer_uri {
        doc["buffers"][0]["uri"] = json!(uri);
    }
    (doc, bin)
}

fn check_gltf_floor(path: &Path) {
    let loaded = load_gltf(path).unwrap();
    let scene = &loaded.scene;
    let floor = &scene.materials()[scene.meshes()[0].material as usize];
    assert!(
        floor.diffuse_map.is_some(),
        "{}: {:?}",
        path.display(),
        loaded.warnings
    );
    let [top_left, top_right, bottom_left, bottom_right] = quadrant_colours();
    assert!(
        close(tint_at(scene, 0.25, -0.75), top_left),
        "{}",
        path.display()
    );
    assert!(close(tint_at(scene, 0.75, -0.75), top_right));
    assert!(close(tint_at(scene, 0.25, -0.25), bottom_left));
    assert!(close(tint_at(scene, 0.75, -0.25), bottom_right));
}

#[test]
fn gltf_base_colour_textures_from_files_data_uris_and_buffer_views() {
    let dir = Dir::new("gltf");
    std::fs::write(dir.0.join("quadrants.png"), quadrants_png()).unwrap();
    // An image file beside the asset, the buffer as a .bin file.
    let (doc, bin) = gltf_document(Some("floor.bin".into()), json!({"uri": "quadrants.png"}));
    std::fs::write(dir.0.join("floor.bin"), &bin).unwrap();
    let file = dir.0.join("file.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    check_gltf_floor(&file);
    let loaded = load_gltf(&file).unwrap();
    let floor = &loaded.scene.materials()[0];
    assert_eq!(
        floor.diffuse_texture.as_deref(),
        Some(dir.0.join("quadrants.png").as_path())
    );
    // A data: URI.
    let uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(quadrants_png())
    );
    let (doc, _) = gltf_document(Some("floor.bin".into()), json!({"uri": uri}));
    let data = dir.0.join("data.gltf");
    std::fs::write(&data, serde_json::to_vec(&doc).unwrap()).unwrap();
    check_gltf_floor(&data);
    // A buffer view of a GLB's BIN chunk.
    let (doc, bin) = gltf_document(None, json!({"bufferView": 4, "mimeType": "image/png"}));
    let view = dir.0.join("view.glb");
    std::fs::write(&view, glb(&doc, &bin)).unwrap();
    check_gltf_floor(&view);
}

#[test]
fn a_broken_gltf_image_is_a_warning_and_the_v_flip_survives_export() {
    let dir = Dir::new("gltf-bad");
    let (doc, bin) = gltf_document(Some("floor.bin".into()), json!({"uri": "missing.png"}));
    std::fs::write(dir.0.join("floor.bin"), &bin).unwrap();
    let path = dir.0.join("bad.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let loaded = load_gltf(&path).unwrap();
    assert!(loaded.scene.materials()[0].diffuse_map.is_none());
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("floor") && w.contains("missing.png")),
        "{:?}",
        loaded.warnings
    );
    // The UVs as loaded are OBJ's: the far edge is v = 1.
    let uvs = &loaded.scene.meshes()[0].uvs;
    assert_eq!(uvs[2], Vec2::new(1.0, 1.0));
    assert_eq!(uvs[0], Vec2::new(0.0, 0.0));
    // Exported and read back, they are the same.
    let out = dir.0.join("out.glb");
    export_gltf(&loaded.scene, &out).unwrap();
    let back = load_gltf(&out).unwrap();
    assert_eq!(&back.scene.meshes()[0].uvs, uvs);
}
