//! Typed errors of `lustre-beams`.

/// Everything that can go wrong in `lustre-beams`; each variant names what is at fault.
#[derive(Debug, thiserror::Error)]
pub enum BeamError {
    /// Beams start at point lights (Duvenhage et al. 2010, section 4: "radiated from a point light source"); the input had none.
    #[error(
        "no point light: beams are traced from point lights only ({lights} other lights ignored)"
    )]
    NoPointLight {
        /// How many lights of other kinds there were.
        lights: usize,
    },
    /// A light or scatterer has a non-finite or otherwise invalid value.
    #[error("invalid {what}: {message}")]
    InvalidInput {
        /// Which input (e.g. `scatterer 3`, `light 0`).
        what: String,
        /// What is wrong with it.
        message: String,
    },
    /// A scatterer material's parameters are out of range for the scatter distribution.
    #[error(transparent)]
    Brdf(#[from] lustre_brdf::BrdfError),
}

/// `Result` with a [`BeamError`].
pub type Result<T> = std::result::Result<T, BeamError>;
