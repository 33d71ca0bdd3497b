//! The headless wgpu device: adapter selection (hardware first, then the
//! software one), the adapter's identity for every output, and whether float32
//! targets can be blended (DESIGN.md "Data flow", step 3).

use std::fmt;

use crate::{MprError, Result};

/// Which adapter [`GpuContext::new`] asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AdapterPreference {
    /// A hardware GPU (`PowerPreference::HighPerformance`, not the fallback
    /// adapter); when none exists, the software one.
    #[default]
    Hardware,
    /// Only a software (CPU-type) adapter such as lavapipe or llvmpipe.
    Software,
}

/// The adapter's identity, printed beside every result and benchmark (DESIGN.md "Benchmarks").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterSummary {
    /// The adapter's name, e.g. `llvmpipe (LLVM 15.0.7, 256 bits)`.
    pub name: String,
    /// The graphics API it runs on.
    pub backend: wgpu::Backend,
    /// Discrete, integrated, virtual, CPU or other.
    pub device_type: wgpu::DeviceType,
    /// Driver name and version, as the driver reports them.
    pub driver: String,
}

impl AdapterSummary {
    /// Whether this is a software (CPU) adapter.
    pub fn is_software(&self) -> bool {
        self.device_type == wgpu::DeviceType::Cpu
    }
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({:?}, {:?}",
            self.name, self.backend, self.device_type
        )?;
        if !self.driver.is_empty() {
            write!(f, ", {}", self.driver)?;
        }
        write!(f, ")")
    }
}

/// A headless device and queue with what the passes need to know about them (cloned cheaply: the wgpu handles are shared).
#[derive(Debug, Clone)]
pub struct GpuContext {
    /// The wgpu device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    adapter: wgpu::Adapter,
    summary: AdapterSummary,
    float32_blendable: bool,
    depth_stencil: bool,
    clip_distances: bool,
    timestamps: bool,
    view_layout: wgpu::BindGroupLayout,
}

/// Request options for the hardware-first attempt.
fn hardware_options() -> wgpu::RequestAdapterOptions<'static, 'static> {
    wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    }
}

/// Request options for the software (fallback) adapter.
fn software_options() -> wgpu::RequestAdapterOptions<'static, 'static> {
    wgpu::RequestAdapterOptions {
        force_fallback_adapter: true,
        ..hardware_options()
    }
}

/// A wgpu instance on the backends `WGPU_BACKEND` names, else every compiled one (Vulkan here), and those backends.
fn instance() -> (wgpu::Instance, wgpu::Backends) {
    let backends =
        wgpu::Backends::from_env().unwrap_or_else(wgpu::Instance::enabled_backend_features);
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    (wgpu::Instance::new(desc), backends)
}

