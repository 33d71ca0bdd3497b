//! glTF 2.0 loading against files these tests write themselves: geometry
//! under node transforms, materials, punctual lights, cameras, the GLB
//! container, and malformed files refused with the file and the part named.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::{Quat, Vec3};
use lustre_geometry::gltf::{LUMENS_PER_WATT, load_gltf};
use lustre_geometry::light::Light;
use lustre_geometry::material::MaterialModel;
use serde_json::{Value, json};

mod support;

use support::{Dir, glb};

/// One buffer: a unit square in the XY plane facing +Z (four positions, four normals, two triangles as u16).
fn square_buffer() -> Vec<u8> {
    let mut bytes = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ] {
        p.iter()
            .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
    }
    for _ in 0..4 {
        [0.0f32, 0.0, 1.0]
            .iter()
            .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes
}

/// A glTF document around [`square_buffer`]: `nodes`, `materials` and `extensions` as given, the buffer at `uri`.
fn document(uri: Option<String>, nodes: Value, materials: Value, extra: Value) -> Value {
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.as_array().unwrap().len()).filter(|&i| i == 0 || !nodes[0].get("children").is_some_and(|c| c.as_array().unwrap().contains(&json!(i)))).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": materials,
        "buffers": [{"byteLength": 108}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    if let Some(uri) = uri {
        doc["buffers"][0]["uri"] = json!(uri);
    }
    for (k, v) in extra.as_object().unwrap() {
        doc[k] = v.clone();
    }
    doc
}

