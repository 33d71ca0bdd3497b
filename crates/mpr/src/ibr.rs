//! Glossy planar reflectors drawn from radiance maps in the frame (Bastos et
//! al. 1999, sections 8.1 and 8.2): `L = k_d D + k_s (M * K) R` at every
//! pixel of a reflector.
//!
//! **Capture (section 8.1.3).** Each sample camera of each reflector
//! ([`lustre_ibr::sampling`]) draws the frame graph's own frame, the scene's
//! real global illumination (direct light, diffuse textures, splats), from
//! its pinhole through the reflector element ([`View::from_pinhole`]),
//! everything behind the reflector's plane clipped and the emitters hidden
//! (see *Composition*). Its HDR image is read back as the map's radiance;
//! each texel's depth is the distance its ray travels to the first surface,
//! cast on the CPU's BVH through the texel centre the rasteriser sampled.
//! This departs from the paper in one way: the paper's maps hold the
//! view-independent radiosity D, ours the radiance the frame draws towards
//! the sample camera. A ray from the camera through element point `q` to a
//! scene point `x` is the ray along which `x` sends light to `q`, so a glossy
//! surface seen in a map shows the radiance it sends to the reflector
//! there, not only its diffuse part.
//!
//! **Per frame (sections 8.1.3, 8.2).** For each reflector the camera sees
//! from its front: the `k` maps per hemisphere nearest the mirrored eye
//! ([`lustre_ibr::select`]) are reprojected as sized points into the
//! mirrored view (M, [`crate::passes::radiance_map`]); M's depth is read
//! back for the kernel's radius ([`lustre_ibr::glossy::kernel_radius`],
//! the mean of `d/(e + d)` over M; with [`KernelSizing::ByDepth`] each
//! pixel's own, section 9's "more accurate method" that keeps contact
//! reflections sharp, but also shows the reconstruction's blocks there,
//! and measured worse on glosbox); `(M * K) R` is computed over M
//! and the reflector's void ([`crate::passes::glossy_reflection`]) and
//! `k_s` times it added at the reflector's pixels
//! ([`crate::passes::reflector_blend`]). The term is added once, through
//! the pixel centres, after a jittered accumulation (as splats drawn once
//! are), so the reflector's silhouette is not antialiased.
//!
//! **Bounces.** With [`IbrSettings::bounces`] 1 a reflector seen in
//! another's maps shows the frame's light without its glossy reflection
//! (its splats are dropped); each further capture pass draws the other
//! reflectors from the previous pass's maps (glosbox: the floor 3 % too
//! dark with one pass, within 0.3 % with two).
//!
//! **Magnitude of `R`.** The paper's K is `D G` normalised to unit sum and
//! its R is `F/(π cos² θ)` (equation 4's second factor), which leaves the
//! magnitude to `k_s`: with unit-sum K, `k_s (M * K) R` of a uniform
//! environment of radiance 1 is `k_s F/(π cos² θ)`, larger than one beyond
//! 56° for `k_s F = 1`, while the lobe reflects at most its albedo. So
//! [`Modulation::Albedo`] (the default) tabulates, under the same flipped
//! index, the glossy lobe's directional albedo `∫ f_s cos θ_l dω_l` over
//! `k_s` ([`crate::passes::glossy_lobe::glossy_albedo`]): the paper's R
//! times the integral that normalising K took out of it, which makes a
//! uniform environment come back at the lobe's albedo.
//! [`Modulation::Paper`] keeps equation 4's R with the lobe's Fresnel term.
//!
//! **Composition.** The frame already holds `k_d D` at the reflector (the
//! direct pass's light and the diffuse textures' Lambertian lobe) and the
//! highlight of the point lights through the reflector's glossy lobe (the
//! direct pass evaluates the full BRDF), so the maps hide the emitters, as
//! the glossy images of [`crate::passes::glossy_image`] do, and the
//! reflector's photon splats must be dropped by the caller
//! ([`crate::passes::splat::SplatBuffers::new_excluding_imaged`] with
//! [`IbrReflectors::surfaces`]).
//!
//! **Resolution (section 2).** With [`ReflectedResolution::FromGlossiness`]
//! M is drawn on a grid [`lustre_ibr::resolution::reflected_scale`] times
//! coarser than the frame, so its kernel spans about 8 of its pixels; the
//! kernel's radius is taken at the depth ratio of the reflector's last M
//! (per view size; on the first frame from a probe M on the coarsest grid
//! the lobe allows). The glossy pass reads the frame's surface ids at each
//! coarse pixel's centre and the blend reads the coarse term bilinearly
//! over its valid pixels. On `house` at 720 × 486 the floors' kernels span
//! tens of frame pixels: the convolution at the frame's resolution took
//! most of the frame on lavapipe (BENCHMARKS.md).
//!
//! **Geometry-based M.** [`ReflectedSource::Geometry`] captures no maps:
//! per frame and reflector the frame graph draws the scene again from the
//! mirrored view (clipped at the reflector's plane, emitters hidden), and
//! its HDR image and depth are M; the rest is the same. This is the
//! paper's comparison (section 9's graph, colour plates (a) and (b)): its
//! cost grows with the scene, the maps' with their resolution. Other
//! reflectors appear in it as the frame draws them, without their glossy
//! terms (one bounce). On glosbox at 128² it errs less than the maps
//! (relMSE 0.00234 against 0.00311): the gold box's grazing side is
//! covered, where the maps leave void; the floor is 2.5 % too dark for the
//! missing bounce.
//!
//! **Times.** [`IbrReflectors::take_times`] splits the frames' reflector
//! work into M, M's depth readback and the convolution and modulation (the
//! share the paper puts at 3 % at most), each stage waited for.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::{Vec3, Vec4};
use lustre_brdf::Fresnel;
use lustre_brdf::kernel_texture::KernelTexture;
use lustre_brdf::microfacet::{Distribution, Shadowing};
use lustre_brdf::reflectance_modulation::FlippedRadialReflectance;
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::{Bvh, Ray, Rgb, Scene, SurfaceKind};
use lustre_ibr::glossy::{kernel_radius, mean_depth_ratio, pixel_kernel};
use lustre_ibr::resolution::reflected_scale;
use lustre_ibr::{
    MemoryReport, PinholeView, QuadtreeSettings, RadianceMap, ReflectedImage, Reflector,
    ReflectorMaps, SampleCamera, SamplingSettings, SelectionRule, select,
};

