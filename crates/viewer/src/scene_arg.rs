//! Scene arguments: a built-in name or a path to an OBJ or glTF 2.0 (`.gltf`, `.glb`) file.

use lustre_geometry::GeometryError;
use lustre_geometry::obj::LoadedScene;

/// Loads a built-in scene by name, or an OBJ or glTF file by path (by its extension: `.gltf` and `.glb` are glTF, anything else OBJ; [`lustre_geometry::load_scene_arg`]); a file that fails to load is named in the error.
pub fn load(arg: &str) -> anyhow::Result<LoadedScene> {
    lustre_geometry::load_scene_arg(arg).map_err(|e| match e {
        GeometryError::NotASceneOrFile { .. } => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(format!("cannot load `{arg}`")),
    })
}
