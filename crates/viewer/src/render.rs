//! `lustre render`: a scene rendered headless by one technique into an EXR
//! (linear) or PNG (sRGB) file, with a JSON sidecar of the settings, the
//! adapter and the time of each phase (DESIGN.md "Data flow", step 4).
//!
//! Techniques (Stürzlinger & Bastos 1997):
//! - `splat`: section 2.2, every photon hit splatted with the BRDF towards the
//!   viewer; diffuse planar surfaces from textures precomputed once from the
//!   same estimate (section 2.2.1's last paragraph; `--diffuse splat` splats
//!   them too).
//! - `splat-direct`: section 2.2.1, the optimised method: direct light from
//!   point lights with shadow maps and per-pixel BRDF, diffuse planar surfaces
//!   from textures precomputed once, and the splats of photons with more than
//!   one bounce on the others. With `--light-samples 1` small area lights
//!   become cosine point lights of equal power in both phases, as in the
//!   paper's section 3; with `K > 1` the direct light comes from `K` jittered
//!   point lights over each area light (Diefenbach & Badler 1997, section
//!   4.4) and the photons from the area light itself.
//!
//! - `mpr` (Diefenbach & Badler 1997): `splat-direct`'s light with the
//!   planar mirrors' specular images: each mirror face masked in the stencil
//!   and the scene drawn again from its virtual camera, recursively to
//!   `--spec-depth` (sections 3, 7.1, 7.3); with `--glossy-images N` the
//!   planar glossy faces too, each from N mirror views sheared about its
//!   normal and averaged (section 3, "glossy marble"), their splats dropped.
//!
//! - `ibr` (Bastos et al. 1999): `splat-direct`'s light with every planar
//!   glossy surface drawn as `k_d D + k_s (M * K) R` from radiance maps
//!   captured from the frame's own lighting (`lustre_mpr::ibr`), its splats
//!   dropped.
//!
//! - `composed`: every technique in one frame,
//!   `L = direct + k_d D + k_s (M * K) R + caustics`, each term from its
//!   crate and each switchable (`--terms`, `--term-images`): direct light under shadow volumes, the
//!   Lambertian lobes from the diffuse textures, planar glossy reflectors
//!   from glossy images, radiance maps or splats (`--reflectors`), mirrors
//!   and glass as specular images, caustics as beams, virtual lights or
//!   splats (`--caustics`), and the splats of the other photons.
//!
//! Every technique's frame is antialiased by `--aa N` jittered accumulation
//! (Diefenbach & Badler 1997, section 7).
//!
//! Techniques (García Hernández, Ureña & Lastra 2003, see [`crate::render_density`]):
//! per-vertex radiance `ρ/π E` of a density estimator (section 1.2) on the
//! scene subdivided to `--mesh-edge`, drawn with Gouraud interpolation
//! (section 2.4) beside the emitters' own radiance:
//! - `detp`: Density Estimation on the Tangent Plane, disc radius `--radius`.
//! - `impact`: Impact Count.
//! - `photonmap`: Photon Maps, `--k` nearest impacts over the part of their
//!   disc on the vertex's surface.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::ValueEnum;
use lustre_beams::{BeamInput, BeamSet, BuildOptions, GlossyVolume, SplitPoint};
use lustre_geometry::camera_path::CameraPath;
use lustre_geometry::obj::Studio;
use lustre_geometry::{Bvh, Camera, Scene};
use lustre_ibr::{SamplingSettings, SelectionRule};
use lustre_image::{Image, Precision};
use lustre_mpr::frame::SplatInputs;
use lustre_mpr::ibr::{
    IbrSettings, KernelSizing, Modulation, ReflectedResolution, ReflectedSource,
};
use lustre_mpr::light_group::GlossyLights;
use lustre_mpr::passes::beams::Traversal;
use lustre_mpr::passes::diffuse_texture::{DiffuseAtlas, DiffuseTextureOptions};
use lustre_mpr::passes::direct::DirectLights;
use lustre_mpr::passes::glossy_image::{Fog, GlossySettings, ShearModel};
use lustre_mpr::passes::shadowed_direct::VolumeJitter;
use lustre_mpr::passes::splat::SplatBuffers;
use lustre_mpr::passes::splat_lowres::{AUTO_QUANTILE, radius_quantile};
use lustre_mpr::projective_texture::{
    DEFAULT_TEXTURE_SIZE, MAX_TEXTURE_SIZE, PaneLight, texture_bytes,
};
use lustre_mpr::virtual_light::{MAX_SHADOW_DEPTH, SpecularShadows, equation_7};
use lustre_mpr::{AdapterPreference, FrameInputs, GpuContext};
use lustre_photon::{
    BounceSelection, Edges, EmissionSampling, EstimatorOptions, Kernel, SplatEstimator, Support,
    TraceOptions, trace_photons,
};
use serde_json::json;

use crate::gpu_frame::{Components, GpuFrame, Lighting, resolve_resolution};
use crate::render_density::{
    DEFAULT_PHOTONMAP_K, DensityLengths, DensitySettings, DetpAcceleration, Estimator,
    GlossyEstimate, PreTestArg, check_lengths, vertex_lit_scene, vertex_radiance,
};
use crate::render_frames::{frame_path, median};
use crate::render_stream::{LeftOut, StreamedPhotons};
use crate::scene_arg;
use crate::trace::{PhotonBar, emission_of};

/// Rendering technique.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Technique {
    /// Photon splatting of every hit (section 2.2).
    Splat,
    /// Direct light by shadow maps plus splats of indirect photons (section 2.2.1).
    SplatDirect,
    /// Per-vertex Density Estimation on the Tangent Plane, Gouraud-shaded (García et al. 2003).
    Detp,
    /// Per-vertex Impact Count, Gouraud-shaded (García et al. 2003).
    Impact,
    /// Per-vertex Photon Maps, Gouraud-shaded (García et al. 2003).
    Photonmap,
    /// Multi-pass pipeline rendering (Diefenbach & Badler 1997): `splat-direct`'s
    /// light with the mirror faces' stencilled specular images to `--spec-depth`.
    Mpr,
    /// `splat-direct`'s light with each planar glossy reflector drawn from
    /// radiance maps (Bastos et al. 1999): `k_d D + k_s (M * K) R`, the maps
    /// captured from the frame's own lighting, in place of its splats.
    Ibr,
    /// `mpr` with the light that point lights send through mirrors, rough
    /// conductors, water and glass panes onto the next surface drawn as
    /// specular and glossy polygon beams (Duvenhage et al. 2010), in place of
    /// those photons' splats.
    Beams,
    /// Every technique in one frame, `L = direct + k_d D + k_s (M * K) R +
    /// caustics`, each term from its crate: direct light under shadow
    /// volumes (`--shadows`), the Lambertian lobes from diffuse textures
    /// (`--diffuse`), planar glossy reflectors from glossy images or
    /// radiance maps (`--reflectors`), mirrors and glass as stencilled
    /// specular images,
    /// the light point lights send through mirrors and glass as beams
    /// (`--caustics`), and the splats of the other photons on every other
    /// surface.
    Composed,
}

impl Technique {
    /// Whether the technique draws direct light from point lights (section 2.2.1) and splats only the indirect photons.
    pub fn direct_light(self) -> bool {
        matches!(
            self,
            Self::SplatDirect | Self::Mpr | Self::Beams | Self::Ibr | Self::Composed
        )
    }

    /// Whether the technique draws the multi-pass pipeline's frame (Diefenbach & Badler 1997): specular images, shadow volumes, virtual lights.
    pub fn multipass(self) -> bool {
        matches!(self, Self::Mpr | Self::Beams | Self::Composed)
    }

    /// Whether the technique lights mesh vertices by a density estimator (García et al.).
    pub fn per_vertex(self) -> bool {
        matches!(self, Self::Detp | Self::Impact | Self::Photonmap)
    }

    /// The density estimator of a per-vertex technique, `None` for the splatting ones.
    fn estimator(self, radius: f32, k: usize) -> Option<Estimator> {
        match self {
            Self::Splat
            | Self::SplatDirect
            | Self::Mpr
            | Self::Beams
            | Self::Ibr
            | Self::Composed => None,
            Self::Detp => Some(Estimator::Detp { radius }),
            Self::Impact => Some(Estimator::ImpactCount),
            Self::Photonmap => Some(Estimator::PhotonMaps { k }),
        }
    }
}

/// How `--technique composed` draws the glossy lobes of planar glossy reflectors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReflectorsArg {
    /// Radiance maps: `k_s (M * K) R` (Bastos et al. 1999), as `--technique ibr`.
    Maps,
    /// Glossy images: sheared mirror images averaged (Diefenbach & Badler 1997, section 3), as `--technique mpr`.
    Images,
    /// Splats of the photons (Stürzlinger & Bastos 1997, section 2.2), as `--technique splat-direct`.
    Splats,
}

/// How `--technique composed` draws the light point lights send through mirrors and glass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CausticsArg {
    /// Specular and glossy polygon beams (Duvenhage et al. 2010), as `--technique beams`.
    Beams,
    /// Virtual lights under light volumes (Diefenbach & Badler 1997, section 4.2), as `--technique mpr`.
    VirtualLights,
    /// Splats of the photons (Stürzlinger & Bastos 1997, section 2.2).
    Splats,
}

/// The additive terms of a frame, as `--terms` and `--term-images` name them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TermArg {
    /// The emitters' own radiance, with the specular recursion's constant
    /// stand-ins (the limit faces' radiance, the glossy images' fog radiance).
    Emission,
    /// Direct light from point lights under shadow maps or volumes.
    Direct,
    /// The Lambertian lobes from the diffuse textures (`k_d D`).
    Diffuse,
    /// The splats of the photon hits and the radiance maps' `k_s (M * K) R`.
    Glossy,
    /// The beams.
    Caustics,
}

impl TermArg {
    /// Every term, in the order term images are written (the declaration order).
    pub fn all() -> &'static [TermArg] {
        TermArg::value_variants()
    }

    /// The term's name in file names and the sidecar: the name `--terms` takes.
    pub fn name(self) -> String {
        self.to_possible_value()
            .map_or_else(|| format!("{self:?}"), |v| v.get_name().to_owned())
    }
}

/// How `--technique ibr` chooses its radiance maps (Bastos et al. 1999, section 8.1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IbrSelectionArg {
    /// Least angle between the mirrored eye's and the camera's direction to the element.
    Angle,
    /// Least distance between the camera and the mirrored eye.
    Distance,
}

/// How `--technique ibr` sizes its kernel (Bastos et al. 1999, sections 8.2.1 and 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IbrKernelArg {
    /// Each pixel's kernel from its own depth.
    Depth,
    /// One kernel per reflector from the mean depth (the paper's).
    Invariant,
}

/// How `--technique ibr` tabulates R (Bastos et al. 1999, section 8.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IbrModulationArg {
    /// The glossy lobe's directional albedo over k_s.
    Albedo,
    /// Equation 4's F/(π cos² θ).
    Paper,
}

/// Where `--technique ibr` takes the reflected image M from (Bastos et al. 1999, section 9's comparison).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IbrReflectedArg {
    /// The selected radiance maps reprojected (the paper's technique).
    Maps,
    /// The frame drawn again from the mirrored view, no maps captured.
    Geometry,
}

/// The resolution of `--technique ibr`'s reflected images (Bastos et al. 1999, section 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IbrResolutionArg {
    /// Chosen from each reflector's glossiness.
    Glossiness,
    /// The frame's.
    Frame,
}

