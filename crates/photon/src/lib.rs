//! # lustre-photon
//!
//! The CPU half of Stürzlinger & Bastos, "Interactive Rendering of Globally
//! Illuminated Glossy Scenes" (Rendering Techniques 1997): particle tracing
//! that stores hit records (section 2.1), the compact 21-byte record file
//! (section 3.1), unit-volume kernels and the kernel support of equation 3,
//! and a CPU estimator of equation 2 that the GPU splatting pass of
//! `lustre-mpr` is compared against. No GPU dependency.
//!
//! | paper | item |
//! |---|---|
//! | 2.1 particle tracing, absorption by random number, BRDF sampling | [`trace_photons`], [`PhotonTracer`] (Russian roulette derived in [`trace`]) |
//! | 2.1 photons per light ∝ Φ_i; 5 quasi-Monte Carlo future work | [`allocate_photons`], [`EmissionSampling`] |
//! | 2.1/3.1 hit records, equation 1 `φ = Φ_i/m_i ρ_φ`, incremental refinement | [`HitRecord`], [`PhotonMap`] |
//! | 3.1 position `(u, v)` on the surface | [`SurfaceParams`], [`PlanarFrame`] |
//! | 3.1 21 bytes per record, stored on disk | [`quantise`], [`write_photon_file`], [`append_photon_file`], [`read_photon_file`] |
//! | 2.1 hits stored on disk, incremental refinement, in bounded memory | [`PhotonFileWriter`], [`PhotonFileReader::batches`], [`merge_photon_files`], [`trace::batch_range`], [`PhotonTracer::trace_streamed`] |
//! | 2.2 unit-volume kernel `k`, equation 3 `h = C √(A/n)` | [`Kernel`], [`kernel_support`] |
//! | 2.2 the kernel `k` of Silverman's book (reference 13): the `n^(-1/6)` bandwidth rate | [`kernel_support_silverman`], [`Support::Silverman`] |
//! | 2.2 equation 2 (with `1/h²`, see [`estimator`]) | [`SplatEstimator`] |
//! | 6 future work: the appearance of polygon edges (beyond the paper: the kernel's mass on the surface) | [`KernelMass`], [`Edges`] |
//! | 2.2.1 direct/indirect split | [`BounceSelection`], [`HitRecord::is_indirect`] |
//!
//! ```
//! use lustre_geometry::{builtin, Bvh};
//! use lustre_photon::{trace_photons, EstimatorOptions, NoProgress, SplatEstimator, TraceOptions};
//!
//! let scene = builtin("cornell").unwrap();
//! let bvh = Bvh::build(&scene);
//! let options = TraceOptions { photons: 2_000, ..TraceOptions::default() };
//! let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
//! assert_eq!(map.emitted(), 2_000);
//! let estimator = SplatEstimator::build(&scene, &map, EstimatorOptions::default()).unwrap();
//! let hit = bvh.closest_hit(&scene.camera().primary_ray(glam::Vec2::ZERO)).unwrap();
//! let radiance = estimator.radiance_at_hit(&hit, -scene.camera().primary_ray(glam::Vec2::ZERO).direction);
//! assert!(radiance.is_finite());
//! ```

mod crc32;
pub mod edge;
pub mod emission;
mod error;
pub mod estimator;
pub mod file;
pub mod grid;
mod hit_record;
pub mod kernel;
pub mod parameterisation;
mod progress;
pub mod quantise;
pub mod stream;
pub mod tally;
pub mod trace;

pub use crc32::{Crc32, crc32};
pub use edge::{KernelMass, MassGrid};
pub use emission::{EmissionSampling, allocate_photons, photon_stream};
pub use error::{PhotonError, Result};
pub use estimator::{BounceSelection, Edges, EstimatorOptions, Splat, SplatEstimator, Support};
pub use file::{
    FileHeader, Provenance, append_photon_file, read_photon_file, read_photon_file_for,
    scene_fingerprint, write_photon_file,
};
pub use grid::PointGrid;
pub use hit_record::{HitRecord, LightEmission, PhotonMap};
pub use kernel::{Kernel, kernel_support, kernel_support_silverman, splat_triangle};
pub use parameterisation::{PlanarFrame, SurfaceParam, SurfaceParams, UvMap};
pub use progress::{NoProgress, Progress};
pub use quantise::RECORD_BYTES;
pub use stream::{PhotonBatches, PhotonFileReader, PhotonFileWriter, merge_photon_files};
pub use tally::SplatTally;
pub use trace::{PhotonTracer, TraceOptions, trace_photons};