use crate::frame::{FrameGraph, FrameInputs};
use crate::passes::glossy_lobe::{glossy_albedo, glossy_lobe};
use crate::passes::glossy_reflection::{Convolution, GlossyReflectionPass, SurfaceMask};
use crate::passes::radiance_map::{
    REFLECTED_NEAR, RadianceMapBuffers, RadianceMapPass, ReflectedTargets,
};
use crate::passes::reflector_blend::ReflectorBlendPass;
use crate::passes::splat_lowres::SplatResolution;
use crate::readback::{read_depth, read_rgba_f32};
use crate::target::RenderTargets;
use crate::view::{View, ViewBuffer};
use crate::{GpuContext, MprError, Result};

/// Entries of the flipped reflectance table (section 9).
pub const TABLE_ENTRIES: u32 = 128;

/// Texels per side of the kernel texture K (section 8.2.1).
pub const KERNEL_TEXELS: usize = 33;

/// How the reflectance modulation R is tabulated (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Modulation {
    /// The glossy lobe's directional albedo over `k_s`: a uniform environment reflects the lobe's albedo.
    #[default]
    Albedo,
    /// Equation 4's `F/(π cos² θ)`, the magnitude left to `k_s`.
    Paper,
}

/// How the kernel is sized over the reflected image (section 8.2.1, section 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KernelSizing {
    /// The paper's space-invariant kernel, its radius from the mean `d/(e + d)` over M.
    #[default]
    SpaceInvariant,
    /// Section 9's "more accurate method": each pixel's kernel from its own depth.
    ByDepth,
}

/// Where the reflected image M comes from (section 8.1; the paper's graph compares the two).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReflectedSource {
    /// The selected radiance maps reprojected as sized points (section 8.1.3).
    #[default]
    RadianceMaps,
    /// The frame drawn again from the mirrored view, the scene's full
    /// geometry (the multi-pass specular image, Diefenbach & Badler): no
    /// maps are captured, and the other reflectors appear in it as the frame
    /// draws them without their glossy terms.
    Geometry,
}

/// The reflected image's resolution (Bastos et al. 1999, section 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReflectedResolution {
    /// M, `M * K` and R at the frame's resolution.
    Frame,
    /// Chosen from the glossiness: M's pixels as wide as keeps the kernel's
    /// support [`lustre_ibr::resolution::REFLECTED_KERNEL_RADIUS`] pixels
    /// wide ([`lustre_ibr::resolution::reflected_scale`]), the term read
    /// back bilinearly at the frame's pixels.
    #[default]
    FromGlossiness,
}