/// The radiance maps' settings of `--technique ibr`.
pub fn ibr_settings(args: &RenderArgs) -> IbrSettings {
    IbrSettings {
        sampling: SamplingSettings {
            planar_resolution: args.ibr_elements,
            arc_step_degrees: args.ibr_arc_step,
            map_resolution: (args.ibr_map_size, args.ibr_map_size),
            ..SamplingSettings::default()
        },
        maps_per_hemisphere: args.ibr_maps,
        bounces: args.ibr_bounces,
        kernel: match args.ibr_kernel {
            IbrKernelArg::Depth => KernelSizing::ByDepth,
            IbrKernelArg::Invariant => KernelSizing::SpaceInvariant,
        },
        selection: match args.ibr_selection {
            IbrSelectionArg::Angle => SelectionRule::MinimalAngle,
            IbrSelectionArg::Distance => SelectionRule::Distance,
        },
        modulation: match args.ibr_modulation {
            IbrModulationArg::Albedo => Modulation::Albedo,
            IbrModulationArg::Paper => Modulation::Paper,
        },
        resolution: match args.ibr_resolution {
            IbrResolutionArg::Glossiness => ReflectedResolution::FromGlossiness,
            IbrResolutionArg::Frame => ReflectedResolution::Frame,
        },
        reflected: match args.ibr_reflected {
            IbrReflectedArg::Maps => ReflectedSource::RadianceMaps,
            IbrReflectedArg::Geometry => ReflectedSource::Geometry,
        },
        ..IbrSettings::default()
    }
}

/// Checks the radiance maps' settings (`--technique ibr`, `composed`) before any work.
fn check_ibr(args: &RenderArgs) -> anyhow::Result<()> {
    if args.ibr_maps == 0 {
        bail!("--ibr-maps 0: at least one radiance map per hemisphere is reprojected");
    }
    if args.diffuse != DiffuseArg::Texture {
        bail!(
            "radiance maps (--technique ibr, composed) need --diffuse texture: the reflectors' \
             Lambertian lobes come from the diffuse textures (their splats are dropped)"
        );
    }
    if args.ibr_bounces == 0 {
        bail!("--ibr-bounces 0: at least one capture pass is needed");
    }
    if let Some(cache) = &args.ibr_cache {
        if args.ibr_reflected == IbrReflectedArg::Geometry {
            bail!(
                "--ibr-cache with --ibr-reflected geometry: geometry-based reflections capture no maps to cache"
            );
        }
        if cache.is_dir() {
            bail!(
                "--ibr-cache {}: is a directory, not a file",
                cache.display()
            );
        }
        check_directory(cache, "--ibr-cache")?;
    }
    ibr_settings(args)
        .sampling
        .validate()
        .context("radiance map sampling (--ibr-elements, --ibr-arc-step, --ibr-map-size)")?;
    Ok(())
}

/// How fragments find their beams (Duvenhage et al. 2010, sections 4.3, 5.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BeamTraversalArg {
    /// Every beam for every fragment.
    Linear,
    /// The beams whose boxes in the beam hierarchy hold the fragment.
    Hierarchy,
}

impl From<BeamTraversalArg> for Traversal {
    fn from(t: BeamTraversalArg) -> Self {
        match t {
            BeamTraversalArg::Linear => Traversal::Linear,
            BeamTraversalArg::Hierarchy => Traversal::Hierarchy,
        }
    }
}

/// The split point of a glossy beam's domain (Duvenhage et al. 2010, figure 12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SplitPointArg {
    /// The paper's: re-scattered at the flux-plane parameter (steps at the beam's edges).
    Paper,
    /// Re-scattered from the edge point whose ray meets the split point (continuous).
    Rescattered,
    /// On the straight edge of the 2D domain (continuous, cheapest).
    Domain,
}

impl From<SplitPointArg> for SplitPoint {
    fn from(s: SplitPointArg) -> Self {
        match s {
            SplitPointArg::Paper => SplitPoint::Paper,
            SplitPointArg::Rescattered => SplitPoint::Rescattered,
            SplitPointArg::Domain => SplitPoint::Domain,
        }
    }
}

/// How a glossy beam's volume is found (Duvenhage et al. 2010, section 4.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GlossyVolumeArg {
    /// The paper's planar facets, clamped to one.
    Facets,
    /// The Gaussian integrated over the domain.
    Integrated,
}

impl From<GlossyVolumeArg> for GlossyVolume {
    fn from(v: GlossyVolumeArg) -> Self {
        match v {
            GlossyVolumeArg::Facets => GlossyVolume::Facets,
            GlossyVolumeArg::Integrated => GlossyVolume::Integrated,
        }
    }
}

/// How the direct light's shadows are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShadowArg {
    /// Silhouette shadow volumes in the stencil (Diefenbach & Badler 1997, section 4.1).
    Volumes,
    /// Cube shadow maps (Stürzlinger & Bastos 1997, section 2.2.1).
    Maps,
}

/// How shadow volumes follow the jittered lights of an area light (Diefenbach & Badler 1997, section 4.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VolumeJitterArg {
    /// `stored` where the stored volumes take at most [`crate::gpu_frame::STORED_VOLUME_BUDGET`] bytes, else `pivot`.
    Auto,
    /// The jittered lights share the volumes of the area light's centre; only their far vertices move (figure 7's jitter approximation).
    Pivot,
    /// Volumes built and stored for every jittered position the accumulation samples draw; each light shadowed exactly.
    Stored,
}

/// Which shadows of virtual lights are drawn (Diefenbach & Badler 1997, table 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpecShadowsArg {
    /// Every stretch of every light path casts shadows (table 2 (a)).
    All,
    /// Shadows that pass two or more specular faces are left out (table 2 (b)).
    OneBounce,
    /// No shadows of virtual lights, light volumes only (table 2 (c)).
    Off,
}

impl SpecShadowsArg {
    pub fn setting(self) -> SpecularShadows {
        match self {
            Self::All => SpecularShadows::All,
            Self::OneBounce => SpecularShadows::OneBounce,
            Self::Off => SpecularShadows::Off,
        }
    }
}

/// How light through stained-glass windows is drawn (Diefenbach & Badler 1997, section 4.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PaneLightArg {
    /// Coplanar panes as one light volume modulated by a projective texture of the window.
    Projective,
    /// One light volume per pane.
    PerPane,
    /// Not by virtual lights: left to the photon splats.
    Off,
}

/// Restriction of splats to their visible surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RestrictionArg {
    /// Compare with the depth pre-pass's surface id, one draw for all splats.
    SurfaceId,
    /// Per-surface stencil masks, as in the paper.
    Stencil,
}

/// Kernel texture filtering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FilterArg {
    /// Read the kernel at each pixel centre (the estimator exactly).
    Centre,
    /// Mip-mapped, anisotropic: the kernel averaged over each pixel (section 3.2).
    Mip,
}

/// The resolution the camera view's splats are accumulated at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SplatResolutionArg {
    /// The coarsest of eighth, quarter, half and full at which 95 % of the splats still span at least 2 low-resolution pixels in radius.
    Auto,
    /// Every splat at the frame's resolution (the paper's pass).
    Full,
    /// Half the width and height, upsampled along surface ids and depth.
    Half,
    /// A quarter of the width and height, upsampled along surface ids and depth.
    Quarter,
    /// An eighth of the width and height, upsampled along surface ids and depth.
    Eighth,
}

/// Reconstruction kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KernelArg {
    /// Silverman's second-order kernel (the paper's example).
    Silverman,
    /// Truncated Gaussian.
    Gaussian,
}

/// How each surface's kernel support `h` is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SupportArg {
    /// Equation 3, `h = C √(A/n)` (`--kernel-c`) on every surface: a fixed count of photons under each kernel.
    Equation3,
    /// Silverman's rate `h = c √A n^(-1/6)` (`--support-c`) on every surface.
    Silverman,
    /// Equation 3 on diffuse surfaces, Silverman's rate on glossy ones.
    GlossySilverman,
}

/// How the splat estimate treats the edges of planar surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EdgesArg {
    /// Kernels cut at the polygon's edges, as in the paper (dark rims of width h along wall joints and box edges).
    Truncated,
    /// The estimate divided by the kernel's mass on the surface (the paper's future work on polygon edges).
    Normalised,
}

impl From<EdgesArg> for Edges {
    fn from(arg: EdgesArg) -> Self {
        match arg {
            EdgesArg::Truncated => Edges::Truncated,
            EdgesArg::Normalised => Edges::Normalised,
        }
    }
}

/// Photon emission sampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EmissionArg {
    /// Pseudo-random (PCG32).
    Random,
    /// Halton sequence.
    Halton,
    /// Owen-scrambled Sobol' sequence.
    Sobol,
}

/// How the Lambertian part of planar surfaces receives its photons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DiffuseArg {
    /// Splatted like every other surface.
    Splat,
    /// Purely Lambertian surfaces precomputed once into textures, view independent (section 2.2.1); the others splatted whole.
    DiffuseSurfaces,
    /// The Lambertian lobes of every planar surface precomputed into textures (equation 3's support), the splats of mixed surfaces carrying only their other lobes.
    Texture,
}

/// How glossy images draw their shears (Diefenbach & Badler 1997, section 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GlossyShearArg {
    /// Isotropic, twice the facet slope, equal weights (the paper's constant shear).
    Isotropic,
    /// The microfacet reflection at the face's centroid, weighted.
    Microfacet,
}

/// Which jittered lights the sheared views of a glossy image draw (`lustre_mpr::light_group`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GlossyLightsArg {
    /// Every light in every sheared view (the paper's loop as written).
    All,
    /// One group of the lights per sheared view, paired with its shear and
    /// weighted by the group count (the accumulation buffer jittering both at once).
    Paired,
}

/// Glossy lobe model on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GlossyArg {
    /// Each material's own BRDF.
    Exact,
    /// Diefenbach's fitted Phong for Beckmann and Ward lobes.
    FittedPhong,
}