fn data_uri(bytes: &[u8]) -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec_pretty(doc).unwrap()).unwrap();
    path
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn nodes_place_meshes_lights_and_the_camera() {
    let dir = Dir::new("nodes");
    let rotation = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    // The parent moves by (10, 0, 0) and scales by 2; the child turns 90° about +Y.
    let nodes = json!([
        {"name": "parent", "translation": [10, 0, 0], "scale": [2, 2, 2], "children": [1, 2, 3, 4]},
        {"name": "square", "mesh": 0, "rotation": rotation.to_array()},
        {"name": "bulb", "translation": [0, 3, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "spot", "translation": [0, 2, 0], "rotation": Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2).to_array(), "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "eye", "translation": [0, 0, 5], "camera": 0}
    ]);
    let materials = json!([{"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.8, 0.3, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.4}}]);
    let extra = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 683.0},
            {"type": "spot", "intensity": 1366.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
        ]}},
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05, "aspectRatio": 1.5}}]
    });
    let path = write(
        dir.0.as_path(),
        "nodes.gltf",
        &document(Some(data_uri(&square_buffer())), nodes, materials, extra),
    );
    let loaded = load_gltf(&path).unwrap();
    assert!(loaded.studio.is_none(), "the file has lights");
    let scene = &loaded.scene;
    assert_eq!(scene.name, "nodes");
    let mesh = &scene.meshes()[0];
    assert_eq!(mesh.name, "square");
    // Corner (1, 0, 0) turned about +Y is (0, 0, -1), scaled by 2, moved by 10.
    assert!(
        close(mesh.positions[1], Vec3::new(10.0, 0.0, -2.0)),
        "{}",
        mesh.positions[1]
    );
    assert!(close(mesh.positions[2], Vec3::new(10.0, 2.0, -2.0)));
    // The normal +Z turns to +X and stays unit.
    assert!(close(mesh.normals[0], Vec3::X), "{}", mesh.normals[0]);
    // Winding agrees with the normal.
    let [a, b, c] = mesh.indices[0].map(|i| mesh.positions[i as usize]);
    assert!((b - a).cross(c - a).normalize().dot(mesh.normals[0]) > 0.99);
    let MaterialModel::RoughConductor { alpha, .. } =
        scene.materials()[mesh.material as usize].model
    else {
        panic!("gold is a rough conductor");
    };
    assert!((alpha - 0.16).abs() < 1e-6);

    let Light::Point(bulb) = &scene.lights()[0] else {
        panic!("a point light first");
    };
    assert!(close(bulb.position, Vec3::new(10.0, 6.0, 0.0)));
    // 683 cd of (1, 0.5, 0.25): 1 W/sr times the colour.
    assert!(close(
        bulb.intensity,
        Vec3::new(1.0, 0.5, 0.25) * 683.0 / LUMENS_PER_WATT
    ));
    let Light::Spot(spot) = &scene.lights()[1] else {
        panic!("a spot light second");
    };
    // −Z turned by −90° about X points down.
    assert!(close(spot.direction, Vec3::NEG_Y), "{}", spot.direction);
    assert!(close(spot.intensity, Vec3::splat(2.0)));
    assert_eq!((spot.beam_width, spot.cutoff_angle), (0.2, 0.5));

    let camera = scene.camera();
    assert!(close(camera.position, Vec3::new(10.0, 0.0, 10.0)));
    assert!(
        (camera.target - camera.position)
            .normalize()
            .dot(Vec3::NEG_Z)
            > 0.9999
    );
    assert!((camera.fov_y_degrees - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!((camera.aspect, camera.near), (1.5, 0.05));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn a_glb_and_a_gltf_with_a_bin_file_load_the_same_scene() {
    let dir = Dir::new("glb");
    let nodes = json!([{"name": "square", "mesh": 0}]);
    let materials = json!([{"emissiveFactor": [1.0, 1.0, 1.0], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5.0}}}]);
    let extra = json!({"extensionsUsed": ["KHR_materials_emissive_strength"]});
    let bin = square_buffer();
    std::fs::write(dir.0.join("square data.bin"), &bin).unwrap();
    let external = write(
        &dir.0,
        "square.gltf",
        &document(
            Some("square%20data.bin".into()),
            nodes.clone(),
            materials.clone(),
            extra.clone(),
        ),
    );
    let binary = dir.0.join("square.glb");
    std::fs::write(&binary, glb(&document(None, nodes, materials, extra), &bin)).unwrap();
    let a = load_gltf(&external).unwrap();
    let b = load_gltf(&binary).unwrap();
    assert_eq!(a.scene.meshes(), b.scene.meshes());
    assert_eq!(a.scene.materials(), b.scene.materials());
    // The emissive square is the light: no studio, emission 1 × 5.
    assert!(a.studio.is_none());
    assert_eq!(a.scene.materials()[0].emission, Vec3::splat(5.0));
    assert_eq!(a.scene.lights().len(), 1);
}

#[test]
fn a_model_without_light_or_camera_is_framed_in_the_studio() {
    let dir = Dir::new("studio");
    // No material: the specification's default (white rough metal).
    let mut doc = document(
        Some(data_uri(&square_buffer())),
        json!([{"mesh": 0}]),
        json!([]),
        json!({}),
    );
    doc["meshes"][0]["primitives"][0]
        .as_object_mut()
        .unwrap()
        .remove("material");
    doc.as_object_mut().unwrap().remove("materials");
    let loaded = load_gltf(&write(&dir.0, "bare.gltf", &doc)).unwrap();
    assert!(loaded.studio.is_some());
    assert!(
        loaded.warnings.iter().any(|w| w.contains("default studio")),
        "{:?}",
        loaded.warnings
    );
    assert_eq!(loaded.scene.materials()[0].name, "gltf-default");
    assert!(matches!(
        loaded.scene.materials()[0].model,
        MaterialModel::RoughConductor { alpha, .. } if alpha == 1.0
    ));
    // The framing camera looks at the square's centre.
    let camera = loaded.scene.camera();
    assert!(
        close(camera.target, Vec3::new(0.5, 0.5, 0.0)),
        "{}",
        camera.target
    );
}

