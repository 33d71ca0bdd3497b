//! Typed errors of the geometry crate.

use std::path::PathBuf;

/// Where in a text file a problem was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub file: PathBuf,
    /// One-based line number, when the problem belongs to a line.
    pub line: Option<usize>,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}", self.file.display()),
            None => write!(f, "{}", self.file.display()),
        }
    }
}

/// Everything that can go wrong while building, loading or exporting a scene.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A file's content is malformed.
    #[error("{location}: {message}")]
    Parse {
        /// Where.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// A mesh has no triangles left (none in the file, or all degenerate).
    #[error("mesh `{mesh}` is empty{}", .file.as_ref().map(|f| format!(" (in {})", f.display())).unwrap_or_default())]
    EmptyMesh {
        /// The mesh's name.
        mesh: String,
        /// The file it came from, when it came from one.
        file: Option<PathBuf>,
    },
    /// A mesh's arrays disagree (lengths, indices out of range, non-finite values).
    #[error("mesh `{mesh}`: {message}")]
    InvalidMesh {
        /// The mesh's name.
        mesh: String,
        /// What is wrong.
        message: String,
    },
    /// A material parameter is missing or out of range.
    #[error("material `{material}`: {message}")]
    InvalidMaterial {
        /// The material's name.
        material: String,
        /// What is wrong.
        message: String,
    },
    /// A light is invalid (zero area, negative power, non-finite values).
    #[error("light `{light}`: {message}")]
    InvalidLight {
        /// The light's name or index.
        light: String,
        /// What is wrong.
        message: String,
    },
    /// The scene has no light at all, so nothing can be lit.
    #[error("scene `{0}` has no light")]
    NoLight(String),
    /// A name does not match any built-in scene.
    #[error("unknown built-in scene `{name}` (built-in scenes: {known})")]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The names that exist, comma separated.
        known: String,
    },
    /// A scene argument names neither a built-in scene nor an existing file.
    #[error("`{arg}` is neither a built-in scene ({known}) nor an existing file")]
    NotASceneOrFile {
        /// The argument given.
        arg: String,
        /// The built-in scenes, comma separated.
        known: String,
    },
    /// An object id or name does not exist.
    #[error("no object `{0}` in the scene")]
    UnknownObject(String),
    /// An object path is invalid: no keyframes, non-finite values, or times that do not increase.
    #[error("invalid object path: {0}")]
    InvalidPath(String),
    /// Something cannot be expressed in the target format (e.g. a material Mitsuba lacks).
    #[error("cannot export {what}: {why}")]
    Unsupported {
        /// The thing that could not be exported.
        what: String,
        /// Why.
        why: String,
    },
}

/// Result alias of the crate.
pub type Result<T, E = GeometryError> = std::result::Result<T, E>;