/// Options of `lustre render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    /// A built-in scene (cornell, glosbox, tree, mirrors, bathroom, cardioid, pool, stained-glass, pyramid, house), or an OBJ or glTF 2.0 file (`.gltf`, `.glb`).
    pub scene: String,
    /// Rendering technique.
    #[arg(long, value_enum, default_value_t = Technique::Composed)]
    pub technique: Technique,
    /// Photons to emit over all lights.
    #[arg(long, default_value_t = 1_000_000)]
    pub photons: u64,
    /// Read the photons from this file (`lustre trace`) in batches instead of tracing them: memory stays bounded by one batch whatever the file's size (splatting techniques).
    #[arg(long, conflicts_with_all = ["photons", "seed", "emission"])]
    pub photons_file: Option<PathBuf>,
    /// Hit records per batch with --photons-file: memory grows by about 0.7 KB per record of a batch (measured on the software driver: 0.99 GB peak at 1,000,000).
    #[arg(long, default_value_t = 1_000_000, requires = "photons_file")]
    pub batch_records: usize,
    /// The constant C of the kernel support h = C sqrt(A/n) (equation 3).
    #[arg(long, default_value_t = DEFAULT_KERNEL_C, allow_negative_numbers = true)]
    pub kernel_c: f32,
    /// Reconstruction kernel.
    #[arg(long, value_enum, default_value_t = KernelArg::Silverman)]
    pub kernel: KernelArg,
    /// How each surface's kernel support is chosen: equation 3, Silverman's n^(-1/6) rate, or equation 3 on diffuse and Silverman's rate on glossy surfaces.
    #[arg(long, value_enum, default_value_t = SupportArg::GlossySilverman)]
    pub support: SupportArg,
    /// The constant c of Silverman's rate h = c sqrt(A) n^(-1/6).
    #[arg(long, default_value_t = DEFAULT_SUPPORT_C, allow_negative_numbers = true)]
    pub support_c: f32,
    /// Splat estimates at polygon edges: kernels cut off as in the paper, or normalised by the kernel's mass on the surface.
    #[arg(long, value_enum, default_value_t = EdgesArg::Normalised)]
    pub edges: EdgesArg,
    /// Image width and height in pixels, `WxH`.
    #[arg(long, default_value = "640x480", value_parser = crate::parse_size)]
    pub size: (u32, u32),
    /// Seed of the photon tracer.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output file: `.exr` (linear float) or `.png` (sRGB); a `.json` sidecar is written beside it.
    #[arg(long, default_value = "render.png")]
    pub out: PathBuf,
    /// How splats are limited to the visible part of their surface.
    #[arg(long, value_enum, default_value_t = RestrictionArg::SurfaceId)]
    pub restriction: RestrictionArg,
    /// How the kernel texture is read.
    #[arg(long, value_enum, default_value_t = FilterArg::Centre)]
    pub filter: FilterArg,
    /// The resolution the camera view's splats are drawn at: below full, the
    /// splats (restricted by surface ids) fill a target 2, 4 or 8 times
    /// smaller per axis, which is then added at full resolution by a joint
    /// bilateral upsampling that never blends across surface ids (the splat
    /// pass is fill-bound: glosbox's default 640x480 frame took 4.5 s at an
    /// eighth against 32 s at full on the software driver, at the same
    /// error). `auto` picks from the splats' projected kernel size; surfaces
    /// thinner than the factor in pixels may get no splat light. Views
    /// through mirrors always splat at full resolution.
    #[arg(long, value_enum, default_value_t = SplatResolutionArg::Auto)]
    pub splat_resolution: SplatResolutionArg,
    /// Photon emission sampling.
    #[arg(long, value_enum, default_value_t = EmissionArg::Sobol)]
    pub emission: EmissionArg,
    /// The Lambertian part of planar surfaces: every Lambertian lobe precomputed into textures (section 2.2.1, drawn in every antialiasing frame), only purely Lambertian surfaces so (the paper's), or splatted like every other surface (section 2.2 as written, drawn once through the pixel centres)
    #[arg(long, value_enum, default_value_t = DiffuseArg::Texture)]
    pub diffuse: DiffuseArg,
    /// Glossy BRDFs on the GPU.
    #[arg(long, value_enum, default_value_t = GlossyArg::Exact)]
    pub glossy: GlossyArg,
    /// Exposure in stops applied to the PNG (EXR files are never scaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// DETP disc radius in scene units (`--technique detp`). Defaults to 2.5 % of the scene's size, the longest side of its bounding box (0.05 m in `cornell`).
    #[arg(long)]
    pub radius: Option<f32>,
    /// DETP disc radius in scene units for the non-diffuse part of glossy surfaces' view-dependent estimate (García et al. section 2.10; their diffuse part keeps `--radius`). Defaults to 3 × the disc radius (0.15 m in `cornell`).
    #[arg(long)]
    pub glossy_radius: Option<f32>,
    /// Nearest impacts of Photon Maps (`--technique photonmap`); their power is divided by the part of their disc that lies on the vertex's surface (half on an edge against a wall, a quarter in a corner).
    #[arg(long, default_value_t = DEFAULT_PHOTONMAP_K)]
    pub k: usize,
    /// DETP with artifact control (García et al. section 1.2.1): each disc's reachable area near walls and corners, and rays followed through concave parts of the vertex's own mesh. On by default; `--artifact-control false` gives the plain estimator of section 1.2.
    #[arg(
        long,
        default_value_t = true,
        num_args = 0..=1,
        default_missing_value = "true",
        action = clap::ArgAction::Set
    )]
    pub artifact_control: bool,
    /// The per-vertex estimate on glossy surfaces (García et al. section 2.10): DETP's per-vertex ray lists in a list, QuadTree or summarised QuadTree (Impact Count and Photon Maps always keep plain impact lists), or `none` for only the diffuse part.
    #[arg(long, value_enum, default_value_t = GlossyEstimate::Quadtree)]
    pub glossy_estimate: GlossyEstimate,
    /// How DETP finds the rays crossing each disc (García et al. sections 2.6–2.7).
    #[arg(long, value_enum, default_value_t = DetpAcceleration::DiscIndex)]
    pub detp_acceleration: DetpAcceleration,
    /// DETP's pre-intersection test against the disc's tangent triangle (García et al. section 2.8).
    #[arg(long, value_enum, default_value_t = PreTestArg::None)]
    pub pretest: PreTestArg,
    /// Longest mesh edge in scene units after subdivision, for the per-vertex techniques. Defaults to 5 % of the scene's size (0.1 m in `cornell`).
    #[arg(long)]
    pub mesh_edge: Option<f32>,
    /// `--technique splat-direct`: jittered point lights per area light for the
    /// direct light, each with its own shadow map (Diefenbach & Badler 1997,
    /// section 4.4: soft shadows), photons then leaving the area light itself;
    /// 1 keeps the paper's single point light of equal power for both phases.
    #[arg(long, default_value_t = DEFAULT_LIGHT_SAMPLES)]
    pub light_samples: u32,
    /// `--technique mpr` and `beams`: depth of the recursive specular images (Diefenbach &
    /// Badler 1997, sections 3 and 8.2); at the limit a mirror shows its
    /// reflectance times the scene's mean radiance instead of a further image.
    #[arg(long, default_value_t = DEFAULT_SPEC_DEPTH)]
    pub spec_depth: u32,
    /// `--technique ibr`: radiance maps reprojected per reflector element
    /// and frame, the nearest to the mirrored eye (Bastos et al. 1999,
    /// section 8.1.3: "the k best").
    #[arg(long, default_value_t = 2)]
    pub ibr_maps: usize,
    /// `--technique ibr`: reflector elements along each reflector's two
    /// sides (the planar resolution of section 8.1.3), one hemisphere of
    /// sample cameras each.
    #[arg(long, default_value = "1x1", value_parser = crate::parse_size)]
    pub ibr_elements: (u32, u32),
    /// `--technique ibr`: arc between neighbouring sample cameras on a
    /// hemisphere, degrees (30: 17 cameras, 45: 7, 60: 6).
    #[arg(long, default_value_t = 30.0)]
    pub ibr_arc_step: f32,
    /// `--technique ibr`: texels of each radiance map along each side.
    #[arg(long, default_value_t = 96)]
    pub ibr_map_size: u32,
    /// `--technique ibr`: how the maps are chosen per frame.
    #[arg(long, value_enum, default_value_t = IbrSelectionArg::Angle)]
    pub ibr_selection: IbrSelectionArg,
    /// `--technique ibr`: the reflectance modulation R: the glossy lobe's
    /// directional albedo over k_s (a uniform environment reflects the
    /// lobe's albedo) or equation 4's F/(π cos² θ), whose magnitude the
    /// paper leaves to k_s (brighter than the lobe beyond 56°).
    #[arg(long, value_enum, default_value_t = IbrModulationArg::Albedo)]
    pub ibr_modulation: IbrModulationArg,
    /// `--technique ibr`: capture passes. 1 shows the other reflectors in
    /// each reflector's maps without their own reflections (their splats
    /// are dropped); each further pass redraws the maps with the other
    /// reflectors drawn from the last pass's maps.
    #[arg(long, default_value_t = 2)]
    pub ibr_bounces: u32,
    /// `--technique ibr`: the paper's one space-invariant kernel K per
    /// reflector, sized from the mean depth, or K sized by each pixel's own
    /// depth (section 9's more accurate method: what touches the reflector
    /// stays sharp, but the reconstruction's blocks show there; glosbox
    /// 256²: relMSE 0.0030 against 0.0028, and slower).
    #[arg(long, value_enum, default_value_t = IbrKernelArg::Invariant)]
    pub ibr_kernel: IbrKernelArg,
    /// `--technique ibr`: the reflected image M from the radiance maps
    /// (the paper's) or from the scene's geometry drawn again from each
    /// reflector's mirrored view, every frame (the paper's comparison:
    /// no capture, a full frame per reflector).
    #[arg(long, value_enum, default_value_t = IbrReflectedArg::Maps)]
    pub ibr_reflected: IbrReflectedArg,
    /// `--technique ibr`: the reflected image's resolution, chosen from each
    /// reflector's glossiness (section 2: M's pixels as wide as keeps the
    /// kernel's support 8 pixels wide, a rougher lobe a coarser M; the
    /// kernel's radius from the depths of the reflector's last M) or the
    /// frame's (the kernel then spans as many frame pixels as it must).
    #[arg(long, value_enum, default_value_t = IbrResolutionArg::Glossiness)]
    pub ibr_resolution: IbrResolutionArg,
    /// `--technique ibr`: a radiance-map cache file. Its maps are used when
    /// it was written for this scene, lighting and sampling (a key over the
    /// scene and every option that changes the maps); otherwise the maps are
    /// captured and written there. Delete it after changing the renderer.
    #[arg(long, value_name = "FILE")]
    pub ibr_cache: Option<PathBuf>,
    /// `--technique composed`: the glossy lobes of planar glossy reflectors
    /// from glossy images, radiance maps or splats [default: images; on
    /// glosbox at 128² images err 0.54 times as much as maps, in 0.47 of the
    /// time].
    #[arg(long, value_enum)]
    pub reflectors: Option<ReflectorsArg>,
    /// `--technique composed`: the light point lights send through mirrors
    /// and glass, as beams, virtual lights or splats [default: beams].
    #[arg(long, value_enum)]
    pub caustics: Option<CausticsArg>,
    /// The terms the frame draws, comma-separated (emission, direct,
    /// diffuse, glossy, caustics) [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub terms: Option<Vec<TermArg>>,
    /// Also write each term the frame draws alone, as linear EXRs beside
    /// `--out` (`NAME-direct.exr`, ...), which sum to the frame.
    #[arg(long)]
    pub term_images: bool,
    /// `--technique mpr` and `beams`: glossy images (Diefenbach & Badler 1997, section 3,
    /// "glossy marble"): N mirror images per planar glossy face, sheared
    /// about its normal by the lobe's roughness and averaged; the face's
    /// splats are dropped (its Lambertian lobe stays in the diffuse textures,
    /// so `--diffuse texture` is needed). 0 makes none. Default 16 with
    /// `--diffuse texture` and `--spec-depth` above 0 (glosbox 256², relMSE
    /// 0.0041 without, 0.0017 with), 0 otherwise.
    #[arg(long)]
    pub glossy_images: Option<u32>,
    /// With `--glossy-images`: faces make glossy images only in views of
    /// recursion level below this (1: the faces the camera sees; 2: also
    /// inside them, one shear per outer sample); deeper they show their
    /// reflectance times the scene's mean radiance.
    #[arg(long, default_value_t = DEFAULT_GLOSSY_DEPTH)]
    pub glossy_depth: u32,
    /// With `--glossy-images`: the fog distance f_max in m, the images fading
    /// linearly towards the scene's mean radiance with distance from the
    /// face; default D/(2α) per material (D the scene's diagonal), `inf` for none.
    #[arg(long)]
    pub glossy_fog: Option<f32>,
    /// With `--glossy-images`: the shears the paper's way (isotropic, twice
    /// the facet slope, equal weights) or the microfacet reflection at each
    /// face's centroid with the estimator's weights (exact at any incidence there).
    #[arg(long, value_enum, default_value_t = GlossyShearArg::Isotropic)]
    pub glossy_shear: GlossyShearArg,
    /// With `--glossy-images`: which of the jittered lights (`--light-samples`
    /// per area light) each sheared view draws: all of them, or one group of
    /// gcd(lights, images) paired with its shear, each light weighted by the
    /// group count, so the image averages the same light with a fraction of
    /// the passes (a glossy floor under 16 light samples and 16 images: one
    /// light per sheared view instead of 16).
    #[arg(long, value_enum, default_value_t = GlossyLightsArg::Paired)]
    pub glossy_lights: GlossyLightsArg,
    /// With `--glossy-images`: frosted glass (Diefenbach & Badler 1997,
    /// section 3, figure 3): every glass slab's images sheared as if one of
    /// its faces were rough with this Beckmann α (there is no rough
    /// dielectric material yet); 0 keeps the glass clear.
    #[arg(long, default_value_t = 0.0)]
    pub frosted_glass: f32,
    /// `--technique mpr` and `beams`: shadows of the direct light by silhouette shadow
    /// volumes (Diefenbach & Badler 1997, section 4.1; with `--light-samples`
    /// K > 1 the K jittered lights follow `--jittered-volumes`, section 4.4)
    /// or by cube shadow maps.
    #[arg(long, value_enum, default_value_t = ShadowArg::Volumes)]
    pub shadows: ShadowArg,
    /// With shadow volumes and `--light-samples` K > 1 (Diefenbach & Badler
    /// 1997, section 4.4): `pivot` shares the volumes of the area light's
    /// centre among its K jittered lights and moves only their far vertices
    /// (the paper's jitter approximation: a face lit from the centre but not
    /// from a jittered light still casts for it); `stored` builds and stores
    /// volumes for every jittered position the accumulation samples draw (K
    /// per sample with paired jitter: that many times the volumes' memory
    /// and build time), each light shadowed exactly; `auto` stores them where
    /// they take at most 64 MiB (cornell, glosbox: 16 light positions
    /// instead of 1), else pivots (bathroom's would take 239 MiB).
    #[arg(long, value_enum, default_value_t = VolumeJitterArg::Auto)]
    pub jittered_volumes: VolumeJitterArg,
    /// `--technique mpr` with shadow volumes: shadow recursion depth, the
    /// longest chain of mirrors, glass slabs and single interfaces a light passes
    /// as a virtual light with its light volume and bent shadows (Diefenbach
    /// & Badler 1997, sections 4.2, 4.3 and 8.1); 0 adds no virtual light.
    /// Default 1, and 0 with `--shadows maps`, which has no virtual lights,
    /// and with `--technique beams`, whose beams draw that light.
    #[arg(long)]
    pub shadow_depth: Option<u32>,
    /// `--technique mpr` and `beams`: which shadows of virtual lights are drawn
    /// (Diefenbach & Badler 1997, table 2: all, none through two or more
    /// faces, or none: light volumes only).
    #[arg(long, value_enum, default_value_t = SpecShadowsArg::All)]
    pub spec_shadows: SpecShadowsArg,
    /// `--technique mpr` with virtual lights: light through windows of
    /// smooth thin-dielectric panes as one light volume per window modulated
    /// by a projective texture of the panes (Diefenbach & Badler 1997,
    /// section 4.5), one light volume per pane, or left to the splats.
    #[arg(long, value_enum, default_value_t = PaneLightArg::Projective)]
    pub pane_light: PaneLightArg,
    /// Texels along each side of a window's projective texture.
    #[arg(long, default_value_t = DEFAULT_TEXTURE_SIZE)]
    pub window_texture: u32,
    /// Antialiasing: frames rendered with sub-pixel jittered projections and
    /// averaged, a box filter over each pixel (Diefenbach & Badler 1997,
    /// section 7); 1 renders once through the pixel centres.
    #[arg(long, default_value_t = DEFAULT_AA)]
    pub aa: u32,
    /// With `--aa N`: draw the photon splats in every jittered frame (N times
    /// the splat fill) instead of once through the pixel centres.
    #[arg(long)]
    pub aa_splats: bool,
    /// With `--aa N` below this: the emitters seen directly drawn apart
    /// through this many jittered cameras of their own (a depth pre-pass and
    /// the emission pass each), since their edges are the frame's sharpest
    /// contrast and N samples leave an edge pixel's coverage in steps of 1/N;
    /// only where no mirror, glass or emitter-showing glossy image can show
    /// an emitter (else they stay in the N frames). 0: always in the N frames.
    #[arg(long, default_value_t = DEFAULT_EMISSION_SAMPLES)]
    pub emission_samples: u32,
    /// With `--aa N` and `--light-samples K > 1`: move the K light positions
    /// within their strata in every jittered frame (N K positions in all,
    /// each frame redrawing K shadow cubes; Diefenbach & Badler 1997, section
    /// 4.4) instead of keeping the same K.
    #[arg(long)]
    pub paired_lights: bool,
    /// `--technique beams`: how each fragment finds the beams that may hold
    /// it: every beam (the paper's linear traversal, Duvenhage et al. 2010,
    /// section 4.3) or a hierarchy over the beams' slab boxes (its section
    /// 5.2's future work); the image is the same.
    #[arg(long, value_enum, default_value_t = BeamTraversalArg::Hierarchy)]
    pub beam_traversal: BeamTraversalArg,
    /// `--technique beams`: where a glossy beam's domain is split outside
    /// its flux triangle (section 4.2.2, figure 12): the paper's point,
    /// re-scattered from the scatterer's edge at the flux-plane parameter;
    /// the edge point whose ray meets the split point (continuous across the
    /// beam's edges); or the point on the 2D domain's edge.
    #[arg(long, value_enum, default_value_t = SplitPointArg::Rescattered)]
    pub split_point: SplitPointArg,
    /// `--technique beams`: a glossy beam's volume under the scatter
    /// Gaussian (section 4.2.2): the Gaussian integrated over the domain (the
    /// better approximation the paper asks for), or the paper's planar
    /// facets clamped to one, which widen each glossy beam by about σ at full
    /// strength (on glosbox 2.5 times the gold box's reflected light,
    /// relMSE 0.011 against the reference where integrated gives 0.0014).
    #[arg(long, value_enum, default_value_t = GlossyVolumeArg::Integrated)]
    pub glossy_volume: GlossyVolumeArg,
    /// `--technique beams`: the Beckmann roughness α of every scatterer as
    /// the beams see it, in place of its material's (the paper's glossy
    /// variance, figures 13 and 14: a window pane sand-blasted coarser and
    /// coarser); the scatter Gaussian's σ follows from it (√2 α for a
    /// reflector, |η − 1| α through a pane, |1 − 1/η| α/√2 through water).
    /// Only the beams change: the surfaces' own images stay as modelled.
    #[arg(long)]
    pub beam_roughness: Option<f32>,
    /// Use the software adapter even where a hardware one exists.
    #[arg(long)]
    pub software: bool,
    /// Move the scene's mobile objects along their paths over this many frames, updating the per-vertex irradiance incrementally (García et al. 2003, section 2), and write one image per frame (`NAME-0000.png`, ...) with a timing sidecar.
    #[arg(long)]
    pub frames: Option<usize>,
    /// With `--frames`: only simulate and report the times, without the GPU or images.
    #[arg(long, requires = "frames")]
    pub timing_only: bool,
    /// Play a camera path (a `lustre-camera-path` JSON file, see `lustre_geometry::camera_path`): the lighting is computed once and every frame of the walkthrough is rendered from it, written as `NAME-0000.png`, ... with each frame's time in the sidecar.
    #[arg(long, value_name = "PATH.json")]
    pub camera_path: Option<PathBuf>,
    /// With `--camera-path`: frames at evenly spaced times from its first keyframe to its last, both included; default 25 a second of the path, at least 2.
    #[arg(long, requires = "camera_path")]
    pub path_frames: Option<usize>,
}

