//! Scene files by their extension: glTF 2.0 (`.gltf`, `.glb`) or OBJ with
//! its MTL libraries (anything else), the one dispatch that `lustre`'s scene
//! argument and `cargo xtask reference` share.

use std::path::Path;

use crate::Result;
use crate::gltf::load_gltf;
use crate::obj::{LoadedScene, load_obj};

/// Whether `path` names a glTF 2.0 file (extension `.gltf` or `.glb`, any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Loads a scene file: [`load_gltf`] for a glTF 2.0 file ([`is_gltf`]), [`load_obj`] otherwise.
pub fn load_scene_file(path: &Path) -> Result<LoadedScene> {
    if is_gltf(path) {
        load_gltf(path)
    } else {
        load_obj(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gltf_by_extension_in_any_case_and_obj_otherwise() {
        for gltf in ["a.gltf", "b.GLB", "dir.obj/c.Gltf"] {
            assert!(is_gltf(Path::new(gltf)), "{gltf}");
        }
        for obj in ["a.obj", "b.OBJ", "gltf", "c.gltf.obj", "d"] {
            assert!(!is_gltf(Path::new(obj)), "{obj}");
        }
    }
}
