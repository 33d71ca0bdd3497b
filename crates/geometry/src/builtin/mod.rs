//! Built-in scenes that need no files (DESIGN.md, "Built-in scenes").

mod cornell;

pub use cornell::{cornell, glosbox};

use crate::{GeometryError, Result, Scene};

/// Names of the built-in scenes.
pub const BUILTIN_SCENES: &[&str] = &["cornell", "glosbox"];

/// The built-in scene with the given name.
pub fn builtin(name: &str) -> Result<Scene> {
    match name {
        "cornell" => Ok(cornell()),
        "glosbox" => Ok(glosbox()),
        _ => Err(GeometryError::UnknownScene {
            name: name.to_owned(),
            known: BUILTIN_SCENES.join(", "),
        }),
    }
}