impl RenderArgs {
    /// How `--technique composed` draws planar glossy reflectors (`--reflectors`, glossy images by default); `None` for the other techniques.
    pub fn reflectors(&self) -> Option<ReflectorsArg> {
        (self.technique == Technique::Composed)
            .then(|| self.reflectors.unwrap_or(ReflectorsArg::Images))
    }

    /// How `--technique composed` draws caustics (`--caustics`, beams by default); `None` for the other techniques.
    pub fn caustics(&self) -> Option<CausticsArg> {
        (self.technique == Technique::Composed).then(|| self.caustics.unwrap_or(CausticsArg::Beams))
    }

    /// Whether the frame draws beams (Duvenhage et al. 2010): `beams`, or `composed` with `--caustics beams`.
    pub fn draws_beams(&self) -> bool {
        self.technique == Technique::Beams || self.caustics() == Some(CausticsArg::Beams)
    }

    /// Whether planar glossy reflectors are drawn from radiance maps (Bastos et al. 1999): `ibr`, or `composed` with `--reflectors maps`.
    pub fn draws_radiance_maps(&self) -> bool {
        self.technique == Technique::Ibr || self.reflectors() == Some(ReflectorsArg::Maps)
    }

    /// Whether planar glossy faces may be drawn as glossy images (Diefenbach & Badler 1997, section 3): `mpr`, `beams`, or `composed` with `--reflectors images`.
    pub fn may_draw_glossy_images(&self) -> bool {
        matches!(self.technique, Technique::Mpr | Technique::Beams)
            || self.reflectors() == Some(ReflectorsArg::Images)
    }

    /// The terms `--terms` leaves in the frame (all by default).
    pub fn drawn_terms(&self) -> Vec<TermArg> {
        TermArg::all()
            .iter()
            .copied()
            .filter(|t| self.terms.as_ref().is_none_or(|terms| terms.contains(t)))
            .collect()
    }

    /// How light through stained-glass windows is drawn, from `--pane-light` and `--window-texture`.
    pub fn pane_light(&self) -> PaneLight {
        match self.pane_light {
            PaneLightArg::Projective => PaneLight::Projective {
                size: self.window_texture,
            },
            PaneLightArg::PerPane => PaneLight::PerPane,
            PaneLightArg::Off => PaneLight::Off,
        }
    }
    /// Whether the photons and the direct light leave point lights that replace the area lights (section 3; one light sample of a direct-light technique).
    pub fn point_lights(&self) -> bool {
        self.technique.direct_light() && self.light_samples == 1
    }

    /// The splats' support rule (equation 3 or Silverman's rate, section 2.2) from `--support`, `--kernel-c` and `--support-c`.
    pub fn support_rule(&self) -> Support {
        match self.support {
            SupportArg::Equation3 => Support::Scaled(self.kernel_c),
            SupportArg::Silverman => Support::Silverman(self.support_c),
            SupportArg::GlossySilverman => Support::GlossySilverman {
                kernel_c: self.kernel_c,
                c: self.support_c,
            },
        }
    }

    /// The per-vertex techniques' lengths on `scene` (in `studio` if it has one): those given, the others relative to its size.
    pub fn density_lengths(
        &self,
        scene: &Scene,
        studio: Option<&Studio>,
    ) -> anyhow::Result<DensityLengths> {
        DensityLengths::for_scene(
            scene,
            studio,
            self.radius,
            self.glossy_radius,
            self.mesh_edge,
        )
    }

    /// The per-vertex techniques' settings from these options and the lengths chosen for the scene.
    pub fn density_settings(&self, lengths: &DensityLengths) -> DensitySettings {
        DensitySettings {
            photons: self.photons,
            seed: self.seed,
            artifact_control: self.artifact_control,
            glossy_radius: lengths.glossy_radius,
            glossy: self.glossy_estimate,
            acceleration: self.detp_acceleration,
            pretest: self.pretest,
            max_glossy_rays: crate::render_density::glossy_ray_limit(),
        }
    }
}