#[test]
fn a_mirroring_node_keeps_triangles_facing_their_normals() {
    let dir = Dir::new("mirror");
    let doc = document(
        Some(data_uri(&square_buffer())),
        json!([{"mesh": 0, "scale": [-1, 1, 1]}]),
        json!([{}]),
        json!({}),
    );
    let loaded = load_gltf(&write(&dir.0, "mirror.gltf", &doc)).unwrap();
    let mesh = &loaded.scene.meshes()[0];
    for t in &mesh.indices {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        assert!(
            (b - a)
                .cross(c - a)
                .normalize()
                .dot(mesh.normals[t[0] as usize])
                > 0.99
        );
    }
}

/// A change that breaks a good document.
type Breaker = Box<dyn Fn(&mut Value)>;

#[test]
fn malformed_files_are_refused_naming_the_file_and_the_part() {
    let dir = Dir::new("bad");
    let good = document(
        Some(data_uri(&square_buffer())),
        json!([{"mesh": 0}]),
        json!([{}]),
        json!({}),
    );
    let cases: Vec<(&str, Breaker, &str)> = vec![
        (
            "index",
            Box::new(|d: &mut Value| {
                let mut bytes = square_buffer();
                bytes[96 + 4] = 9; // the third index becomes 9
                d["buffers"][0]["uri"] = json!(data_uri(&bytes));
            }),
            "index 9 is out of range",
        ),
        (
            "short",
            Box::new(|d: &mut Value| {
                d["buffers"][0]["uri"] = json!(data_uri(&square_buffer()[..50]));
            }),
            "less than its declared",
        ),
        (
            "type",
            Box::new(|d: &mut Value| {
                d["accessors"][0]["componentType"] = json!(5123);
            }),
            "POSITION",
        ),
        (
            "missing",
            Box::new(|d: &mut Value| {
                d["buffers"][0]["uri"] = json!("nowhere.bin");
            }),
            "nowhere.bin",
        ),
        (
            "reference",
            Box::new(|d: &mut Value| {
                d["meshes"][0]["primitives"][0]["indices"] = json!(7);
            }),
            "not valid glTF",
        ),
        (
            "overrun",
            Box::new(|d: &mut Value| {
                d["accessors"][1]["count"] = json!(40);
            }),
            "NORMAL",
        ),
    ];
    for (name, break_it, expected) in cases {
        let mut doc = good.clone();
        break_it(&mut doc);
        let path = write(&dir.0, &format!("{name}.gltf"), &doc);
        let error = load_gltf(&path).unwrap_err().to_string();
        assert!(error.contains(&format!("{name}.gltf")), "{name}: {error}");
        assert!(error.contains(expected), "{name}: {error}");
    }
    std::fs::write(dir.0.join("text.gltf"), b"{ not json").unwrap();
    let error = load_gltf(&dir.0.join("text.gltf")).unwrap_err().to_string();
    assert!(
        error.contains("text.gltf") && error.contains("not valid glTF"),
        "{error}"
    );
    let truncated = glb(&good, &square_buffer());
    std::fs::write(dir.0.join("cut.glb"), &truncated[..30]).unwrap();
    let error = load_gltf(&dir.0.join("cut.glb")).unwrap_err().to_string();
    assert!(error.contains("cut.glb"), "{error}");
    assert!(load_gltf(&dir.0.join("absent.glb")).is_err());
}

