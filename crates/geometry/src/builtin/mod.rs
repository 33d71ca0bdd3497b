//! Built-in scenes that need no files (DESIGN.md, "Built-in scenes").

pub mod bathroom;
pub mod cardioid;
mod cornell;
pub mod house;
pub mod mirrors;
pub(crate) mod parts;
pub mod pool;
pub mod pyramid;
pub mod stained_glass;
pub mod tree;

pub use bathroom::bathroom;
pub use cardioid::cardioid;
pub use cornell::{cornell, glosbox, small_box_path};
pub use house::{house, house_path};
pub use mirrors::mirrors;
pub use pool::{pool, pool_at};
pub use pyramid::pyramid;
pub use stained_glass::{stained_glass, stained_glass_with};
pub use tree::tree;

use crate::{GeometryError, Result, Scene};

/// Names of the built-in scenes.
pub const BUILTIN_SCENES: &[&str] = &[
    "cornell",
    "glosbox",
    "tree",
    "mirrors",
    "bathroom",
    "cardioid",
    "pool",
    "stained-glass",
    "pyramid",
    "house",
];

/// The built-in scene with the given name.
pub fn builtin(name: &str) -> Result<Scene> {
    match name {
        "cornell" => Ok(cornell()),
        "glosbox" => Ok(glosbox()),
        "tree" => Ok(tree()),
        "mirrors" => Ok(mirrors()),
        "bathroom" => Ok(bathroom()),
        "cardioid" => Ok(cardioid()),
        "pool" => Ok(pool()),
        "stained-glass" => Ok(stained_glass()),
        "pyramid" => Ok(pyramid()),
        "house" => Ok(house()),
        _ => Err(GeometryError::UnknownScene {
            name: name.to_owned(),
            known: BUILTIN_SCENES.join(", "),
        }),
    }
}