/// The default C of equation 3; chosen by the error against the Mitsuba reference (BENCHMARKS.md).
pub const DEFAULT_KERNEL_C: f32 = 16.0;

/// The default `c` of Silverman's rate `h = c √A n^(-1/6)`: glosbox at 1M photons, 256², relMSE splat / splat-direct 0.0049 / 0.0047 at c = 1, 0.0043 / 0.0041 at 1.25, 0.0039 / 0.0038 at 1.5 (BENCHMARKS.md); larger kernels fill more, as c².
pub const DEFAULT_SUPPORT_C: f32 = 1.25;

/// The default `--light-samples`, chosen by error against the Mitsuba
/// reference and time on lavapipe: on `cornell` at 256×256 FLIP 0.066 with 1,
/// 0.061 with 4, 0.056 with 16 jittered point lights (BENCHMARKS.md).
pub const DEFAULT_LIGHT_SAMPLES: u32 = 16;
/// Default `--spec-depth`: two levels of specular images (the paper's figure 18(a)).
pub const DEFAULT_SPEC_DEPTH: u32 = 2;
/// Default `--shadow-depth` with shadow volumes: lights followed through one specular face.
pub const DEFAULT_SHADOW_DEPTH: u32 = 1;
/// Default `--glossy-images` with `--diffuse texture`: 16 sheared images per
/// glossy face (glosbox 256², otherwise default settings, relMSE against the
/// path-traced reference: 0.00409 without glossy images; at depth 2 0.00173
/// with 16, 0.00165 with 32 for twice the frame time).
pub const DEFAULT_GLOSSY_IMAGES: u32 = 16;
/// Default `--glossy-depth`: glossy images also inside glossy images, one
/// shear per outer sample (glosbox: relMSE 0.00207 at depth 1, 0.00173 at 2,
/// 0.00173 at 3).
pub const DEFAULT_GLOSSY_DEPTH: u32 = 2;

/// The default `--aa`, chosen by error against the Mitsuba reference and
/// time on lavapipe: with 16 light samples on `cornell` at 256×256 relMSE
/// 0.0027 with 1, 0.0019 with 4 jittered frames (BENCHMARKS.md).
pub const DEFAULT_AA: u32 = 4;

/// `--emission-samples`' default: the emitters' edges through 64 jittered cameras.
pub const DEFAULT_EMISSION_SAMPLES: u32 = 64;

/// The most `--emission-samples` (one view block each in the frame's view buffer).
pub const MAX_EMISSION_SAMPLES: u32 = 4096;

/// Milliseconds since `start`.
fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// The process's peak resident memory (`VmHWM` of `/proc/self/status`), where the system reports it.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The scene with every area light replaced by a cosine point light of equal power (section 3: "small area light sources ... replaced by point light sources with equivalent power for both phases").
fn with_point_lights(scene: &Scene) -> anyhow::Result<Scene> {
    scene
        .with_area_lights_as_points()
        .context("cannot replace the area lights by point lights")
}

