//! Built-in scenes that need no files (DESIGN.md, "Built-in scenes").

mod cornell;
pub mod tree;

pub use cornell::{cornell, glosbox, small_box_path};
pub use tree::tree;

use crate::{GeometryError, Result, Scene};

/// Names of the built-in scenes.
pub const BUILTIN_SCENES: &[&str] = &["cornell", "glosbox", "tree"];

/// The built-in scene with the given name.
pub fn builtin(name: &str) -> Result<Scene> {
    match name {
        "cornell" => Ok(cornell()),
        "glosbox" => Ok(glosbox()),
        "tree" => Ok(tree()),
        _ => Err(GeometryError::UnknownScene {
            name: name.to_owned(),
            known: BUILTIN_SCENES.join(", "),
        }),
    }
}