/// How the reflectors are sampled, selected and shaded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IbrSettings {
    /// Reflector elements, cameras per hemisphere, map resolution (section 8.1.3).
    pub sampling: SamplingSettings,
    /// The maps' quadtrees.
    pub quadtree: QuadtreeSettings,
    /// Maps reprojected per hemisphere and frame.
    pub maps_per_hemisphere: usize,
    /// How the maps are chosen.
    pub selection: SelectionRule,
    /// How R is tabulated.
    pub modulation: Modulation,
    /// Capture passes: 1 draws the other reflectors in the maps without
    /// their reflections (the frame's splats of them are dropped); each
    /// further pass draws them from the previous pass's maps, one more
    /// reflection between reflectors.
    pub bounces: u32,
    /// How the kernel is sized.
    pub kernel: KernelSizing,
    /// Where M comes from.
    pub reflected: ReflectedSource,
    /// M's resolution.
    pub resolution: ReflectedResolution,
}

impl Default for IbrSettings {
    fn default() -> Self {
        Self {
            sampling: SamplingSettings {
                map_resolution: (96, 96),
                ..SamplingSettings::default()
            },
            quadtree: QuadtreeSettings::default(),
            maps_per_hemisphere: 2,
            selection: SelectionRule::MinimalAngle,
            modulation: Modulation::Albedo,
            bounces: 2,
            kernel: KernelSizing::SpaceInvariant,
            reflected: ReflectedSource::RadianceMaps,
            resolution: ReflectedResolution::FromGlossiness,
        }
    }
}

/// One reflector on the GPU: its maps, kernel, table and `k_s`.
#[derive(Debug)]
pub struct IbrReflector {
    /// The maps and quadtrees.
    pub maps: ReflectorMaps,
    buffers: RadianceMapBuffers,
    kernel: KernelTexture,
    table: FlippedRadialReflectance,
    ks: Vec3,
}

impl IbrReflector {
    /// `reflector` with its kernel, table and `k_s` from `model`'s glossy lobe, and no maps yet.
    fn new(
        ctx: &GpuContext,
        reflector: Reflector,
        model: &MaterialModel,
        settings: &IbrSettings,
    ) -> Result<Self> {
        let surface = reflector.surface;
        let lobe = glossy_lobe(model).ok_or_else(|| MprError::InvalidSetting {
            what: "radiance maps",
            message: format!("surface {surface} has no glossy lobe"),
        })?;
        let distribution =
            Distribution::new(MicrofacetDistribution::Beckmann, lobe.alpha, "reflector")?;
        let kernel = KernelTexture::new(&distribution, Shadowing::Smith, KERNEL_TEXELS)?;
        let ks = lobe.factor;
        let table = match settings.modulation {
            Modulation::Paper => {
                FlippedRadialReflectance::new(&lobe_fresnel(model), TABLE_ENTRIES)?
            }
            Modulation::Albedo => {
                let albedo = (0..TABLE_ENTRIES)
                    .map(|k| glossy_albedo(model, (k as f32 + 0.5) / TABLE_ENTRIES as f32))
                    .collect::<std::result::Result<Vec<_>, _>>()?;
                FlippedRadialReflectance::from_fn(TABLE_ENTRIES, |c| {
                    let k = ((c * TABLE_ENTRIES as f32 - 0.5).round() as usize)
                        .min(TABLE_ENTRIES as usize - 1);
                    albedo[k] / ks.max(Vec3::splat(1e-6))
                })?
            }
        };
        let maps =
            ReflectorMaps::from_maps(reflector, settings.sampling, Vec::new(), &settings.quadtree)?;
        let buffers = RadianceMapBuffers::upload(ctx, &maps)?;
        Ok(Self {
            maps,
            buffers,
            kernel,
            table,
            ks,
        })
    }
}

/// The per-frame textures of one size of M.
#[derive(Debug)]
struct FrameTextures {
    /// M: the reprojection's own targets, or with [`ReflectedSource::Geometry`] the mirrored frame's HDR and depth.
    reflected: ReflectedTargets,
    term: wgpu::Texture,
    /// [`ReflectedSource::Geometry`]'s mirrored frame.
    geometry: Option<OffscreenTargets>,
}

/// One reflector's M as [`IbrReflectors::add`] drew it.
struct Drawn {
    textures: Arc<FrameTextures>,
    /// The mirrored view on M's grid.
    view: PinholeView,
    /// M's depths (radiance left empty: it stays on the GPU).
    m: ReflectedImage,
    reflected_ms: f64,
    depth_readback_ms: f64,
}