/// Renders as `args` says and writes the image and its sidecar.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    check_output(&args.out, "--out")?;
    if !(args.kernel_c > 0.0 && args.kernel_c.is_finite()) {
        bail!("--kernel-c {}: must be positive", args.kernel_c);
    }
    if !(args.support_c > 0.0 && args.support_c.is_finite()) {
        bail!("--support-c {}: must be positive", args.support_c);
    }
    if args.photons == 0 {
        bail!("--photons 0: at least one photon is needed");
    }
    if args.light_samples == 0 {
        bail!("--light-samples 0: at least one point light per area light is needed");
    }
    if args.aa == 0 {
        bail!("--aa 0: at least one sample per pixel is needed");
    }
    if args.emission_samples > MAX_EMISSION_SAMPLES {
        bail!(
            "--emission-samples {}: at most {MAX_EMISSION_SAMPLES} (256 already leaves a light's \
             edge within 1/256 of its coverage)",
            args.emission_samples
        );
    }
    if args.restriction == RestrictionArg::Stencil
        && matches!(
            args.splat_resolution,
            SplatResolutionArg::Half | SplatResolutionArg::Quarter | SplatResolutionArg::Eighth
        )
    {
        bail!(
            "--splat-resolution below full restricts splats by surface ids: \
             leave out --restriction stencil or use --splat-resolution full"
        );
    }
    if args.photons_file.is_some() {
        if !matches!(
            args.technique,
            Technique::Splat
                | Technique::SplatDirect
                | Technique::Mpr
                | Technique::Beams
                | Technique::Composed
        ) {
            bail!(
                "--photons-file: only the splatting techniques (splat, splat-direct, mpr, beams, \
                 composed) read photons in batches; --technique {:?} needs them all in memory",
                args.technique
            );
        }
        if args.draws_radiance_maps() {
            bail!(
                "--photons-file: radiance maps capture the frame with all its splats, which a \
                 file read in batches adds only after the frame; use --reflectors images or splats"
            );
        }
        if args.aa_splats {
            bail!(
                "--photons-file: batches of splats are drawn once through the pixel centres; \
                 leave out --aa-splats"
            );
        }
        if args.batch_records == 0 {
            bail!("--batch-records 0: at least one record per batch");
        }
        if args.frames.is_some() {
            bail!("--photons-file: --frames animates the per-vertex techniques only");
        }
    }
    // The camera path first, so that a bad file fails before any work.
    let camera_path = match &args.camera_path {
        Some(file) => {
            if args.frames.is_some() {
                bail!("--camera-path: leave out --frames (which moves objects, not the camera)");
            }
            if args.photons_file.is_some() {
                bail!(
                    "--camera-path: photons streamed from --photons-file are splatted once, into one view"
                );
            }
            if args.technique.per_vertex() {
                bail!(
                    "--camera-path: the per-vertex techniques compute their glossy radiance towards one eye \
                     (García et al. section 2.10), so they render single frames; use splat, splat-direct, mpr, beams, ibr or composed"
                );
            }
            let path = CameraPath::load(file)
                .with_context(|| format!("cannot read the camera path {}", file.display()))?;
            let frames = match args.path_frames {
                Some(0) => bail!("--path-frames 0: at least one frame"),
                Some(n) => n,
                None => ((path.duration() * PATH_FRAMES_PER_SECOND).round() as usize + 1).max(2),
            };
            Some((path, frames))
        }
        None => None,
    };
    let (shadow_depth, glossy_images) = render_settings(args)?;
    if args.draws_radiance_maps() {
        check_ibr(args)?;
    }
    if args.technique == Technique::Photonmap && args.k == 0 {
        bail!("--k 0: Photon Maps needs at least one nearest impact");
    }
    // Given lengths are checked before anything is loaded.
    check_lengths(args.radius, args.glossy_radius, args.mesh_edge)?;
    let mut timings = serde_json::Map::new();
    let start = Instant::now();
    let Prepared {
        scene,
        studio,
        lengths,
        density,
    } = prepare_scene(args)?;
    let (width, height) = args.size;
    timings.insert("load".into(), json!(ms(start)));

    if let Some(frames) = args.frames {
        let (Some(estimator), Some(lengths)) = (density, lengths) else {
            bail!("--frames: only the per-vertex techniques (detp, impact, photonmap) animate");
        };
        return crate::render_frames::run(args, &lengths, scene, estimator, frames);
    }
    let lit = light(args, &scene, shadow_depth, density, lengths, &mut timings)?;
    let Lit {
        beams,
        beam_scatterers,
        kernel,
        splatting,
        vertex,
        atlas,
    } = &lit;
    let diffuse = args.diffuse;

    // GPU frame.
    let start = Instant::now();
    let preference = if args.software {
        AdapterPreference::Software
    } else {
        AdapterPreference::Hardware
    };
    let ctx = GpuContext::new(preference)?;
    eprintln!("rendering {width}x{height} on {}", ctx.adapter());
    let cameras: Vec<Camera> = match &camera_path {
        Some((path, frames)) => path
            .frames(*frames)
            .into_iter()
            .map(|c| c.with_aspect(width as f32 / height as f32))
            .collect(),
        None => vec![*scene.camera()],
    };
    let camera = cameras[0];
    let streamed = match splatting.as_ref().map(|s| &s.photons) {
        Some(Photons::File(streamed)) => Some(streamed),
        _ => None,
    };
    let mut gpu = GpuFrame::new(
        args,
        lit.lighting(&scene, shadow_depth, glossy_images),
        ctx,
        (width, height),
        &camera,
    )?;
    gpu.components = Components::only(&args.drawn_terms());
    timings.insert("gpu_setup".into(), json!(ms(start) - gpu.ibr_capture_ms));
    if gpu.ibr.is_some() {
        timings.insert("radiance_maps".into(), json!(gpu.ibr_capture_ms));
    }
    // A walkthrough: every frame of the camera path from the same lighting, each read back and written.
    let mut path_frame_ms = Vec::new();
    let mut path_write_ms = 0.0;
    let mut ibr_times = Vec::new();
    for (i, camera) in cameras.iter().enumerate() {
        let start = Instant::now();
        gpu.draw(camera, args.aa)?;
        path_frame_ms.push(ms(start));
        if let Some(ibr) = &gpu.ibr {
            ibr_times.push(ibr.take_times());
        }
        if camera_path.is_some() {
            let start = Instant::now();
            let image = gpu.read_hdr()?;
            write_image(&frame_path(&args.out, i), args.exposure, &image)?;
            path_write_ms += ms(start);
            eprintln!(
                "frame {}/{}: {:.0} ms",
                i + 1,
                cameras.len(),
                path_frame_ms[i]
            );
        }
    }
    timings.insert("frame".into(), json!(path_frame_ms.iter().sum::<f64>()));
    // A streamed photon file: each batch's splats uploaded, added, dropped.
    let mut streamed_splats = (0u64, 0u64);
    let mut splat_resolution = gpu.splat_resolution;
    if let (Some(streamed), Some(splatting)) = (streamed, &splatting) {
        let start = Instant::now();
        let bar = PhotonBar::new("splatting photons", splatting.hit_records)?;
        let template = streamed.template(&scene, splatting.options)?;
        let frame = gpu.inputs(&camera);
        streamed.for_each_batch(
            &mut |batch| {
                let estimator = template.with_photons(batch)?;
                let buffers = SplatBuffers::new_excluding_imaged(
                    &gpu.ctx,
                    &scene,
                    &estimator,
                    gpu.glossy,
                    &gpu.exclude,
                    &gpu.imaged,
                    &gpu.maps,
                )
                .with_context(|| format!("scene `{}`", scene.name))?;
                let resolution = *splat_resolution.get_or_insert_with(|| {
                    resolve_resolution(args, gpu.restriction, &buffers.supports, &camera, height)
                });
                gpu.graph.add_splats(
                    &gpu.ctx,
                    &FrameInputs {
                        splats: Some(SplatInputs {
                            buffers: &buffers,
                            restriction: gpu.restriction,
                            filtering: gpu.filtering,
                            resolution,
                        }),
                        direct: None,
                        diffuse: None,
                        ..frame
                    },
                    streamed_splats.1 == 0,
                )?;
                // One batch on the GPU at a time.
                gpu.ctx
                    .device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .context("waiting for a batch of splats")?;
                streamed_splats.0 += u64::from(buffers.count);
                streamed_splats.1 += 1;
                Ok(())
            },
            &bar,
        )?;
        timings.insert("streamed_splats".into(), json!(ms(start)));
    }

    if camera_path.is_some() {
        timings.insert("readback_and_write".into(), json!(path_write_ms));
    } else {
        let start = Instant::now();
        let image = gpu.read_hdr()?;
        timings.insert("readback".into(), json!(ms(start)));

        let start = Instant::now();
        write_outputs(args, &image)?;
        timings.insert("write".into(), json!(ms(start)));
    }
    let term_images = if args.term_images {
        let start = Instant::now();
        let written = write_term_images(args, &mut gpu, &camera)?;
        timings.insert("term_images".into(), json!(ms(start)));
        written
    } else {
        Vec::new()
    };
    let (graph, ctx, targets) = (&gpu.graph, &gpu.ctx, &gpu.targets);
    let (splats, direct, imaged, glossy_images) =
        (&gpu.splats, &gpu.direct, &gpu.imaged, &gpu.glossy_images);
    let (restriction, filtering, glossy) = (gpu.restriction, gpu.filtering, gpu.glossy);
    let (shadow_volumes, paired, beam_set) = (gpu.shadow_volumes, gpu.paired, beams.as_ref());
    let scene_passes = graph.view_tree(ctx, &camera)?.scene_passes();
    // Multi-pass pipeline rendering's pass counts (tables 1-3, equations 7 and 8).
    let mpr_passes = json!({
        "shadow_volume_bytes": graph.shadow_volumes.as_ref().map(|v| v.set().byte_size()),
        "specular_faces": graph.specular.as_ref().map(|s| s.faces().len()),
        "scene_passes": scene_passes,
        "shadow_passes": graph.shadow_volumes.as_ref().map(|v| scene_passes * v.shadow_generations()),
        "virtual_light_volume_bytes": graph.shadow_volumes.as_ref().and_then(|v| v.virtual_lights()).map(|v| v.byte_size()),
        // Section 4.5: stained-glass windows as projective textures.
        "windows": graph.shadow_volumes.as_ref().and_then(|v| v.virtual_lights()).map(|v| json!({
            "pane_light": format!("{:?}", args.pane_light),
            "count": v.windows().len(),
            "panes": v.windows().iter().map(|w| w.surfaces.len()).sum::<usize>(),
            "texture_size": v.windows().first().map(|w| w.texture.width),
            "texture_bytes": texture_bytes(v.windows()),
        })),
        "shadow_depth": args.technique.multipass().then_some(shadow_depth),
        "spec_shadows": (shadow_depth > 0).then(|| format!("{:?}", args.spec_shadows)),
        "equation_8_scene_passes": graph.specular.as_ref().map(|s| {
            (s.faces().len() as f64).powi(args.spec_depth as i32) + 1.0
        }),
        "shadow_generations_per_light": graph.shadow_volumes.as_ref().map(|v| {
            let (_, of) = v.positions();
            of.iter().map(|&c| v.virtual_lights().map_or(1, |l| l.shadow_generations(c))).collect::<Vec<_>>()
        }),
        // n: the faces a light may pass, the windows' too (section 4.5).
        "equation_7_shadow_generations_per_light": graph.specular.as_ref().map(|s| {
            let windows = graph.shadow_volumes.as_ref().and_then(|v| v.virtual_lights()).map_or(0, |v| v.windows().len());
            equation_7(s.faces().len() + 2 * windows, shadow_depth)
        }),
        "clip_method": graph.specular.as_ref().map(|_| format!("{:?}", ctx.clip_method())),
    });
    let beam_photon_hits = splatting.as_ref().and_then(|s| s.beam_hits);
    let total: f64 = timings.values().filter_map(serde_json::Value::as_f64).sum();
    timings.insert("total".into(), json!(total));

    // Bastos et al. 1999: the reflectors drawn from radiance maps.
    let radiance_maps = gpu.ibr.as_ref().map(|ibr| {
            let settings = ibr.settings();
            let memory = ibr.memory();
            json!({
                "reflectors": ibr.reflectors().iter().map(|r| r.maps.reflector.surface).collect::<Vec<_>>(),
                "elements": settings.sampling.planar_resolution,
                "arc_step_degrees": settings.sampling.arc_step_degrees,
                "maps_per_reflector": ibr.reflectors().first().map(|r| r.maps.maps.len()),
                "map_resolution": settings.sampling.map_resolution,
                "maps_per_hemisphere": settings.maps_per_hemisphere,
                "selection": format!("{:?}", settings.selection),
                "modulation": format!("{:?}", settings.modulation),
                "kernel": format!("{:?}", settings.kernel),
                "bounces": settings.bounces,
                "bytes": memory.iter().map(|m| m.bytes).sum::<usize>(),
                // Table 1's columns per reflector.
                "table": memory.iter().map(|m| json!({
                    "surface": m.surface,
                    "material": scene.surfaces().get(m.surface as usize)
                        .and_then(|s| scene.materials().get(s.material as usize))
                        .map(|mat| mat.name.clone()),
                    "hemispheres": m.hemispheres,
                    "maps_per_hemisphere": m.maps_per_hemisphere,
                    "resolution": m.resolution,
                    "bytes": m.bytes,
                })).collect::<Vec<_>>(),
                "reflected": format!("{:?}", settings.reflected),
                "resolution": format!("{:?}", settings.resolution),
                // Each stage's median over the frames drawn (milliseconds, the GPU waited for).
                "frame_ms": {
                    "reflected": median(ibr_times.iter().map(|t| t.reflected_ms).collect()),
                    "depth_readback": median(ibr_times.iter().map(|t| t.depth_readback_ms).collect()),
                    "convolution_modulation": median(ibr_times.iter().map(|t| t.convolution_modulation_ms).collect()),
                    "total": median(ibr_times.iter().map(|t| t.total_ms).collect()),
                },
                "cache": args.ibr_cache.as_ref().map(|path| json!({
                    "path": path.display().to_string(),
                    "hit": gpu.ibr_cached,
                })),
            })
        });
    // The composed frame's method per term, and the terms drawn.
    let composed = (args.technique == Technique::Composed).then(|| {
        json!({
            "reflectors": args.reflectors().and_then(|r| r.to_possible_value()).map(|v| v.get_name().to_owned()),
            "caustics": args.caustics().and_then(|c| c.to_possible_value()).map(|v| v.get_name().to_owned()),
        })
    });
    let drawn_terms: Vec<_> = args.drawn_terms().iter().map(|t| t.name()).collect();
    let term_image_files = (!term_images.is_empty()).then(|| {
        term_images
            .iter()
            .map(|(t, p)| (t.name().to_owned(), json!(p.display().to_string())))
            .collect::<serde_json::Map<_, _>>()
    });
    let sidecar = sidecar_path(&args.out);
    let mut info = json!({
        "scene": scene.name,
        "studio": studio,
        "technique": args.technique.to_possible_value().map(|v| v.get_name().to_owned()),
        "photons": splatting.as_ref().map_or(args.photons, |s| s.emitted),
        "hit_records": splatting.as_ref().map(|s| s.hit_records),
        "splats": splats.as_ref().map(|s| u64::from(s.count)).or(streamed.map(|_| streamed_splats.0)),
        "kernel": format!("{kernel:?}"),
        "kernel_c": args.kernel_c,
        "support": format!("{:?}", args.support_rule()),
        "emission": splatting.as_ref().map(|s| format!("{:?}", s.emission)),
        "estimator": density.map(|e| format!("{e:?}")),
        "mesh_edge": lengths.map(|l| l.mesh_edge),
        "artifact_control": density.map(|_| args.artifact_control),
        "glossy_radius": lengths.filter(|_| matches!(density, Some(Estimator::Detp { .. }))).map(|l| l.glossy_radius),
        "glossy_estimate": density.map(|_| format!("{:?}", args.glossy_estimate)),
        "detp_acceleration": density.map(|_| format!("{:?}", args.detp_acceleration)),
        "pretest": density.map(|_| format!("{:?}", args.pretest)),
        "triangles": scene.triangle_count(),
        "ray_segments": vertex.as_ref().map(|v| v.segments),
        "light_samples": args.technique.direct_light().then_some(args.light_samples),
        "spec_depth": args.technique.multipass().then_some(args.spec_depth),
        "beams": beam_set.map(|set| {
            let stats = set.stats();
            json!({
                "scattered": stats.scattered,
                "shadow": stats.shadow,
                "scatterers": beam_scatterers,
                "light_scatterer_pairs": stats.pairs,
                "back_facing": stats.back_facing,
                "total_internal_reflection": stats.total_internal_reflection,
                "too_wide": stats.too_wide,
                "hierarchy_boxes": set.hierarchy().len(),
                "gpu_bytes": graph.beams.as_ref().map(|b| b.byte_size()),
                "traversal": format!("{:?}", args.beam_traversal),
                "split_point": format!("{:?}", args.split_point),
                "glossy_volume": format!("{:?}", args.glossy_volume),
                "roughness": args.beam_roughness,
                "shadow_beams": false,
                "photon_hits_left_to_beams": beam_photon_hits,
            })
        }),
        "glossy_images": (glossy_images.samples > 0).then(|| json!({
            "samples": glossy_images.samples,
            "depth": glossy_images.depth,
            "fog": format!("{:?}", glossy_images.fog),
            "shear": format!("{:?}", glossy_images.shear),
            "lights": format!("{:?}", glossy_images.lights),
            "frosted_glass": glossy_images.frosted_alpha,
            "imaged_surfaces": imaged.iter().filter(|&&i| i).count(),
        })),
        "passes": mpr_passes,
        "shadows": args.technique.direct_light().then_some(if shadow_volumes { "volumes" } else { "maps" }),
        "direct_lights": direct.as_ref().map(DirectLights::len),
        "aa": args.aa,
        "aa_splats": args.aa_splats,
        "paired_light_jitter": paired,
        "seed": args.seed,
        "size": [width, height],
        "restriction": format!("{restriction:?}"),
        "filter": format!("{filtering:?}"),
        "glossy": format!("{glossy:?}"),
        "diffuse": format!("{diffuse:?}"),
        "diffuse_atlas": atlas.as_ref().map(|a| [a.width, a.height]),
        "exposure": args.exposure,
        "adapter": ctx.adapter().to_string(),
        "hdr_format": format!("{:?}", targets.hdr_format()),
        "timings_ms": timings,
        "version": env!("CARGO_PKG_VERSION"),
    });
    // Section 4.4: how the volumes follow jittered lights, and how many light positions have volumes.
    info["jittered_volumes"] = json!(graph.shadow_volumes.as_ref().map(|v| json!({
        "jitter": match v.jitter() {
            VolumeJitter::Pivot => "pivot",
            VolumeJitter::Stored => "stored",
        },
        "positions": v.positions().0.len(),
    })));
    info["radiance_maps"] = radiance_maps.unwrap_or_default();
    info["composed"] = json!(composed);
    // The jittered cameras the emitters seen directly were drawn through (`--emission-samples`).
    info["emission_samples"] =
        json!(graph.emission_samples(gpu.inputs(&camera).graph_terms, args.aa));
    info["terms"] = json!(drawn_terms);
    info["term_images"] = json!(term_image_files);
    info["splat_resolution"] = json!(splat_resolution.map(|r| format!("{r:?}")));
    // The projected kernel radius `auto` reads (pixels, the 5 % quantile).
    info["splat_radius_q05_px"] = json!(splats.as_ref().and_then(|b| radius_quantile(
        &b.supports,
        &camera,
        height,
        AUTO_QUANTILE
    )));
    info["photons_file"] = json!(args.photons_file.as_ref().map(|p| json!({
        "path": p.display().to_string(),
        "batches": streamed_splats.1,
        "batch_records": args.batch_records,
    })));
    info["camera_path"] = json!(camera_path.as_ref().map(|(_, frames)| json!({
        "path": args.camera_path.as_ref().map(|p| p.display().to_string()),
        "frames": frames,
        "frame_ms": path_frame_ms,
        "median_frame_ms": median(path_frame_ms.clone()),
        "first": frame_path(&args.out, 0).display().to_string(),
    })));
    // GPU time of each pass of the last frame (timestamp queries, where the adapter has them).
    info["gpu_pass_ms"] = json!(gpu.pass_times()?.map(|t| {
        t.into_iter()
            .map(|(n, ms)| (n.to_owned(), json!(ms)))
            .collect::<serde_json::Map<_, _>>()
    }));
    info["peak_memory_bytes"] = json!(peak_memory_bytes());
    // The size the per-vertex techniques' default lengths scale with.
    info["scene_size"] = json!(lengths.map(|l| l.scene_size));
    lustre_image::write_json_atomic(&sidecar, &info)
        .with_context(|| format!("cannot write {}", sidecar.display()))?;
    if camera_path.is_some() {
        eprintln!(
            "wrote {} frames {} ... and {}",
            cameras.len(),
            frame_path(&args.out, 0).display(),
            sidecar.display()
        );
    } else {
        eprintln!("wrote {} and {}", args.out.display(), sidecar.display());
    }
    Ok(())
}

