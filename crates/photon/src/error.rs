//! Typed errors of particle tracing, hit-record files and reconstruction.

use std::path::PathBuf;

use lustre_brdf::BrdfError;

/// Result with a [`PhotonError`].
pub type Result<T, E = PhotonError> = std::result::Result<T, E>;

/// Everything that can go wrong in `lustre-photon`; each variant names the file, record, material or option at fault.
#[derive(Debug, thiserror::Error)]
pub enum PhotonError {
    /// A scene material could not become a BRDF.
    #[error("material `{material}`")]
    Brdf {
        /// The material's name.
        material: String,
        /// Why.
        #[source]
        source: BrdfError,
    },
    /// A tracing or reconstruction option is out of range.
    #[error("invalid option `{option}`: {message}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// Two photon maps (or a map and a file) describe different lights.
    #[error("light table mismatch: {0}")]
    LightMismatch(String),
    /// A hit record names a surface, triangle or light that does not exist.
    #[error("hit record {index}: {message}")]
    InvalidRecord {
        /// The record's index in its map.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A hit record cannot be packed into the 21-byte format.
    #[error("hit record {index} cannot be stored in 21 bytes: {message}")]
    Unrepresentable {
        /// The record's index in its map.
        index: usize,
        /// Which field overflows.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start with the photon file magic.
    #[error("{path}: not a Lustre photon file (bad magic)")]
    BadMagic {
        /// The file.
        path: PathBuf,
    },
    /// The file was written by an incompatible version of the format.
    #[error(
        "{path}: photon file version {found} is not supported (this build reads versions 1 to {supported})"
    )]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// The version in the file.
        found: u32,
        /// The newest version this build reads (and the one it writes).
        supported: u32,
    },
    /// The file is shorter than its header says.
    #[error("{path}: truncated: {expected} bytes expected, {found} present")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The length the header implies (or the minimum header length).
        expected: u64,
        /// The file's length.
        found: u64,
    },
    /// The file is longer than its header says.
    #[error("{path}: {found} bytes where the header implies {expected}")]
    TrailingBytes {
        /// The file.
        path: PathBuf,
        /// The length the header implies.
        expected: u64,
        /// The file's length.
        found: u64,
    },
    /// A checksum does not match its data.
    #[error("{path}: {part} checksum mismatch (stored {stored:#010x}, computed {computed:#010x})")]
    Checksum {
        /// The file.
        path: PathBuf,
        /// `header` or `records`.
        part: &'static str,
        /// The stored CRC-32.
        stored: u32,
        /// The CRC-32 of the data read.
        computed: u32,
    },
    /// The header's values are inconsistent (checksum correct but nonsensical counts).
    #[error("{path}: corrupt header: {message}")]
    CorruptHeader {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A record's fields are out of range although the checksum matched.
    #[error("{path}: record {index}: {message}")]
    CorruptRecord {
        /// The file.
        path: PathBuf,
        /// The record's index.
        index: u64,
        /// What is wrong.
        message: String,
    },
    /// The file's surface table does not describe the scene it is used with.
    #[error("{path}: the file's surface table does not match the scene: {message}")]
    SceneMismatch {
        /// The file.
        path: PathBuf,
        /// What differs.
        message: String,
    },
    /// Photon files that cannot be merged or appended to: other scenes, lights, seeds, or overlapping photon ranges.
    #[error("{path}: {message}")]
    Incompatible {
        /// The file at fault.
        path: PathBuf,
        /// What does not match.
        message: String,
    },
}
