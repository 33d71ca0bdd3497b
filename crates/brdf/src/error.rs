//! Typed errors of BRDF construction.

/// Why a [`lustre_geometry::material::MaterialModel`] could not become a BRDF.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BrdfError {
    /// The `Named` model is not one `lustre-brdf` knows (see [`crate::MODEL_NAMES`]).
    #[error("unknown BRDF model `{0}` (known models: {known})", known = crate::MODEL_NAMES.join(", "))]
    UnknownModel(String),
    /// A parameter name that the model does not take (a typo would otherwise be silently ignored).
    #[error("BRDF model `{model}` has no parameter `{param}`")]
    UnknownParameter {
        /// The model's name.
        model: String,
        /// The parameter given.
        param: String,
    },
    /// A parameter the model needs and has no default for.
    #[error("BRDF model `{model}` needs parameter `{param}`")]
    MissingParameter {
        /// The model's name.
        model: String,
        /// The missing parameter.
        param: String,
    },
    /// A parameter with the wrong number of values (one value, or an RGB triple where allowed).
    #[error("BRDF model `{model}`: parameter `{param}` takes {expected} values, got {got}")]
    ParameterArity {
        /// The model's name.
        model: String,
        /// The parameter.
        param: String,
        /// What is accepted, e.g. "1 or 3".
        expected: String,
        /// How many values were given.
        got: usize,
    },
    /// A parameter value outside the range the model allows (negative roughness, reflectance above one, NaN).
    #[error("BRDF model `{model}`: parameter `{param}` = {value} is out of range ({expected})")]
    OutOfRange {
        /// The model's name.
        model: String,
        /// The parameter.
        param: String,
        /// The offending value (one channel for RGB parameters).
        value: f32,
        /// The allowed range, in words.
        expected: String,
    },
    /// An iterative fit (Diefenbach's chi-square fit) stopped without converging.
    #[error("{fit}: no convergence after {iterations} iterations (chi-square {chi_square})")]
    FitDidNotConverge {
        /// What was being fitted.
        fit: String,
        /// Iterations run.
        iterations: usize,
        /// The chi-square reached.
        chi_square: f64,
    },
    /// A tabulated BRDF could not meet the requested error bound within the largest resolution allowed.
    #[error(
        "BRDF table of `{model}`: relative error {achieved} above the bound {requested} at the largest resolution {resolution}"
    )]
    ErrorBoundNotMet {
        /// The tabulated model's name.
        model: String,
        /// The bound asked for.
        requested: f32,
        /// The validation error at the largest resolution tried.
        achieved: f32,
        /// That resolution (nodes per axis).
        resolution: usize,
    },
}

/// Result type of BRDF construction.
pub type Result<T> = std::result::Result<T, BrdfError>;

/// Checks `lo <= v <= hi` (and not NaN) for every channel (the common parameter check of all models).
pub(crate) fn check_range(model: &str, param: &str, v: f32, lo: f32, hi: f32) -> Result<f32> {
    if v.is_nan() || v < lo || v > hi {
        return Err(BrdfError::OutOfRange {
            model: model.into(),
            param: param.into(),
            value: v,
            expected: format!("{lo} to {hi}"),
        });
    }
    Ok(v)
}

/// Checks every channel of an RGB parameter with [`check_range`].
pub(crate) fn check_rgb(
    model: &str,
    param: &str,
    v: glam::Vec3,
    lo: f32,
    hi: f32,
) -> Result<glam::Vec3> {
    for c in v.to_array() {
        check_range(model, param, c, lo, hi)?;
    }
    Ok(v)
}

/// Checks that the sum of two reflectances is at most one per channel (models whose diffuse + specular must conserve energy).
pub(crate) fn check_sum(model: &str, a: glam::Vec3, b: glam::Vec3) -> Result<()> {
    let s = a + b;
    for c in s.to_array() {
        if c > 1.0 + 1e-6 {
            return Err(BrdfError::OutOfRange {
                model: model.into(),
                param: "diffuse + specular".into(),
                value: c,
                expected: "sum at most 1 per channel".into(),
            });
        }
    }
    Ok(())
}