/// The per-frame textures, made for one frame size (width, height, HDR format) and dropped when it changes.
#[derive(Debug, Default)]
struct TextureCache {
    frame: Option<(u32, u32, wgpu::TextureFormat)>,
    by_size: HashMap<(u32, u32), Arc<FrameTextures>>,
}

/// Off-screen targets a frame is drawn into from another view than the
/// camera's, with a tone-mapped output nobody reads: a sample camera's
/// capture, and the mirrored frame of [`ReflectedSource::Geometry`], whose
/// HDR and depth M reads.
#[derive(Debug)]
struct OffscreenTargets {
    targets: RenderTargets,
    output: wgpu::TextureView,
}

impl OffscreenTargets {
    fn new(
        ctx: &GpuContext,
        graph: &FrameGraph,
        (w, h): (u32, u32),
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        let targets = RenderTargets::with_hdr_format(ctx, w, h, hdr_format)?;
        let output = ctx.checked("off-screen frame output", || {
            crate::passes::radiance_map::texture_2d(
                ctx,
                "off-screen-output",
                w,
                h,
                graph.tonemap.output_format(),
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
        })?;
        Ok(Self {
            targets,
            output: output.create_view(&Default::default()),
        })
    }

    /// M as the glossy pass reads it: the mirrored frame's HDR radiance and reverse-Z depth (near [`REFLECTED_NEAR`]).
    fn reflected(&self) -> ReflectedTargets {
        ReflectedTargets {
            color: self.targets.hdr.texture.clone(),
            depth: self.targets.depth.texture.clone(),
        }
    }
}

/// Wall-clock milliseconds of [`IbrReflectors::add`]'s stages, summed over the reflectors and the frames since the last [`IbrReflectors::take_times`]; each stage waits for the GPU before it is timed, as the paper's graph splits a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct IbrTimes {
    /// M: the selected maps reprojected, or with [`ReflectedSource::Geometry`] the mirrored frame drawn.
    pub reflected_ms: f64,
    /// M's depth read back for the kernel's radius.
    pub depth_readback_ms: f64,
    /// The convolution with K, the modulation by R and the blend into the frame (section 8.2).
    pub convolution_modulation_ms: f64,
    /// The whole of [`IbrReflectors::add`]: the surface ids, every reflector and the tone map.
    pub total_ms: f64,
}

/// Milliseconds since `start`.
fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Every glossy planar reflector of a scene drawn from radiance maps (module documentation).
#[derive(Debug)]
pub struct IbrReflectors {
    reflectors: Vec<IbrReflector>,
    settings: IbrSettings,
    radiance_map: RadianceMapPass,
    glossy: GlossyReflectionPass,
    blend: ReflectorBlendPass,
    /// The frame's size and the textures of each size of M used at it.
    textures: Mutex<TextureCache>,
    /// Each reflector's mean `d/(e + d)` over its last M, by surface and
    /// view size: the next frame's M is as coarse as the kernel's radius it
    /// gives allows.
    ratio_hints: Mutex<HashMap<(u32, u32, u32), f32>>,
    times: Mutex<IbrTimes>,
}

/// The reflectors of `scene`: its planar surfaces whose material has a glossy lobe ([`glossy_lobe`]), with the lobe's model.
pub fn reflector_surfaces(scene: &Scene) -> Vec<(u32, MaterialModel)> {
    scene
        .surfaces()
        .iter()
        .enumerate()
        .filter_map(|(id, surface)| {
            let SurfaceKind::Planar(_) = surface.kind else {
                return None;
            };
            let material = scene.materials().get(surface.material as usize)?;
            glossy_lobe(&material.model)?;
            Some((id as u32, material.model.clone()))
        })
        .collect()
}

/// The Fresnel term of `model`'s glossy lobe for equation 4's R (a blend's glossy side; none is `F = 1`).
fn lobe_fresnel(model: &MaterialModel) -> Fresnel {
    match model {
        MaterialModel::RoughConductor {
            fresnel: ConductorFresnel::Complex { eta, k },
            ..
        } => Fresnel::Conductor { eta: *eta, k: *k },
        MaterialModel::Blend { first, second, .. } => {
            if glossy_lobe(second).is_some() {
                lobe_fresnel(second)
            } else {
                lobe_fresnel(first)
            }
        }
        _ => Fresnel::One,
    }
}

