//! Typed errors of the GPU pipeline.

use thiserror::Error;

/// Everything that can go wrong in `lustre-mpr`, with the object at fault named.
#[derive(Debug, Error)]
pub enum MprError {
    /// No adapter at all: neither a hardware GPU nor a software (CPU) one.
    #[error(
        "no GPU adapter: install mesa-vulkan-drivers for the software one (lavapipe); tried {tried}"
    )]
    NoAdapter {
        /// What was asked for, in order.
        tried: String,
    },
    /// The window's surface could not be created.
    #[error("cannot create a surface for the window: {0}")]
    Surface(String),
    /// The adapter exists but refused to open a device.
    #[error("adapter `{adapter}` refused a device: {source}")]
    RequestDevice {
        /// The adapter's name and backend.
        adapter: String,
        /// wgpu's reason.
        source: wgpu::RequestDeviceError,
    },
    /// A render target or image of zero or too large a size was requested.
    #[error("{what}: size {width}x{height} is not in 1..={max} per side")]
    InvalidSize {
        /// The target or image at fault.
        what: &'static str,
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// The device's largest 2D texture side.
        max: u32,
    },
    /// A texture format a function cannot handle.
    #[error("{what}: unsupported texture format {format:?}")]
    UnsupportedFormat {
        /// The operation at fault.
        what: &'static str,
        /// The format it was given.
        format: wgpu::TextureFormat,
    },
    /// Pixel data whose length does not match the image size.
    #[error("{what}: {got} pixels given for a {width}x{height} image")]
    PixelCount {
        /// The operation at fault.
        what: &'static str,
        /// Pixels given.
        got: usize,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// A setting outside its valid range.
    #[error("{what}: {message}")]
    InvalidSetting {
        /// The setting at fault.
        what: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A material the GPU passes cannot evaluate.
    #[error("material `{material}`: {message}")]
    UnsupportedMaterial {
        /// The material's name.
        material: String,
        /// Why.
        message: String,
    },
    /// Mapping a readback buffer failed.
    #[error("reading back `{what}` failed: {message}")]
    Readback {
        /// The texture being read.
        what: String,
        /// The cause.
        message: String,
    },
    /// Radiance maps refused (lustre-ibr: settings, reflector, kernel or table).
    #[error("radiance maps: {0}")]
    Ibr(#[from] lustre_ibr::IbrError),
    /// A BRDF lustre-brdf refused to build or tabulate.
    #[error("BRDF: {0}")]
    Brdf(#[from] lustre_brdf::BrdfError),
    /// Waiting for the device failed (device lost or timeout).
    #[error("waiting for the GPU failed: {0}")]
    Poll(#[from] wgpu::PollError),
    /// A wgpu validation or out-of-memory error caught in an error scope.
    #[error("wgpu error in {what}: {message}")]
    Wgpu {
        /// The operation at fault.
        what: &'static str,
        /// wgpu's message.
        message: String,
    },
}

/// Result with [`MprError`].
pub type Result<T, E = MprError> = std::result::Result<T, E>;
