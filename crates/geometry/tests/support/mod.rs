//! Shared by the scene tests: meshes by name and the closed-manifold check;
//! and by the glTF tests: a scratch directory and the GLB container.

#![allow(dead_code)]

use std::collections::HashMap;

use glam::Vec3;
use lustre_geometry::{Mesh, Scene, triangle_area};

/// The mesh named `name` of `scene` and its id.
pub fn mesh<'a>(scene: &'a Scene, name: &str) -> (u32, &'a Mesh) {
    let m = scene
        .meshes()
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("{}: no mesh {name}", scene.name));
    (m as u32, &scene.meshes()[m])
}

/// Every directed edge (by exact positions) of `mesh` occurs once and its
/// reverse once: a closed 2-manifold with consistent winding. Returns the
/// signed volume (positive when the faces point out).
pub fn check_closed(mesh: &Mesh) -> f32 {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut directed: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for tri in &mesh.indices {
        for e in 0..3 {
            let a = key(mesh.positions[tri[e] as usize]);
            let b = key(mesh.positions[tri[(e + 1) % 3] as usize]);
            assert_ne!(a, b, "{}: a triangle repeats a position", mesh.name);
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        assert_eq!(count, 1, "{}: edge used {count} times one way", mesh.name);
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "{}: edge {:?} -> {:?} has no opposite twin",
            mesh.name,
            a.map(f32::from_bits),
            b.map(f32::from_bits)
        );
    }
    mesh.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Every triangle has an area and no vanishing altitude.
pub fn check_no_degenerate_triangles(scene: &Scene) {
    for m in scene.meshes() {
        for t in 0..m.indices.len() {
            let [a, b, c] = m.triangle(t);
            let area = triangle_area([a, b, c]);
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            // Area over the longest edge: the smallest altitude / 2.
            assert!(
                area > 1e-7 && area / longest > 1e-5,
                "{}: {} triangle {t} has area {area} and longest edge {longest}",
                scene.name,
                m.name
            );
        }
    }
}

/// Each mesh named in `names` is closed ([`check_closed`]) with a positive volume no larger than its bounding box's.
pub fn check_closed_meshes(scene: &Scene, names: &[&str]) {
    for name in names {
        let (_, m) = mesh(scene, name);
        let volume = check_closed(m);
        let extent = m.bounds().extent();
        assert!(
            volume > 0.0 && volume <= extent.x * extent.y * extent.z,
            "{name}: {volume}"
        );
    }
}

/// A scratch directory removed on drop.
pub struct Dir(pub std::path::PathBuf);

impl Dir {
    pub fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("lustre-geometry-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A GLB container: the JSON chunk padded with spaces and the BIN chunk with zeros (glTF 2.0, section 4.4).
pub fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
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