/// Picks an adapter per `preference`, ending with any CPU-type adapter the instance enumerates.
fn select_adapter(
    instance: &wgpu::Instance,
    backends: wgpu::Backends,
    preference: AdapterPreference,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<wgpu::Adapter> {
    let attempts: &[(&str, wgpu::RequestAdapterOptions<'_, '_>)] = match preference {
        AdapterPreference::Hardware => &[
            ("a high-performance adapter", hardware_options()),
            ("the fallback adapter", software_options()),
        ],
        AdapterPreference::Software => &[("the fallback adapter", software_options())],
    };
    for (_, options) in attempts {
        let options = wgpu::RequestAdapterOptions {
            compatible_surface: surface,
            ..*options
        };
        if let Ok(adapter) = pollster::block_on(instance.request_adapter(&options)) {
            return Ok(adapter);
        }
    }
    // `force_fallback_adapter` keeps only CPU-type adapters; enumerate in case
    // a backend reports its software driver only through enumeration.
    let adapters = pollster::block_on(instance.enumerate_adapters(backends));
    if let Some(adapter) = adapters.into_iter().find(|a| {
        a.get_info().device_type == wgpu::DeviceType::Cpu
            && surface.is_none_or(|s| a.is_surface_supported(s))
    }) {
        return Ok(adapter);
    }
    let mut tried: Vec<&str> = attempts.iter().map(|(what, _)| *what).collect();
    tried.push("any CPU-type adapter");
    Err(MprError::NoAdapter {
        tried: format!("{} on backends {backends:?}", tried.join(", then ")),
    })
}

impl GpuContext {
    /// Opens a headless device on the adapter `preference` selects; backends
    /// come from `WGPU_BACKEND` when set, else every compiled one (Vulkan here).
    pub fn new(preference: AdapterPreference) -> Result<Self> {
        let (_instance, adapter) = wayland_quiet::run(|| {
            let (instance, backends) = instance();
            let adapter = select_adapter(&instance, backends, preference, None);
            (instance, adapter)
        });
        Self::open(adapter?)
    }

    /// Opens a device on the adapter `preference` selects among those that can present to `window`, and the window's surface (unconfigured).
    pub fn with_surface(
        preference: AdapterPreference,
        window: impl Into<wgpu::SurfaceTarget<'static>>,
    ) -> Result<(Self, wgpu::Surface<'static>)> {
        let (_instance, found) = wayland_quiet::run(|| {
            let (instance, backends) = instance();
            let found = instance
                .create_surface(window)
                .map_err(|e| MprError::Surface(e.to_string()))
                .and_then(|surface| {
                    let adapter = select_adapter(&instance, backends, preference, Some(&surface))?;
                    Ok((adapter, surface))
                });
            (instance, found)
        });
        let (adapter, surface) = found?;
        Ok((Self::open(adapter)?, surface))
    }

    /// Opens the device with the features the passes use where the adapter has them.
    fn open(adapter: wgpu::Adapter) -> Result<Self> {
        let info = adapter.get_info();
        let summary = AdapterSummary {
            name: info.name.clone(),
            backend: info.backend,
            device_type: info.device_type,
            driver: [info.driver.as_str(), info.driver_info.as_str()]
                .iter()
                .filter(|s| !s.is_empty())
                .copied()
                .collect::<Vec<_>>()
                .join(" "),
        };
        let float32_blendable = adapter
            .features()
            .contains(wgpu::Features::FLOAT32_BLENDABLE);
        let depth_stencil = adapter
            .features()
            .contains(wgpu::Features::DEPTH32FLOAT_STENCIL8);
        let mut required_features = wgpu::Features::empty();
        if float32_blendable {
            required_features |= wgpu::Features::FLOAT32_BLENDABLE;
        }
        if depth_stencil {
            required_features |= wgpu::Features::DEPTH32FLOAT_STENCIL8;
        }
        // Per-pass GPU times (crate::pass_timing) where the adapter has them.
        let timestamps =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let timestamps = adapter
            .features()
            .contains(timestamps)
            .then_some(timestamps);
        if let Some(t) = timestamps {
            required_features |= t;
        }
        let clip_distances = adapter.features().contains(wgpu::Features::CLIP_DISTANCES)
            && std::env::var_os("LUSTRE_NO_CLIP_DISTANCES").is_none();
        if clip_distances {
            required_features |= wgpu::Features::CLIP_DISTANCES;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lustre-mpr"),
            required_features,
            required_limits: wgpu::Limits::default().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|source| MprError::RequestDevice {
            adapter: summary.to_string(),
            source,
        })?;
        let view_layout = crate::view::view_layout(&device);
        Ok(Self {
            device,
            queue,
            adapter,
            summary,
            float32_blendable,
            depth_stencil,
            clip_distances,
            timestamps: timestamps.is_some(),
            view_layout,
        })
    }

    /// Whether timestamps can be written between passes (`TIMESTAMP_QUERY_INSIDE_ENCODERS` enabled).
    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    /// The adapter's name, backend, type and driver.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.summary
    }

    /// The underlying wgpu adapter.
    pub fn wgpu_adapter(&self) -> &wgpu::Adapter {
        &self.adapter
    }

    /// Whether `Rgba32Float` render targets can be blended (`FLOAT32_BLENDABLE` enabled on the device).
    pub fn float32_blendable(&self) -> bool {
        self.float32_blendable
    }

    /// Whether accumulation must fall back to 16-bit float targets (no float32 blending).
    pub fn needs_16bit_fallback(&self) -> bool {
        !self.float32_blendable
    }

    /// Whether the depth target carries a stencil; always true since the
    /// specular recursion needs one ([`GpuContext::depth_format`]).
    pub fn has_stencil(&self) -> bool {
        self.depth_format().has_stencil_aspect()
    }

    /// The depth format of every pass: `Depth32FloatStencil8` where the
    /// device has it, else `Depth24PlusStencil8` (every WebGPU device has it).
    pub fn depth_format(&self) -> wgpu::TextureFormat {
        if self.depth_stencil {
            wgpu::TextureFormat::Depth32FloatStencil8
        } else {
            wgpu::TextureFormat::Depth24PlusStencil8
        }
    }

    /// Whether vertex stages write user clip distances (`CLIP_DISTANCES`;
    /// `LUSTRE_NO_CLIP_DISTANCES` set in the environment turns it off, to test
    /// the oblique near plane on such a device).
    pub fn has_clip_distances(&self) -> bool {
        self.clip_distances
    }

    /// How this device clips geometry in front of a specular face ([`crate::view::ClipMethod`]).
    pub fn clip_method(&self) -> crate::view::ClipMethod {
        if self.clip_distances {
            crate::view::ClipMethod::Hardware
        } else {
            crate::view::ClipMethod::ObliqueNearPlane
        }
    }

    /// The layout of group 0 of every scene pass: the view at a dynamic offset ([`crate::view`]).
    pub fn view_layout(&self) -> &wgpu::BindGroupLayout {
        &self.view_layout
    }

    /// A scene pass's WGSL as compiled on this device: with user clip distances
    /// enabled where the device has them ([`crate::shaders::specialise`]).
    pub fn scene_wgsl(&self, source: &str) -> String {
        crate::shaders::specialise(source, self.clip_distances)
    }

    /// The HDR accumulation format: `Rgba32Float` when blendable, `Rgba16Float` otherwise.
    pub fn hdr_format(&self) -> wgpu::TextureFormat {
        if self.float32_blendable {
            wgpu::TextureFormat::Rgba32Float
        } else {
            wgpu::TextureFormat::Rgba16Float
        }
    }

    /// Whether `format` is blendable on this device (from its format features and enabled features).
    pub fn is_blendable(&self, format: wgpu::TextureFormat) -> bool {
        format
            .guaranteed_format_features(self.device.features())
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE)
    }

    /// Waits until every submitted command has finished.
    pub fn wait(&self) -> Result<()> {
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        Ok(())
    }
}

