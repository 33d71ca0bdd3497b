//! Scene arguments: a built-in name or a path to an OBJ or glTF 2.0 (`.gltf`, `.glb`) file.

use std::path::Path;

use anyhow::{Context, bail};
use lustre_geometry::builtin::BUILTIN_SCENES;
use lustre_geometry::obj::LoadedScene;

/// Loads a built-in scene by name, or an OBJ or glTF file by path (by its extension: `.gltf` and `.glb` are glTF, anything else OBJ).
pub fn load(arg: &str) -> anyhow::Result<LoadedScene> {
    if BUILTIN_SCENES.contains(&arg) {
        return Ok(LoadedScene {
            scene: lustre_geometry::builtin(arg)?,
            degenerate_triangles_dropped: 0,
            warnings: Vec::new(),
            studio: None,
        });
    }
    let path = Path::new(arg);
    if !path.exists() {
        bail!(
            "`{arg}` is neither a built-in scene ({}) nor an existing file",
            BUILTIN_SCENES.join(", ")
        );
    }
    lustre_geometry::load_scene_file(path).with_context(|| format!("cannot load `{arg}`"))
}