/// Checks an output path: `.exr` or `.png`, in a directory that exists (nothing half-written, no render thrown away); `flag` names the option in the message.
pub fn check_output(out: &Path, flag: &str) -> anyhow::Result<()> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("exr" | "png")) {
        bail!(
            "{flag} {}: the file must end in .exr or .png",
            out.display()
        );
    }
    check_directory(out, flag)
}

/// Checks that the directory a file is to be written to exists, before any work (nothing half-written, no render thrown away); `flag` names the option in the message.
fn check_directory(file: &Path, flag: &str) -> anyhow::Result<()> {
    let dir = match file.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{flag} {}: the directory {} does not exist",
            file.display(),
            dir.display()
        );
    }
    Ok(())
}

/// Checks the options that belong to `--technique composed` and to the splatting techniques' terms.
fn check_composed(args: &RenderArgs) -> anyhow::Result<()> {
    if args.technique != Technique::Composed {
        if args.reflectors.is_some() {
            bail!("--reflectors: only --technique composed chooses how reflectors are drawn");
        }
        if args.caustics.is_some() {
            bail!("--caustics: only --technique composed chooses how caustics are drawn");
        }
    }
    if args.reflectors() == Some(ReflectorsArg::Images)
        && (args.diffuse != DiffuseArg::Texture || args.spec_depth == 0)
    {
        bail!(
            "--reflectors images needs --diffuse texture and --spec-depth 1 or more: glossy \
             images are specular images of faces whose Lambertian lobes come from the textures"
        );
    }
    if args.reflectors() == Some(ReflectorsArg::Images) && args.glossy_images == Some(0) {
        bail!("--glossy-images 0 with --reflectors images: use --reflectors splats or maps");
    }
    if args.technique.per_vertex() && (args.terms.is_some() || args.term_images) {
        bail!(
            "--terms and --term-images: the per-vertex techniques draw one Gouraud-shaded term; \
             use a splatting technique"
        );
    }
    if args.terms.as_ref().is_some_and(|t| t.is_empty()) {
        bail!("--terms: name at least one term");
    }
    if args.term_images && (args.camera_path.is_some() || args.photons_file.is_some()) {
        bail!(
            "--term-images: one frame from photons in memory; leave out --camera-path and --photons-file"
        );
    }
    Ok(())
}

/// The virtual light generations and glossy image settings of `args`, checked against the technique and each other.
pub fn render_settings(args: &RenderArgs) -> anyhow::Result<(u32, GlossySettings)> {
    check_composed(args)?;
    let shadow_depth = args.shadow_depth.unwrap_or(match args.shadows {
        // The beams draw the light that mirrors and glass send on.
        _ if args.draws_beams() => 0,
        // Left to the splats.
        _ if args.caustics() == Some(CausticsArg::Splats) => 0,
        ShadowArg::Volumes => DEFAULT_SHADOW_DEPTH,
        ShadowArg::Maps => 0,
    });
    if args.window_texture == 0 || args.window_texture > MAX_TEXTURE_SIZE {
        bail!(
            "--window-texture {}: expected 1 to {MAX_TEXTURE_SIZE} texels",
            args.window_texture
        );
    }
    if let Some(alpha) = args.beam_roughness {
        if !args.draws_beams() {
            bail!(
                "--beam-roughness: only --technique beams and composed (with --caustics beams) draw beams"
            );
        }
        if !(alpha >= 0.0 && alpha.is_finite()) {
            bail!("--beam-roughness {alpha}: must be finite and not negative");
        }
    }
    if args.draws_beams() && shadow_depth > 0 {
        bail!(
            "--shadow-depth {shadow_depth}: the beams draw the light that \
             mirrors and glass send on; virtual lights would add it twice"
        );
    }
    if args.shadow_depth.is_some() && !args.technique.multipass() {
        bail!("--shadow-depth: virtual lights belong to --technique mpr, beams and composed");
    }
    if args.caustics() == Some(CausticsArg::Splats) && shadow_depth > 0 {
        bail!(
            "--shadow-depth {shadow_depth} with --caustics splats: the splats draw the light that \
             mirrors and glass send on; use --caustics virtual-lights"
        );
    }
    if args.caustics() == Some(CausticsArg::VirtualLights) && args.shadows == ShadowArg::Maps {
        bail!("--caustics virtual-lights needs --shadows volumes (light volumes, section 4.2)");
    }
    if shadow_depth > 0 && args.shadows == ShadowArg::Maps {
        bail!("--shadow-depth {shadow_depth}: virtual lights need --shadows volumes");
    }
    if shadow_depth > MAX_SHADOW_DEPTH {
        bail!("--shadow-depth {shadow_depth}: at most {MAX_SHADOW_DEPTH}");
    }
    let glossy_images = GlossySettings {
        samples: match (args.may_draw_glossy_images(), args.glossy_images) {
            (true, Some(n)) => n,
            (true, None) if args.diffuse == DiffuseArg::Texture && args.spec_depth > 0 => {
                DEFAULT_GLOSSY_IMAGES
            }
            _ => 0,
        },
        depth: args.glossy_depth,
        fog: args.glossy_fog.map_or(Fog::Material, Fog::Distance),
        fog_radiance: glam::Vec3::ZERO,
        hide_emitters: true,
        shear: match args.glossy_shear {
            GlossyShearArg::Isotropic => ShearModel::Isotropic,
            GlossyShearArg::Microfacet => ShearModel::Microfacet,
        },
        frosted_alpha: args.frosted_glass,
        lights: match args.glossy_lights {
            GlossyLightsArg::All => GlossyLights::All,
            GlossyLightsArg::Paired => GlossyLights::Paired,
        },
    };
    if args.glossy_images.is_some_and(|n| n > 0) && !args.may_draw_glossy_images() {
        bail!(
            "--glossy-images: only --technique mpr, beams and composed (with --reflectors images) draw glossy images"
        );
    }
    if glossy_images.samples > 0 && args.diffuse != DiffuseArg::Texture {
        bail!(
            "--glossy-images needs --diffuse texture: the imaged faces' Lambertian lobes come \
             from the diffuse textures, their splats are dropped"
        );
    }
    if glossy_images.samples > 0 && args.spec_depth == 0 {
        bail!(
            "--glossy-images needs --spec-depth 1 or more: glossy images are specular images \
             (at depth 0 the faces would show only their reflectance times the mean radiance)"
        );
    }
    glossy_images.validate()?;
    Ok((shadow_depth, glossy_images))
}

/// A scene loaded and prepared for a technique.
pub struct Prepared {
    /// The scene: point lights and per-vertex meshing applied, the camera at the image's aspect.
    pub scene: Scene,
    /// The default studio of a model without lights, for the sidecar.
    pub studio: Option<serde_json::Value>,
    /// The per-vertex techniques' lengths.
    pub lengths: Option<DensityLengths>,
    /// The per-vertex estimator.
    pub density: Option<Estimator>,
}

/// Loads `args.scene` (printing its warnings) and prepares it for `args.technique`.
pub fn prepare_scene(args: &RenderArgs) -> anyhow::Result<Prepared> {
    let loaded = scene_arg::load(&args.scene)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    // A model without a light got a default studio (lustre_geometry::obj::Studio).
    let studio = loaded.studio.map(|s| {
        json!({
            "ground_height": s.ground_height,
            "ground_half_side": s.ground_half_side,
            "light_centre": s.light_centre.to_array(),
            "light_side": s.light_side,
            "radiance": s.radiance,
            "model_size": s.model_size,
        })
    });
    let mut scene = loaded.scene;
    // The per-vertex techniques' lengths, relative to the scene as loaded.
    let lengths = args
        .technique
        .per_vertex()
        .then(|| args.density_lengths(&scene, loaded.studio.as_ref()))
        .transpose()?;
    let density = lengths.and_then(|l| args.technique.estimator(l.radius, args.k));
    // Section 3: one point light of equal power for both phases; with more
    // light samples the photons leave the area light itself and only the
    // direct light uses its jittered point lights.
    if args.point_lights() {
        scene = with_point_lights(&scene)?;
    }
    if let Some(lengths) = &lengths {
        scene = vertex_lit_scene(&scene, lengths.mesh_edge).with_context(|| {
            format!(
                "cannot mesh `{}` to {} edges for per-vertex lighting",
                scene.name, lengths.mesh_edge
            )
        })?;
    }
    let (width, height) = args.size;
    scene.set_camera(scene.camera().with_aspect(width as f32 / height as f32));
    if scene.lights().is_empty() {
        bail!("scene `{}` has no light", scene.name);
    }
    Ok(Prepared {
        scene,
        studio,
        lengths,
        density,
    })
}

/// What the lighting phase computed for the GPU frame.
pub struct Lit {
    /// Duvenhage et al.'s beams (`--technique beams`).
    pub beams: Option<BeamSet>,
    /// Mirror, conductor and glass triangles the beams scatter from.
    pub beam_scatterers: usize,
    /// The splats' reconstruction kernel.
    pub kernel: Kernel,
    /// Photons and splat settings of the splatting techniques.
    pub splatting: Option<Splatting>,
    /// Per-vertex radiance of the per-vertex techniques.
    pub vertex: Option<crate::render_density::VertexRadiance>,
    /// The diffuse textures' atlas.
    pub atlas: Option<DiffuseAtlas>,
}

impl Lit {
    /// No lighting yet: the window's first frame (direct light and emitters) while the photons are traced.
    pub fn unlit(args: &RenderArgs) -> Self {
        Self {
            beams: None,
            beam_scatterers: 0,
            kernel: kernel_of(args),
            splatting: None,
            vertex: None,
            atlas: None,
        }
    }

    /// The lighting as the GPU frame takes it.
    pub fn lighting<'a>(
        &'a self,
        scene: &'a Scene,
        shadow_depth: u32,
        glossy_images: GlossySettings,
    ) -> Lighting<'a> {
        Lighting {
            scene,
            splats: match self.splatting.as_ref().map(|s| &s.photons) {
                Some(Photons::Memory { estimator, .. }) => Some(estimator),
                _ => None,
            },
            splatting: self.splatting.is_some(),
            corners: self.vertex.as_ref().map(|v| v.corners.as_slice()),
            atlas: self.atlas.as_ref(),
            beams: self.beams.as_ref(),
            shadow_depth,
            glossy_images,
            kernel: self.kernel,
        }
    }
}