impl GpuContext {
    /// Runs `f` inside validation and out-of-memory error scopes and turns a
    /// captured wgpu error into [`MprError::Wgpu`] naming `what`.
    pub fn checked<T>(&self, what: &'static str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let first = pollster::block_on(validation.pop());
        let second = pollster::block_on(oom.pop());
        match first.or(second) {
            Some(error) => Err(MprError::Wgpu {
                what,
                message: error.to_string(),
            }),
            None => Ok(value),
        }
    }

    /// [`GpuContext::checked`] for a closure that can fail itself: its error comes first, then wgpu's.
    pub fn checked_result<T>(
        &self,
        what: &'static str,
        f: impl FnOnce() -> Result<T>,
    ) -> Result<T> {
        self.checked(what, f)?
    }
}

/// Silences libwayland's complaint about a missing desktop session during
/// adapter enumeration, and nothing else.
///
/// wgpu 30 enables `VK_KHR_wayland_surface` on every Vulkan instance it
/// creates, even without a display handle, and Mesa's implicit
/// `VK_LAYER_MESA_device_select` layer, seeing it, asks the Wayland compositor
/// for the default GPU on each `vkEnumeratePhysicalDevices`: without
/// `XDG_RUNTIME_DIR` (no desktop session: CI, ssh) libwayland prints
/// [`wayland_quiet::NOISE`] to stderr twice. Neither wgpu's instance options
/// nor anything else short of the environment (`NODEVICE_SELECT=1`, which
/// safe Rust cannot set in-process) turns that off, so without a session the
/// enumeration runs with stderr captured in an unlinked temporary file, and
/// every captured line but that one is written back to stderr afterwards.
mod wayland_quiet {
    use std::io::{Read, Seek, Write};

    /// libwayland's message when `XDG_RUNTIME_DIR` is unset or invalid.
    pub const NOISE: &str = "error: XDG_RUNTIME_DIR is invalid or not set in the environment.";

    /// Serialises the captures of concurrent device creations (parallel tests).
    #[cfg(unix)]
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

    /// Runs `f`, filtering [`NOISE`] out of what it writes to stderr when there is no desktop session.
    pub fn run<T>(f: impl FnOnce() -> T) -> T {
        #[cfg(unix)]
        if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
            // Stderr is one per process: one capture at a time, or a second
            // thread would save the first's file as "the original" and
            // leave stderr pointing at it.
            let _one_at_a_time = ONE_AT_A_TIME
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            if let Some(capture) = Capture::start() {
                let value = f();
                capture.finish();
                return value;
            }
        }
        f()
    }

    /// The lines of `captured` to write back: all but [`NOISE`].
    pub fn kept(captured: &str) -> impl Iterator<Item = &str> {
        captured.lines().filter(|line| line.trim_end() != NOISE)
    }

    /// Stderr redirected into a temporary file, restored on drop.
    #[cfg(unix)]
    struct Capture {
        /// The original stderr.
        saved: std::os::fd::OwnedFd,
        /// Where stderr goes meanwhile (already unlinked).
        file: std::fs::File,
    }

    #[cfg(unix)]
    impl Capture {
        /// Redirects stderr, or `None` (leaving it alone) when anything fails.
        fn start() -> Option<Self> {
            use std::os::fd::AsFd;
            let path = std::env::temp_dir().join(format!(
                "lustre-stderr-{}-{:?}",
                std::process::id(),
                std::thread::current().id()
            ));
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .open(&path)
                .ok();
            let _ = std::fs::remove_file(&path);
            let file = file?;
            let _ = std::io::stderr().flush();
            let saved = rustix::io::dup(std::io::stderr().as_fd()).ok()?;
            rustix::stdio::dup2_stderr(file.as_fd()).ok()?;
            Some(Self { saved, file })
        }

        /// Restores stderr and writes back what was captured, less [`NOISE`].
        fn finish(mut self) {
            self.restore();
            let mut captured = String::new();
            if self.file.rewind().is_ok() {
                let _ = self.file.read_to_string(&mut captured);
            }
            for line in kept(&captured) {
                eprintln!("{line}");
            }
        }

        /// Points stderr back at the original.
        fn restore(&self) {
            let _ = std::io::stderr().flush();
            let _ = rustix::stdio::dup2_stderr(&self.saved);
        }
    }

    #[cfg(unix)]
    impl Drop for Capture {
        fn drop(&mut self) {
            self.restore();
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn only_the_wayland_line_is_dropped() {
            let captured = format!("{NOISE}\nMESA: warning: something real\n{NOISE}\n");
            assert_eq!(
                kept(&captured).collect::<Vec<_>>(),
                vec!["MESA: warning: something real"]
            );
        }
    }
}