/// Every built-in scene exported to glTF and loaded back is the same scene: meshes (world positions, normals, UVs, winding), lights, camera, and each material the loader can make; the others were approximated with a warning.
#[test]
fn built_in_scenes_survive_a_round_trip() {
    use lustre_geometry::builtin::{BUILTIN_SCENES, builtin};
    use lustre_geometry::gltf::export_gltf;
    let dir = Dir::new("roundtrip");
    for name in BUILTIN_SCENES {
        let scene = builtin(name).unwrap();
        for ext in ["glb", "gltf"] {
            let path = dir.0.join(format!("{name}.{ext}"));
            let warnings = export_gltf(&scene, &path).unwrap();
            let loaded = load_gltf(&path).unwrap();
            assert!(loaded.studio.is_none(), "{name}: the lights came back");
            let back = &loaded.scene;
            assert_eq!(back.meshes().len(), scene.meshes().len(), "{name}");
            for (m, (a, b)) in scene.meshes().iter().zip(back.meshes()).enumerate() {
                let positions = scene.world_positions(m as u32);
                let normals = scene.world_normals(m as u32);
                assert_eq!(a.indices, b.indices, "{name}: {}", a.name);
                assert_eq!(positions, b.positions, "{name}: {}", a.name);
                // glTF's v is 1 − v both ways: equal within the rounding of 1 − (1 − v).
                assert_eq!(a.uvs.len(), b.uvs.len(), "{name}: {}", a.name);
                for (ua, ub) in a.uvs.iter().zip(&b.uvs) {
                    assert!(
                        (*ua - *ub).abs().max_element() <= 1e-6,
                        "{name}: {}: {ua} {ub}",
                        a.name
                    );
                }
                for (n, nb) in normals.iter().zip(&b.normals) {
                    assert!(close(*n, *nb), "{name}: {}: {n} {nb}", a.name);
                }
                let (ma, mb) = (
                    &scene.materials()[a.material as usize],
                    &back.materials()[b.material as usize],
                );
                assert_eq!(ma.name, mb.name);
                assert_eq!(ma.emission, mb.emission, "{name}: {}", ma.name);
                // The exact models come back (α through √α and back, within rounding); the others were reported.
                let exact = match (&ma.model, &mb.model) {
                    (
                        MaterialModel::RoughConductor { alpha: x, .. },
                        MaterialModel::RoughConductor { alpha: y, .. },
                    ) => (x - y).abs() <= 1e-6 * x,
                    (
                        MaterialModel::Phong {
                            diffuse: d1,
                            specular: s1,
                            exponent: e1,
                        },
                        MaterialModel::Phong {
                            diffuse: d2,
                            specular: s2,
                            exponent: e2,
                        },
                    ) => close(*d1, *d2) && close(*s1, *s2) && (e1 - e2).abs() <= 1e-3 * e1,
                    (x, y) => x == y,
                };
                assert!(
                    exact
                        || warnings
                            .iter()
                            .any(|w| w.contains(&format!("`{}`", ma.name))),
                    "{name}: {} came back as {:?} from {:?} without a warning",
                    ma.name,
                    mb.model,
                    ma.model
                );
            }
            assert_eq!(
                back.lights().len(),
                scene.lights().len()
                    - warnings
                        .iter()
                        .filter(|w| w.contains("point light has no glTF"))
                        .count(),
                "{name}"
            );
            for (la, lb) in scene.lights().iter().zip(back.lights()) {
                match (la, lb) {
                    (Light::Point(a), Light::Point(b)) => {
                        assert!(close(a.position, b.position) && close(a.intensity, b.intensity))
                    }
                    (Light::Spot(a), Light::Spot(b)) => {
                        assert!(close(a.position, b.position) && close(a.direction, b.direction));
                        assert!(close(a.intensity, b.intensity));
                        assert_eq!(
                            (a.beam_width, a.cutoff_angle),
                            (b.beam_width, b.cutoff_angle)
                        );
                    }
                    (Light::Area(a), Light::Area(b)) => assert_eq!(a.radiance, b.radiance),
                    (a, b) => panic!("{name}: {a:?} came back as {b:?}"),
                }
            }
            let (ca, cb) = (scene.camera(), back.camera());
            assert!(close(ca.position, cb.position), "{name}");
            let (va, vb) = (ca.view_matrix(), cb.view_matrix());
            assert!(va.abs_diff_eq(vb, 1e-4), "{name}: {va} {vb}");
            assert!((ca.fov_y_degrees - cb.fov_y_degrees).abs() < 1e-4);
            assert_eq!((ca.aspect, ca.near), (cb.aspect, cb.near));
        }
    }
}
