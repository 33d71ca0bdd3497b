//! Built-in scenes that need no files (DESIGN.md, "Built-in scenes").

pub mod bathroom;
mod cornell;
pub mod mirrors;
mod parts;
pub mod tree;

pub use bathroom::bathroom;
pub use cornell::{cornell, glosbox, small_box_path};
pub use mirrors::mirrors;
pub use tree::tree;

use crate::{GeometryError, Result, Scene};

/// Names of the built-in scenes.
pub const BUILTIN_SCENES: &[&str] = &["cornell", "glosbox", "tree", "mirrors", "bathroom"];

/// The built-in scene with the given name.
pub fn builtin(name: &str) -> Result<Scene> {
    match name {
        "cornell" => Ok(cornell()),
        "glosbox" => Ok(glosbox()),
        "tree" => Ok(tree()),
        "mirrors" => Ok(mirrors()),
        "bathroom" => Ok(bathroom()),
        _ => Err(GeometryError::UnknownScene {
            name: name.to_owned(),
            known: BUILTIN_SCENES.join(", "),
        }),
    }
}