/// The view of sample camera `camera` for a `w × h` capture: its pinhole, everything on the far side of the reflector's plane from the scene clipped, emitters hidden.
pub fn capture_view(ctx: &GpuContext, camera: &SampleCamera, w: u32, h: u32) -> View {
    let pinhole = camera.pinhole(w, h);
    let e = &camera.element;
    // The scene lies along +normal from the element; keep n·p − n·c ≥ a hair.
    let offset = e.normal.dot(e.centre);
    let keep =
        Vec4::new(e.normal.x, e.normal.y, e.normal.z, -offset) - Vec4::W * (1e-4 * camera.height());
    let mut view = View::from_pinhole(&pinhole, 0.5 * camera.height())
        .with_clip_plane(keep, ctx.clip_method());
    view.shows_emitters = false;
    view
}

impl IbrReflectors {
    /// Captures the maps of every reflector of `scene` by drawing `frame`'s
    /// lighting through `graph` from each sample camera (module
    /// documentation); `bvh` gives the texels' depths; `progress(done,
    /// total)` after each map. `frame.targets` and `frame.output` are not
    /// touched. With [`ReflectedSource::Geometry`] nothing is captured.
    pub fn capture(
        ctx: &GpuContext,
        graph: &FrameGraph,
        frame: &FrameInputs<'_>,
        scene: &Scene,
        bvh: &Bvh,
        settings: &IbrSettings,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Self> {
        let mut this = Self::without_maps(ctx, scene, settings, frame.targets.hdr_format())?;
        if settings.reflected == ReflectedSource::Geometry {
            return Ok(this);
        }
        let (w, h) = settings.sampling.map_resolution;
        let capture = OffscreenTargets::new(ctx, graph, (w, h), frame.targets.hdr_format())?;
        let targets = &capture.targets;
        let inputs = FrameInputs {
            graph_terms: crate::frame::GraphTerms::ALL,
            targets,
            output: &capture.output,
            splats: frame.splats.map(|s| crate::frame::SplatInputs {
                resolution: SplatResolution::Full,
                ..s
            }),
            ..*frame
        };
        // Every reflector has as many maps as the sampling gives one: its count times the reflectors and passes.
        let passes = this.reflectors.len() * settings.bounces as usize;
        let mut done = 0;
        for bounce in 0..settings.bounces {
            let mut captured = Vec::with_capacity(this.reflectors.len());
            for reflector in &this.reflectors {
                captured.push(ReflectorMaps::capture_with(
                    &reflector.maps.reflector,
                    &settings.sampling,
                    &settings.quadtree,
                    &mut |camera: &SampleCamera| -> Result<RadianceMap> {
                        let view = capture_view(ctx, camera, w, h);
                        graph.render_view(ctx, &inputs, view)?;
                        if bounce > 0 {
                            // The other reflectors as the frame draws them, from the last bounce's maps.
                            this.add_from(ctx, &inputs, graph, view, &camera.pinhole(w, h))?;
                        }
                        let hdr = read_rgba_f32(ctx, &targets.hdr.texture)?;
                        Ok(RadianceMap::capture_texels(camera, w, h, &|k, q, dir| {
                            let hit =
                                bvh.closest_hit(&Ray::segment(q, dir, 1e-4, f32::INFINITY))?;
                            let c = hdr[k];
                            Some((Rgb::new(c[0], c[1], c[2]), hit.t))
                        }))
                    },
                    &mut |_, per_reflector| {
                        done += 1;
                        progress(done, per_reflector * passes);
                    },
                )?);
            }
            for (reflector, maps) in this.reflectors.iter_mut().zip(captured) {
                reflector.buffers = RadianceMapBuffers::upload(ctx, &maps)?;
                reflector.maps = maps;
            }
        }
        // The later passes' reflectors drawn into the maps are not frames.
        this.take_times();
        Ok(this)
    }

    /// Every reflector of `scene` with its kernel, table and `k_s`, and no
    /// maps: what [`ReflectedSource::Geometry`] draws from (no capture, no
    /// BVH), and what [`IbrReflectors::capture`] and
    /// [`IbrReflectors::from_maps`] fill; `hdr_format` is the frame's HDR
    /// target's.
    pub fn without_maps(
        ctx: &GpuContext,
        scene: &Scene,
        settings: &IbrSettings,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        if settings.bounces == 0 {
            return Err(MprError::InvalidSetting {
                what: "radiance maps",
                message: "at least one capture pass is needed".into(),
            });
        }
        if settings.maps_per_hemisphere == 0 {
            return Err(MprError::InvalidSetting {
                what: "radiance maps",
                message: "at least one map per hemisphere must be reprojected".into(),
            });
        }
        settings.sampling.validate()?;
        settings.quadtree.validate()?;
        let mut reflectors = Vec::new();
        for (surface, model) in reflector_surfaces(scene) {
            let reflector = Reflector::from_surface(scene, surface)?;
            reflectors.push(IbrReflector::new(ctx, reflector, &model, settings)?);
        }
        Ok(Self {
            reflectors,
            settings: *settings,
            radiance_map: RadianceMapPass::new(ctx)?,
            glossy: GlossyReflectionPass::new(ctx)?,
            blend: ReflectorBlendPass::new(ctx, hdr_format)?,
            textures: Mutex::new(TextureCache::default()),
            ratio_hints: Mutex::new(HashMap::new()),
            times: Mutex::new(IbrTimes::default()),
        })
    }

    /// The reflectors of `scene` drawn from `maps`, captured before (a
    /// [`lustre_ibr::cache`] file) under `settings`: one per reflector of
    /// `scene`, in order, each on the same surface and plane and sampled as
    /// `settings.sampling` says, else [`MprError::InvalidSetting`]; `frame`
    /// as [`IbrReflectors::capture`] takes it.
    pub fn from_maps(
        ctx: &GpuContext,
        frame: &FrameInputs<'_>,
        scene: &Scene,
        settings: &IbrSettings,
        maps: Vec<ReflectorMaps>,
    ) -> Result<Self> {
        let mut this = Self::without_maps(ctx, scene, settings, frame.targets.hdr_format())?;
        let mismatch = |message: String| MprError::InvalidSetting {
            what: "radiance maps",
            message,
        };
        if maps.len() != this.reflectors.len() {
            return Err(mismatch(format!(
                "{} reflectors' maps for a scene with {} reflectors",
                maps.len(),
                this.reflectors.len()
            )));
        }
        for (reflector, maps) in this.reflectors.iter_mut().zip(maps) {
            let (want, got) = (&reflector.maps.reflector, &maps.reflector);
            if want.surface != got.surface || want.plane != got.plane {
                return Err(mismatch(format!(
                    "maps of surface {} where the scene's reflector is surface {}",
                    got.surface, want.surface
                )));
            }
            if maps.sampling != settings.sampling {
                return Err(mismatch(format!(
                    "surface {}'s maps were sampled as {:?}, not as {:?}",
                    got.surface, maps.sampling, settings.sampling
                )));
            }
            reflector.buffers = RadianceMapBuffers::upload(ctx, &maps)?;
            reflector.maps = maps;
        }
        Ok(this)
    }

    /// Every reflector's maps, to write to a [`lustre_ibr::cache`] file.
    pub fn maps(&self) -> impl ExactSizeIterator<Item = &ReflectorMaps> {
        self.reflectors.iter().map(|r| &r.maps)
    }

    /// The reflectors' surface ids, true at each (the surfaces whose photon splats the caller drops).
    pub fn surfaces(scene: &Scene) -> Vec<bool> {
        let mut out = vec![false; scene.surfaces().len()];
        for (surface, _) in reflector_surfaces(scene) {
            out[surface as usize] = true;
        }
        out
    }

    /// The reflectors.
    pub fn reflectors(&self) -> &[IbrReflector] {
        &self.reflectors
    }

    /// The memory of each reflector's maps (the paper's table 1).
    pub fn memory(&self) -> Vec<MemoryReport> {
        self.reflectors.iter().map(|r| r.maps.memory()).collect()
    }

    /// The stage times of the frames added since the last call, and a fresh start.
    pub fn take_times(&self) -> IbrTimes {
        std::mem::take(&mut *self.times.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// Adds `f(times)` to the running stage times.
    fn time(&self, f: impl FnOnce(&mut IbrTimes)) {
        f(&mut self.times.lock().unwrap_or_else(|e| e.into_inner()));
    }

    /// The settings the maps were captured and are drawn with.
    pub fn settings(&self) -> &IbrSettings {
        &self.settings
    }

    /// Adds `k_s (M * K) R` of every reflector seen from `frame.camera` into
    /// the frame that `graph` left in `frame.targets`' HDR target, and tone
    /// maps the sum to `frame.output` (module documentation). The surface
    /// ids are drawn again through the pixel centres first, so a jittered
    /// accumulation's last sample does not shift the reflectors' masks.
    pub fn add(&self, ctx: &GpuContext, graph: &FrameGraph, frame: &FrameInputs<'_>) -> Result<()> {
        let start = Instant::now();
        let (w, h) = (frame.targets.width, frame.targets.height);
        self.add_from(
            ctx,
            frame,
            graph,
            View::from_camera(frame.camera),
            &PinholeView::from_camera(frame.camera, w, h),
        )?;
        ctx.checked_result("radiance-map tone map", || {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            graph.tonemap.encode(
                &ctx.device,
                &mut encoder,
                &frame.targets.hdr.view,
                frame.output,
            );
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })?;
        ctx.wait()?;
        self.time(|t| t.total_ms += ms_since(start));
        Ok(())
    }

    /// [`IbrReflectors::add`] seen from `view`, whose pinhole is `pinhole`, without the tone map: the surface ids drawn again under `view`, then every reflector's term.
    fn add_from(
        &self,
        ctx: &GpuContext,
        frame: &FrameInputs<'_>,
        graph: &FrameGraph,
        view: View,
        pinhole: &PinholeView,
    ) -> Result<()> {
        let targets = frame.targets;
        let (views, slot) = ViewBuffer::for_view(ctx, view)?;
        ctx.checked_result("radiance-map surface ids", || {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            graph
                .depth
                .encode(&mut encoder, frame.scene, targets, &views, slot, true);
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })?;
        let geometry = self.settings.reflected == ReflectedSource::Geometry;
        for reflector in &self.reflectors {
            if !reflector.maps.maps.is_empty() || geometry {
                self.add_reflector(ctx, graph, frame, reflector, pinhole)?;
            }
        }
        Ok(())
    }

    /// The textures for an M of `size` in a frame like `targets`, made on first use.
    fn textures(
        &self,
        ctx: &GpuContext,
        graph: &FrameGraph,
        targets: &RenderTargets,
        size: (u32, u32),
    ) -> Result<Arc<FrameTextures>> {
        let mut cache = self.textures.lock().unwrap_or_else(|e| e.into_inner());
        let frame = (targets.width, targets.height, targets.hdr_format());
        if cache.frame != Some(frame) {
            *cache = TextureCache {
                frame: Some(frame),
                by_size: HashMap::new(),
            };
        }
        if let Some(textures) = cache.by_size.get(&size) {
            return Ok(Arc::clone(textures));
        }
        let (reflected, geometry) = match self.settings.reflected {
            ReflectedSource::RadianceMaps => (ReflectedTargets::new(ctx, size.0, size.1)?, None),
            ReflectedSource::Geometry => {
                let geometry = OffscreenTargets::new(ctx, graph, size, targets.hdr_format())?;
                (geometry.reflected(), Some(geometry))
            }
        };
        let textures = Arc::new(FrameTextures {
            reflected,
            term: GlossyReflectionPass::output(ctx, size.0, size.1)?,
            geometry,
        });
        cache.by_size.insert(size, Arc::clone(&textures));
        Ok(textures)
    }

    /// M of `reflector` seen from `eye` on a grid `scale` times coarser than the frame: the selected maps reprojected, or the mirrored frame drawn ([`ReflectedSource`]), and its depth read back.
    fn draw_reflected(
        &self,
        ctx: &GpuContext,
        graph: &FrameGraph,
        frame: &FrameInputs<'_>,
        reflector: &IbrReflector,
        eye: &PinholeView,
        scale: u32,
    ) -> Result<Drawn> {
        let plane = reflector.maps.reflector.plane;
        let view = eye.reflected(&plane).coarsened(scale);
        let (w, h) = (view.width, view.height);
        let textures = self.textures(ctx, graph, frame.targets, (w, h))?;
        let start = Instant::now();
        match &textures.geometry {
            Some(geometry) => {
                // The scene lies along +normal; keep n·p − offset ≥ a hair, as View::reflected does.
                let hair = 1e-4 * plane.signed_distance(eye.eye);
                let keep = plane.normal.extend(-plane.offset) - Vec4::W * hair;
                let mut mirrored = View::from_pinhole(&view, REFLECTED_NEAR)
                    .with_clip_plane(keep, ctx.clip_method());
                mirrored.shows_emitters = false;
                let inputs = FrameInputs {
                    graph_terms: crate::frame::GraphTerms::ALL,
                    targets: &geometry.targets,
                    output: &geometry.output,
                    ..*frame
                };
                graph.render_view(ctx, &inputs, mirrored)?;
            }
            None => {
                let selected = select(
                    &reflector.maps.cameras(),
                    view.eye,
                    self.settings.maps_per_hemisphere,
                    self.settings.selection,
                );
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                self.radiance_map.encode(
                    ctx,
                    &mut encoder,
                    &reflector.maps,
                    &reflector.buffers,
                    &selected,
                    &view,
                    &textures.reflected,
                )?;
                ctx.queue.submit([encoder.finish()]);
            }
        }
        ctx.wait()?;
        let reflected_ms = ms_since(start);
        // The kernel's radius from M's depths (reverse Z: near / z).
        let start = Instant::now();
        let depth = read_depth(ctx, &textures.reflected.depth)?;
        let depth_readback_ms = ms_since(start);
        let mut m = ReflectedImage::new(w, h);
        for (out, z) in m.depth.iter_mut().zip(&depth) {
            if *z > 0.0 {
                *out = REFLECTED_NEAR / z;
            }
        }
        Ok(Drawn {
            textures,
            view,
            m,
            reflected_ms,
            depth_readback_ms,
        })
    }

    /// M, `(M * K) R` and the blend of one reflector.
    fn add_reflector(
        &self,
        ctx: &GpuContext,
        graph: &FrameGraph,
        frame: &FrameInputs<'_>,
        reflector: &IbrReflector,
        eye: &PinholeView,
    ) -> Result<()> {
        let targets = frame.targets;
        let plane = reflector.maps.reflector.plane;
        // The reflector's front faces the scene: an eye behind it sees no reflection.
        if plane.signed_distance(eye.eye) <= 1e-6 {
            return Ok(());
        }
        // The mirrored view keeps the eye's pixels and focal length.
        let widest = eye.focal.y * reflector.kernel.half_angle.tan();
        let surface = reflector.maps.reflector.surface;
        // Hints are per view size: the capture's sample cameras (map-sized) and the camera's frames apart.
        let hint_key = (surface, eye.width, eye.height);
        let hint = self
            .ratio_hints
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&hint_key)
            .copied();
        let (drawn, scale) = match (self.settings.resolution, hint) {
            (ReflectedResolution::Frame, _) => (None, 1),
            (ReflectedResolution::FromGlossiness, Some(ratio)) => {
                (None, reflected_scale(widest * ratio))
            }
            (ReflectedResolution::FromGlossiness, None) => {
                // No earlier frame: M probed at the coarsest grid the lobe allows for the kernel's radius.
                let probe_scale = reflected_scale(widest);
                let probe = self.draw_reflected(ctx, graph, frame, reflector, eye, probe_scale)?;
                let ratio = mean_depth_ratio(&probe.m, &probe.view, &plane);
                let scale = reflected_scale(widest * ratio);
                (Some(probe).filter(|_| scale == probe_scale), scale)
            }
        };
        let drawn = match drawn {
            Some(drawn) => drawn,
            None => self.draw_reflected(ctx, graph, frame, reflector, eye, scale)?,
        };
        let Drawn {
            textures,
            view,
            m,
            reflected_ms,
            depth_readback_ms,
        } = drawn;
        let start = Instant::now();
        let mean_ratio = mean_depth_ratio(&m, &view, &plane);
        if mean_ratio > 0.0 {
            self.ratio_hints
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(hint_key, mean_ratio);
        }
        let taps = match self.settings.kernel {
            KernelSizing::SpaceInvariant => pixel_kernel(
                &reflector.kernel,
                kernel_radius(&m, &view, &plane, reflector.kernel.half_angle),
            ),
            KernelSizing::ByDepth => Vec::new(),
        };
        let convolution = match self.settings.kernel {
            KernelSizing::SpaceInvariant => Convolution::SpaceInvariant(&taps),
            KernelSizing::ByDepth => Convolution::ByDepth {
                kernel: &reflector.kernel,
                mean_ratio,
            },
        };
        ctx.checked_result("radiance-map glossy term", || {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            self.glossy.encode(
                ctx,
                &mut encoder,
                &textures.reflected,
                &view,
                &plane,
                convolution,
                &reflector.table,
                Some(SurfaceMask {
                    ids: &targets.surface_id.texture,
                    surface: reflector.maps.reflector.surface,
                    scale,
                }),
                &textures.term,
            )?;
            self.blend.encode(
                ctx,
                &mut encoder,
                targets,
                &textures.term,
                reflector.maps.reflector.surface,
                reflector.ks,
                scale,
            )?;
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })?;
        ctx.wait()?;
        self.time(|t| {
            t.reflected_ms += reflected_ms;
            t.depth_readback_ms += depth_readback_ms;
            t.convolution_modulation_ms += ms_since(start);
        });
        Ok(())
    }
}