/// The lighting phase of `scene` (loaded and prepared): beams, photons and splats or per-vertex radiance, and the diffuse textures, each phase's time added to `timings`.
pub fn light(
    args: &RenderArgs,
    scene: &Scene,
    shadow_depth: u32,
    density: Option<Estimator>,
    lengths: Option<DensityLengths>,
    timings: &mut serde_json::Map<String, serde_json::Value>,
) -> anyhow::Result<Lit> {
    // Beams start at point lights: each area light's cosine point light of
    // equal power at its centre (Stürzlinger & Bastos 1997, section 3).
    let (beams, beam_scatterers) = if args.draws_beams() {
        let start = Instant::now();
        let point_scene = if scene.lights().iter().any(|l| !l.is_delta()) {
            scene.with_area_lights_as_points()?
        } else {
            scene.clone()
        };
        let options = BuildOptions {
            // The direct pass's shadow maps or volumes already hold the
            // scatterers' shadows (section 3.1's first-order shadows).
            shadow_beams: false,
            split_point: args.split_point.into(),
            glossy_volume: args.glossy_volume.into(),
            ..BuildOptions::default()
        };
        let mut input = BeamInput::from_scene(&point_scene)
            .with_context(|| format!("cannot build the beams of `{}`", scene.name))?;
        if let Some(alpha) = args.beam_roughness {
            for s in &mut input.scatterers {
                s.material = s.material.with_roughness(alpha);
            }
        }
        let set = BeamSet::build(&input.lights, &input.scatterers, scene.bounds(), &options)
            .with_context(|| format!("cannot build the beams of `{}`", scene.name))?;
        timings.insert("beams".into(), json!(ms(start)));
        if input.scatterers.is_empty() {
            // `composed` draws whatever caustics the scene has: none is no mistake.
            if args.technique == Technique::Beams {
                eprintln!(
                    "warning: scene `{}` has no mirror, conductor or glass triangle: no beams",
                    scene.name
                );
            }
        } else {
            eprintln!(
                "beams: {} scattered from {} scatterer triangles and {} point lights in {:.0} ms",
                set.stats().scattered,
                input.scatterers.len(),
                input.lights.len(),
                ms(start)
            );
        }
        (Some(set), input.scatterers.len())
    } else {
        (None, 0)
    };
    let bvh = Bvh::build(scene);
    let kernel = kernel_of(args);
    let (splatting, vertex) = match density {
        None => (
            Some(splat_setup(
                args,
                scene,
                &bvh,
                kernel,
                args.technique.multipass().then_some(shadow_depth),
                beams.is_some(),
                timings,
            )?),
            None,
        ),
        Some(estimator) => {
            let lengths = lengths.context("a per-vertex technique has its lengths")?;
            let v = vertex_radiance(estimator, scene, &args.density_settings(&lengths))?;
            eprintln!(
                "{}: ray set of {} primary rays, {} segments in {:.0} ms; estimate at {} vertices in {:.0} ms",
                estimator.name(),
                v.primary_rays,
                v.segments,
                v.ray_set_ms,
                scene
                    .meshes()
                    .iter()
                    .map(|m| m.positions.len())
                    .sum::<usize>(),
                v.estimate_ms
            );
            timings.insert("ray_set".into(), json!(v.ray_set_ms));
            timings.insert("estimate".into(), json!(v.estimate_ms));
            (None, Some(v))
        }
    };

    // Diffuse surfaces precomputed into textures (section 2.2.1).
    let start = Instant::now();
    let diffuse = args.diffuse;
    let texture_options = DiffuseTextureOptions {
        lambertian_lobes: diffuse == DiffuseArg::Texture,
        ..DiffuseTextureOptions::default()
    };
    let atlas = match (diffuse, &splatting) {
        (DiffuseArg::Texture | DiffuseArg::DiffuseSurfaces, Some(splatting)) => Some(
            match &splatting.photons {
                Photons::Memory {
                    estimator,
                    lambertian,
                } => DiffuseAtlas::build(
                    scene,
                    lambertian.as_ref().unwrap_or(estimator),
                    texture_options,
                )
                .map_err(anyhow::Error::from),
                Photons::File(streamed) => streamed.atlas(
                    scene,
                    splatting.lambertian_options.unwrap_or(splatting.options),
                    texture_options,
                ),
            }
            .context("cannot precompute the diffuse textures")?,
        ),
        _ => None,
    };
    if atlas.is_some() {
        timings.insert("diffuse_textures".into(), json!(ms(start)));
    }
    Ok(Lit {
        beams,
        beam_scatterers,
        kernel,
        splatting,
        vertex,
        atlas,
    })
}

/// The splats' reconstruction kernel of `--kernel`.
fn kernel_of(args: &RenderArgs) -> Kernel {
    match args.kernel {
        KernelArg::Silverman => Kernel::Silverman,
        KernelArg::Gaussian => Kernel::Gaussian,
    }
}

/// Frames a second of a camera path that `--camera-path` renders without `--path-frames`.
const PATH_FRAMES_PER_SECOND: f32 = 25.0;

/// What splatting produced before the GPU frame (Stürzlinger & Bastos 1997, sections 2.1 and 2.2).
pub struct Splatting {
    /// Hit records left out because the beams draw their light.
    beam_hits: Option<u64>,
    /// Photons emitted.
    emitted: u64,
    /// Hit records of the photon map (after the virtual lights' filter).
    hit_records: u64,
    /// Emission sampling of the photon tracer.
    emission: EmissionSampling,
    /// The estimator settings of the splats.
    options: EstimatorOptions,
    /// Under `--support glossy-silverman` with `--diffuse texture`: the settings with equation 3's support on every surface, for the Lambertian lobes of glossy surfaces in their textures (a diffuse estimate keeps equation 3's support); `None` where `options` serve.
    lambertian_options: Option<EstimatorOptions>,
    /// Where the photons are.
    photons: Photons,
}

/// The photons of a render: traced into memory, or streamed from a file.
pub enum Photons {
    /// Traced now: the splats' estimator, and the Lambertian lobes' one where its settings differ.
    Memory {
        estimator: SplatEstimator,
        lambertian: Option<SplatEstimator>,
    },
    /// Read from `--photons-file` batch by batch.
    File(Box<StreamedPhotons>),
}

/// Particle tracing (section 2.1), or a photon file's tally, and the splat settings (section 2.2).
fn splat_setup(
    args: &RenderArgs,
    scene: &Scene,
    bvh: &Bvh,
    kernel: Kernel,
    virtual_depth: Option<u32>,
    beams: bool,
    timings: &mut serde_json::Map<String, serde_json::Value>,
) -> anyhow::Result<Splatting> {
    let selection = match args.technique {
        Technique::Splat => BounceSelection::All,
        Technique::SplatDirect
        | Technique::Mpr
        | Technique::Beams
        | Technique::Ibr
        | Technique::Composed => BounceSelection::Indirect,
        Technique::Detp | Technique::Impact | Technique::Photonmap => {
            bail!("--technique {:?} does not splat", args.technique)
        }
    };
    let options = EstimatorOptions {
        kernel,
        support: args.support_rule(),
        selection,
        edges: args.edges.into(),
    };
    let lambertian_options = match (args.support, args.diffuse) {
        (SupportArg::GlossySilverman, DiffuseArg::Texture) => Some(EstimatorOptions {
            support: Support::Scaled(args.kernel_c),
            ..options
        }),
        _ => None,
    };
    // Light that scatterers send onto the next surface is drawn by the
    // beams (Duvenhage et al. 2010, section 3.1), light that passed only
    // mirrors and slabs by the virtual lights (Diefenbach & Badler 1997,
    // sections 4.2, 6): the splats leave both out.
    let left_out = LeftOut::new(scene, beams, virtual_depth, args.pane_light())?;
    let start = Instant::now();
    if let Some(path) = &args.photons_file {
        let streamed = StreamedPhotons::open(
            path,
            scene,
            args.point_lights(),
            args.batch_records,
            &options,
            left_out,
        )?;
        timings.insert("tally".into(), json!(ms(start)));
        eprintln!(
            "{}: {} photons, {} hit records ({} indirect), read in batches of {} records",
            path.display(),
            streamed.emitted(),
            streamed.kept_records,
            streamed.indirect_records,
            args.batch_records
        );
        return Ok(Splatting {
            beam_hits: beams.then_some(streamed.beam_records),
            emitted: streamed.emitted(),
            hit_records: streamed.kept_records,
            emission: streamed.emission(),
            options,
            lambertian_options,
            photons: Photons::File(Box::new(streamed)),
        });
    }
    let trace_options = TraceOptions {
        photons: args.photons,
        seed: args.seed,
        emission: emission_of(args.emission),
        ..TraceOptions::default()
    };
    let bar = PhotonBar::new("tracing photons", args.photons)?;
    let map = trace_photons(scene, bvh, &trace_options, &bar)
        .with_context(|| format!("cannot trace photons in `{}`", scene.name))?;
    timings.insert("trace".into(), json!(ms(start)));
    let (map, beam_records) = left_out.apply(map)?;
    let beam_hits = beams.then_some(beam_records);
    eprintln!(
        "traced {} photons: {} hit records ({} indirect)",
        map.emitted(),
        map.len(),
        map.indirect().count()
    );

    // Preprocessing (section 2.2): one splat per selected hit, sized by equation 3.
    let start = Instant::now();
    let estimator =
        SplatEstimator::build(scene, &map, options).context("cannot build the splats")?;
    let lambertian = lambertian_options
        .map(|o| SplatEstimator::build(scene, &map, o))
        .transpose()
        .context("cannot build the splats of the Lambertian lobes")?;
    timings.insert("splat_setup".into(), json!(ms(start)));
    Ok(Splatting {
        beam_hits,
        emitted: map.emitted(),
        hit_records: map.len() as u64,
        emission: trace_options.emission,
        options,
        lambertian_options,
        photons: Photons::Memory {
            estimator,
            lambertian,
        },
    })
}

/// `out` with the extension `.json`.
pub fn sidecar_path(out: &Path) -> PathBuf {
    out.with_extension("json")
}

/// Writes the image as the extension of `--out` says, atomically.
fn write_outputs(args: &RenderArgs, image: &Image) -> anyhow::Result<()> {
    write_image(&args.out, args.exposure, image)
}

/// The linear EXR that `--term-images` writes `term` to beside `out`: `NAME-TERM.exr`.
pub fn term_image_path(out: &Path, term: TermArg) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
    out.with_file_name(format!("{stem}-{}.exr", term.name()))
}

/// Draws `camera` once per term of `--terms` with that term alone and writes each as [`term_image_path`]; returns the terms written with their files.
fn write_term_images(
    args: &RenderArgs,
    gpu: &mut GpuFrame,
    camera: &Camera,
) -> anyhow::Result<Vec<(TermArg, PathBuf)>> {
    let drawn = gpu.components;
    let mut written = Vec::new();
    for term in args.drawn_terms() {
        gpu.components = Components::only(&[term]);
        gpu.draw(camera, args.aa)?;
        let image = gpu.read_hdr()?;
        let path = term_image_path(&args.out, term);
        write_image(&path, args.exposure, &image)?;
        written.push((term, path));
    }
    gpu.components = drawn;
    Ok(written)
}

/// Writes an image atomically as the extension of `path` says: linear EXR, or sRGB PNG after `exposure` stops.
pub fn write_image(path: &Path, exposure: f32, image: &Image) -> anyhow::Result<()> {
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        lustre_image::write_exr(path, image, Precision::F32)
    } else {
        lustre_image::write_png(path, image, exposure)
    }
    .with_context(|| format!("cannot write {}", path.display()))
}
