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
    /// The glossy vertices' ray lists would hold more rays than the caller allows (memory).
    #[error(
        "the glossy vertices' ray lists would hold about {rays} rays ({gib:.1} GiB), more than the limit of {limit}",
        gib = (*rays as f64) * (crate::glossy::BYTES_PER_STORED_RAY as f64) / f64::from(1u32 << 30)
    )]
    TooManyRays {
        /// Rays the lists would hold (estimated from a sample of the segments when far above the limit).
        rays: u64,
        /// The most allowed.
        limit: u64,
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
