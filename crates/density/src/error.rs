//! Typed errors of `lustre-density`.

use lustre_photon::PhotonError;

/// Everything that can go wrong in `lustre-density`; each variant names the option or object at fault.
#[derive(Debug, thiserror::Error)]
pub enum DensityError {
    /// An option is out of range.
    #[error("invalid option `{option}`: {message}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A scene change was refused (e.g. a non-finite object transform).
    #[error(transparent)]
    Geometry(#[from] lustre_geometry::GeometryError),
    /// A material has no valid BRDF, or another particle-tracing failure.
    #[error(transparent)]
    Photon(#[from] PhotonError),
}

/// `Result` with a [`DensityError`].
pub type Result<T> = std::result::Result<T, DensityError>;
