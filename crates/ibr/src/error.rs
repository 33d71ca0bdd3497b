//! Typed errors of `lustre-ibr`.

use std::path::PathBuf;

/// Everything that can go wrong in `lustre-ibr`; each variant names what is at fault.
#[derive(Debug, thiserror::Error)]
pub enum IbrError {
    /// A setting or input value is out of its range.
    #[error("invalid {what}: {value} (expected {expected})")]
    OutOfRange {
        /// Which setting or input.
        what: String,
        /// The value given, as text.
        value: String,
        /// What it must be.
        expected: String,
    },
    /// A surface cannot be a reflector (not planar, no area).
    #[error("surface {surface} is not a planar reflector: {reason}")]
    NotAReflector {
        /// The scene's surface id.
        surface: u32,
        /// Why.
        reason: String,
    },
    /// Reading or writing the radiance-map cache failed.
    #[error("radiance-map cache {}: {source}", path.display())]
    Io {
        /// The cache file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The cache file is not one this version reads, or is damaged.
    #[error("radiance-map cache {}: {reason}", path.display())]
    BadCache {
        /// The cache file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
}

/// `Result` with an [`IbrError`].
pub type Result<T> = std::result::Result<T, IbrError>;

/// An [`IbrError::OutOfRange`] for `what`.
pub(crate) fn out_of_range(what: &str, value: impl std::fmt::Display, expected: &str) -> IbrError {
    IbrError::OutOfRange {
        what: what.to_owned(),
        value: value.to_string(),
        expected: expected.to_owned(),
    }
}
