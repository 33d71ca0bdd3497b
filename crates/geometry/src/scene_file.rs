//! Scene files by their extension: glTF 2.0 (`.gltf`, `.glb`) or OBJ with
//! its MTL libraries (anything else), and scene arguments (a built-in name or
//! such a file): the one dispatch that `lustre`'s scene argument and `cargo
//! xtask reference` share.

use std::path::Path;

use crate::builtin::{BUILTIN_SCENES, builtin};
use crate::gltf::load_gltf;
use crate::obj::{LoadedScene, load_obj};
use crate::{GeometryError, Result};

/// Loads the scene an argument names: a built-in scene by its name, else a scene file by its path ([`load_scene_file`]). Fails with [`GeometryError::NotASceneOrFile`] when the argument is neither a built-in name nor an existing path, and as the loader fails on a file.
pub fn load_scene_arg(arg: &str) -> Result<LoadedScene> {
    if BUILTIN_SCENES.contains(&arg) {
        return Ok(LoadedScene {
            scene: builtin(arg)?,
            degenerate_triangles_dropped: 0,
            warnings: Vec::new(),
            studio: None,
        });
    }
    let path = Path::new(arg);
    if !path.exists() {
        return Err(GeometryError::NotASceneOrFile {
            arg: arg.to_owned(),
            known: BUILTIN_SCENES.join(", "),
        });
    }
    load_scene_file(path)
}

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

    #[test]
    fn a_scene_argument_is_a_builtin_name_or_an_existing_file() {
        let loaded = load_scene_arg("cornell").unwrap();
        assert_eq!(loaded.scene.name, builtin("cornell").unwrap().name);
        assert!(loaded.studio.is_none() && loaded.warnings.is_empty());
        let error = load_scene_arg("no-such-scene.obj").unwrap_err();
        assert!(
            matches!(&error, GeometryError::NotASceneOrFile { arg, known }
                if arg == "no-such-scene.obj" && known.starts_with("cornell, ")),
            "{error}"
        );
    }
}
