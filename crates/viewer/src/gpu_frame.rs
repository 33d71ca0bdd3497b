//! The GPU state of one lit scene and the frame drawn from it: the one code path of `lustre render` and `lustre view` (DESIGN.md "Data flow", steps 3 and 4).
//!
//! [`GpuFrame::new`] uploads what the lighting phase computed (splats, diffuse
//! textures, direct lights, beams, per-vertex radiance) and builds the frame
//! graph once; [`GpuFrame::draw`] renders one camera into the HDR target and
//! the sRGB output, so a walkthrough, a headless render and the window draw
//! every frame through the same calls.

use anyhow::Context;
use glam::Vec2;
use lustre_beams::BeamSet;
use lustre_geometry::light::{jittered_point_lights, paired_rotation, pivot_point_lights};
use lustre_geometry::{Bvh, Camera, Light, Scene};
use lustre_image::Image;
use lustre_mpr::diffuse_map::DiffuseMaps;
use lustre_mpr::frame::{AccumulatedSplats, SplatInputs};
use lustre_mpr::ibr::{IbrReflectors, ReflectedSource};
use lustre_mpr::material::GlossyModel;
use lustre_mpr::pass_timing::PassTimes;
use lustre_mpr::passes::diffuse_texture::{DiffuseAtlas, DiffuseTextures};
use lustre_mpr::passes::direct::DirectLights;
use lustre_mpr::passes::glossy_image::{GlossySettings, imaged_surfaces};
use lustre_mpr::passes::gouraud::corner_layers;
use lustre_mpr::passes::shadowed_direct::{ShadowVolumes, VolumeJitter};
use lustre_mpr::passes::specular::{SpecularSettings, mean_radiance};
use lustre_mpr::passes::splat::{KernelFiltering, Restriction, SplatBuffers};
use lustre_mpr::passes::splat_lowres::SplatResolution;
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::virtual_light::VirtualLightSettings;
use lustre_mpr::{FrameGraph, FrameInputs, GpuContext, GraphTerms, RenderTargets, SceneBuffers};
use lustre_photon::{Kernel, SplatEstimator};

use crate::render::{
    FilterArg, GlossyArg, RenderArgs, RestrictionArg, ShadowArg, SplatResolutionArg, Technique,
    TermArg, VolumeJitterArg, ibr_settings,
};
use crate::render_density::tinted_at_vertices;

/// The format of the tone-mapped output every frame is drawn into.
pub const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// What the lighting phase hands to the GPU.
pub struct Lighting<'a> {
    /// The scene as lit (point lights, per-vertex meshing applied).
    pub scene: &'a Scene,
    /// The splats' estimator of photons traced into memory.
    pub splats: Option<&'a SplatEstimator>,
    /// Splatting of any kind (in memory or streamed): the splat pass is built.
    pub splatting: bool,
    /// Per-corner radiance of a per-vertex technique, drawn with Gouraud interpolation.
    pub corners: Option<&'a [[f32; 3]]>,
    /// The diffuse textures' atlas (Stürzlinger & Bastos section 2.2.1).
    pub atlas: Option<&'a DiffuseAtlas>,
    /// Duvenhage et al.'s beams.
    pub beams: Option<&'a BeamSet>,
    /// Virtual light generations (Diefenbach & Badler section 4.2).
    pub shadow_depth: u32,
    /// Glossy images of the planar glossy faces (Diefenbach & Badler section 3).
    pub glossy_images: GlossySettings,
    /// The splats' reconstruction kernel.
    pub kernel: Kernel,
}

/// Which lighting terms a frame draws (the window's switches, `--terms`; a render draws all).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Components {
    /// The emitters' own radiance (and the specular recursion's limit faces).
    pub emission: bool,
    /// Direct light from the point lights with shadow maps or volumes.
    pub direct: bool,
    /// The Lambertian lobes from the diffuse textures (Stürzlinger & Bastos section 2.2.1).
    pub diffuse: bool,
    /// The splats of the photon hits (section 2.2).
    pub splats: bool,
    /// The reflectors' `k_s (M * K) R` from radiance maps (Bastos et al. 1999).
    pub radiance_maps: bool,
    /// The beams (Duvenhage et al. 2010).
    pub beams: bool,
}

impl Default for Components {
    fn default() -> Self {
        Self::only(TermArg::all())
    }
}

impl Components {
    /// The components of `terms`: the glossy term is the splats with the radiance maps, the caustics the beams.
    pub fn only(terms: &[TermArg]) -> Self {
        let has = |t| terms.contains(&t);
        Self {
            emission: has(TermArg::Emission),
            direct: has(TermArg::Direct),
            diffuse: has(TermArg::Diffuse),
            splats: has(TermArg::Glossy),
            radiance_maps: has(TermArg::Glossy),
            beams: has(TermArg::Caustics),
        }
    }
}

/// The uploaded scene, lighting and frame graph of one render, and its targets.
pub struct GpuFrame {
    /// The device.
    pub ctx: GpuContext,
    /// The frame graph.
    pub graph: FrameGraph,
    /// HDR, depth and id targets at the frame's size.
    pub targets: RenderTargets,
    /// The scene's vertex and index buffers.
    pub scene_buffers: SceneBuffers,
    /// The splats of photons traced into memory.
    pub splats: Option<SplatBuffers>,
    /// The scene's diffuse maps, uploaded once and shared by every pass that reads them (and each batch of streamed splats).
    pub maps: DiffuseMaps,
    /// The direct pass's point lights.
    pub direct: Option<DirectLights>,
    /// The diffuse textures.
    pub diffuse_textures: Option<DiffuseTextures>,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    tonemap: Tonemap,
    /// How splats keep to their surface.
    pub restriction: Restriction,
    /// How the kernel texture is read.
    pub filtering: KernelFiltering,
    /// The resolution the view's splats are drawn at (`None` without splats in memory).
    pub splat_resolution: Option<SplatResolution>,
    /// Glossy BRDFs on the GPU.
    pub glossy: GlossyModel,
    /// Surfaces drawn by glossy images (their splats dropped).
    pub imaged: Vec<bool>,
    /// Surfaces whose Lambertian lobes come from the textures.
    pub exclude: Vec<bool>,
    /// The glossy images' settings with the scene's mean radiance as fog.
    pub glossy_images: GlossySettings,
    /// Shadows by volumes (else shadow maps).
    pub shadow_volumes: bool,
    /// A different set of jittered light positions per accumulation sample.
    pub paired: bool,
    lights: Vec<Light>,
    light_samples: u32,
    aa_splats: bool,
    /// The lighting terms drawn.
    pub components: Components,
    /// The glossy reflectors drawn from radiance maps (`--technique ibr`, Bastos et al. 1999).
    pub ibr: Option<IbrReflectors>,
    /// Milliseconds the radiance maps took to capture (or to read from `--ibr-cache`).
    pub ibr_capture_ms: f64,
    /// Whether the radiance maps came from `--ibr-cache`.
    pub ibr_cached: bool,
}

impl GpuFrame {
    /// Uploads the lighting and builds the frame graph for `args`' technique at `width` × `height`; `camera` (the first frame's) chooses the splats' `auto` resolution.
    pub fn new(
        args: &RenderArgs,
        lighting: Lighting<'_>,
        ctx: GpuContext,
        (width, height): (u32, u32),
        camera: &Camera,
    ) -> anyhow::Result<Self> {
        let scene = lighting.scene;
        let glossy = match args.glossy {
            GlossyArg::Exact => GlossyModel::Exact,
            GlossyArg::FittedPhong => GlossyModel::FittedPhong,
        };
        let targets = RenderTargets::new(&ctx, width, height)?;
        let scene_buffers = SceneBuffers::upload(&ctx, scene)?;
        let exclude = lighting
            .atlas
            .map(DiffuseAtlas::textured)
            .unwrap_or_default();
        let glossy_images = GlossySettings {
            fog_radiance: mean_radiance(scene),
            ..lighting.glossy_images
        };
        // Surfaces whose glossy lobes are drawn as images or from radiance maps, not splatted.
        let mut imaged = imaged_surfaces(scene, &glossy_images);
        if args.draws_radiance_maps() {
            for (i, reflector) in IbrReflectors::surfaces(scene).into_iter().enumerate() {
                imaged[i] |= reflector;
            }
        }
        // The scene's diffuse texture maps, uploaded once for every pass that draws them.
        let maps = DiffuseMaps::upload(&ctx, scene)?;
        // Streamed photons are splatted batch by batch after the frame.
        let splats = match lighting.splats {
            Some(estimator) => Some(
                SplatBuffers::new_excluding_imaged(
                    &ctx, scene, estimator, glossy, &exclude, &imaged, &maps,
                )
                .with_context(|| format!("scene `{}`", scene.name))?,
            ),
            None => None,
        };
        let mut graph = FrameGraph::new(&ctx, OUTPUT_FORMAT)?
            .with_pass_timing(&ctx)
            .with_emission(&ctx, targets.hdr_format(), scene)?
            .with_emission_samples(args.emission_samples);
        if lighting.splatting {
            graph = graph.with_splats(&ctx, targets.hdr_format(), lighting.kernel)?;
        }
        if let Some(corners) = lighting.corners {
            graph = graph.with_gouraud(&ctx, targets.hdr_format(), &scene_buffers)?;
            graph.set_gouraud_radiance(&ctx, corners)?;
            if maps.is_textured() {
                let tinted = tinted_at_vertices(scene, args.glossy_estimate);
                let layers = corner_layers(scene, &maps, &tinted);
                graph.set_gouraud_diffuse_maps(&ctx, &maps, &layers)?;
            }
        }
        let diffuse_textures = match lighting.atlas {
            Some(atlas) => {
                graph = graph.with_diffuse_textures(&ctx, targets.hdr_format())?;
                let pass = graph.diffuse.as_ref().context("diffuse texture pass")?;
                Some(DiffuseTextures::with_maps(&ctx, pass, atlas, &maps)?)
            }
            None => None,
        };
        let shadow_volumes = args.technique.multipass() && args.shadows == ShadowArg::Volumes;
        // Paired light jitter: a different set of light positions per accumulation sample.
        let paired = args.aa > 1
            && args.light_samples > 1
            && args.paired_lights
            && scene.lights().iter().any(|l| !l.is_delta());
        let direct = if args.technique.direct_light() {
            graph = graph.with_direct(&ctx, targets.hdr_format())?;
            let pass = graph.direct.as_ref().context("direct pass")?;
            let lights = DirectLights::jittered_with_maps(
                &ctx,
                pass,
                scene,
                glossy,
                args.light_samples,
                maps.clone(),
            )
            .with_context(|| format!("scene `{}`", scene.name))?;
            if shadow_volumes {
                graph = graph.with_shadow_volumes(
                    &ctx,
                    targets.hdr_format(),
                    scene,
                    &pivot_point_lights(scene.lights(), args.light_samples),
                )?;
                if lighting.shadow_depth > 0 {
                    graph = graph.with_virtual_lights(
                        &ctx,
                        scene,
                        VirtualLightSettings {
                            depth: lighting.shadow_depth,
                            shadows: args.spec_shadows.setting(),
                            panes: args.pane_light(),
                        },
                    )?;
                }
                let sets = sample_light_sets(scene.lights(), args.light_samples, args.aa, paired);
                let store = match args.jittered_volumes {
                    VolumeJitterArg::Pivot => false,
                    VolumeJitterArg::Stored => true,
                    VolumeJitterArg::Auto => graph
                        .shadow_volumes
                        .as_ref()
                        .is_some_and(|v| stored_volume_bytes(v, &sets) <= STORED_VOLUME_BUDGET),
                };
                if store {
                    graph.store_jittered_volumes(&ctx, scene, &sets)?;
                }
            } else {
                graph.update_shadows(&ctx, &scene_buffers, &lights)?;
            }
            Some(lights)
        } else {
            None
        };
        if let Some(set) = lighting.beams {
            graph = graph.with_beams(
                &ctx,
                targets.hdr_format(),
                scene,
                glossy,
                &maps,
                set,
                args.beam_traversal.into(),
            )?;
        }
        if args.technique.multipass() {
            graph = graph.with_glossy_images(
                &ctx,
                targets.hdr_format(),
                scene,
                SpecularSettings {
                    max_depth: args.spec_depth,
                    limit_radiance: mean_radiance(scene),
                    clip: None,
                },
                &glossy_images,
            )?;
        }
        if args.aa > 1 || (lighting.splatting && lighting.splats.is_none()) {
            graph = graph.with_accumulation(&ctx, targets.hdr_format())?;
        }
        let (output, output_view) = output_texture(&ctx, width, height);
        let restriction = match args.restriction {
            RestrictionArg::SurfaceId => Restriction::SurfaceId,
            RestrictionArg::Stencil => Restriction::Stencil,
        };
        let filtering = match args.filter {
            FilterArg::Centre => KernelFiltering::PixelCentre,
            FilterArg::Mip => KernelFiltering::MipMapped,
        };
        let splat_resolution = splats
            .as_ref()
            .map(|b| resolve_resolution(args, restriction, &b.supports, camera, height));
        Self {
            ctx,
            graph,
            targets,
            scene_buffers,
            splats,
            maps,
            direct,
            diffuse_textures,
            output,
            output_view,
            tonemap: Tonemap::default(),
            restriction,
            filtering,
            splat_resolution,
            glossy,
            imaged,
            exclude,
            glossy_images,
            shadow_volumes,
            paired,
            lights: scene.lights().to_vec(),
            light_samples: args.light_samples,
            aa_splats: args.aa_splats,
            components: Components::default(),
            ibr: None,
            ibr_capture_ms: 0.0,
            ibr_cached: false,
        }
        .with_radiance_maps(args, scene, camera)
    }

    /// With radiance maps (`--technique ibr`, `composed`), the maps of every glossy planar
    /// reflector captured from this frame's lighting (Bastos et al. 1999,
    /// section 8.1.3), with a progress bar on a terminal.
    fn with_radiance_maps(
        mut self,
        args: &RenderArgs,
        scene: &Scene,
        camera: &Camera,
    ) -> anyhow::Result<Self> {
        if !args.draws_radiance_maps() {
            return Ok(self);
        }
        let inputs = self.inputs(camera);
        if lustre_mpr::ibr::reflector_surfaces(scene).is_empty() {
            if args.technique != Technique::Ibr {
                return Ok(self);
            }
            eprintln!(
                "--technique ibr: scene `{}` has no planar glossy surface; every surface is drawn as splat-direct draws it",
                scene.name
            );
            return Ok(self);
        }
        let start = std::time::Instant::now();
        let settings = ibr_settings(args);
        if settings.reflected == ReflectedSource::Geometry {
            // M is drawn from the scene every frame: nothing to capture or cache.
            self.ibr = Some(IbrReflectors::without_maps(
                &self.ctx,
                scene,
                &settings,
                inputs.targets.hdr_format(),
            )?);
            self.ibr_capture_ms = start.elapsed().as_secs_f64() * 1e3;
            return Ok(self);
        }
        let cache = args
            .ibr_cache
            .as_deref()
            .map(|path| (path, crate::ibr_cache::key(args, scene)));
        if let Some((path, key)) = cache.filter(|(path, _)| path.exists()) {
            let cached = lustre_ibr::cache::read(path, key, &settings.quadtree)
                .map_err(anyhow::Error::from)
                .and_then(|maps| {
                    Ok(IbrReflectors::from_maps(
                        &self.ctx, &inputs, scene, &settings, maps,
                    )?)
                });
            match cached {
                Ok(ibr) => {
                    self.ibr = Some(ibr);
                    self.ibr_cached = true;
                    self.ibr_capture_ms = start.elapsed().as_secs_f64() * 1e3;
                    return Ok(self);
                }
                Err(e) => eprintln!("{e:#}; capturing the radiance maps again"),
            }
        }
        let bvh = Bvh::build(scene);
        let bar = indicatif::ProgressBar::new(0).with_style(
            indicatif::ProgressStyle::with_template(
                "capturing radiance maps {bar:40} {pos}/{len} ({eta} left)",
            )
            .context("progress bar template")?,
        );
        let ibr = IbrReflectors::capture(
            &self.ctx,
            &self.graph,
            &inputs,
            scene,
            &bvh,
            &settings,
            &mut |done, total| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            },
        )
        .with_context(|| format!("radiance maps of scene `{}`", scene.name))?;
        bar.finish_and_clear();
        if let Some((path, key)) = cache {
            lustre_ibr::cache::write(path, key, ibr.maps())
                .with_context(|| format!("--ibr-cache {}", path.display()))?;
        }
        self.ibr = Some(ibr);
        self.ibr_capture_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(self)
    }

    /// The mobile objects moved (a quasi-static frame, García et al. 2003,
    /// section 2): `scene`'s pose uploaded and the per-vertex radiance
    /// `corners` drawn from now on. The triangles must be those the frame was
    /// built with, moved; a frame without the Gouraud pass refuses
    /// ([`FrameGraph::set_gouraud_radiance`]).
    pub fn set_pose(&mut self, scene: &Scene, corners: &[[f32; 3]]) -> anyhow::Result<()> {
        self.graph.set_gouraud_radiance(&self.ctx, corners)?;
        self.scene_buffers = SceneBuffers::upload(&self.ctx, scene)?;
        if let Some(emission) = self.graph.emission.as_mut() {
            emission.set_emitters(scene);
        }
        Ok(())
    }

    /// The frame's inputs for `camera`, drawn into the sRGB output.
    pub fn inputs<'a>(&'a self, camera: &'a Camera) -> FrameInputs<'a> {
        FrameInputs {
            graph_terms: GraphTerms {
                emission: self.components.emission,
                beams: self.components.beams,
            },
            scene: &self.scene_buffers,
            camera,
            tonemap: &self.tonemap,
            targets: &self.targets,
            output: &self.output_view,
            splats: self
                .splats
                .as_ref()
                .filter(|_| self.components.splats)
                .map(|buffers| SplatInputs {
                    buffers,
                    restriction: self.restriction,
                    filtering: self.filtering,
                    resolution: self.splat_resolution.unwrap_or_default(),
                }),
            direct: self.direct.as_ref().filter(|_| self.components.direct),
            diffuse: self
                .diffuse_textures
                .as_ref()
                .filter(|_| self.components.diffuse),
        }
    }

    /// Under `--jittered-volumes stored`, stores the shadow volumes of every
    /// jittered light position that `aa` samples draw (Diefenbach & Badler
    /// 1997, section 4.4; built once per sample count), so that
    /// [`GpuFrame::draw`] with `aa` finds them; nothing otherwise.
    pub fn store_jittered_volumes(&mut self, scene: &Scene, aa: u32) -> anyhow::Result<()> {
        let stored = self
            .graph
            .shadow_volumes
            .as_ref()
            .is_some_and(|v| v.jitter() == VolumeJitter::Stored);
        if stored {
            let sets = sample_light_sets(&self.lights, self.light_samples, aa, self.paired);
            self.graph
                .store_jittered_volumes(&self.ctx, scene, &sets)
                .context("storing the jittered shadow volumes")?;
        }
        Ok(())
    }

    /// Draws `camera` with `aa` jittered samples into the HDR target and the output, and waits for the GPU (Diefenbach & Badler section 7's accumulation).
    pub fn draw(&self, camera: &Camera, aa: u32) -> anyhow::Result<()> {
        let ctx = &self.ctx;
        self.graph.render_accumulated(
            ctx,
            &self.inputs(camera),
            aa,
            if self.aa_splats {
                AccumulatedSplats::EverySample
            } else {
                AccumulatedSplats::Once
            },
            &mut |s| {
                let (Some(lights), Some(pass)) = (&self.direct, &self.graph.direct) else {
                    return Ok(());
                };
                if !self.paired || aa <= 1 {
                    return Ok(());
                }
                let rotation = paired_rotation(s, aa, self.light_samples);
                lights.set_lights(
                    pass,
                    &ctx.queue,
                    &jittered_point_lights(&self.lights, self.light_samples, rotation),
                )?;
                if self.shadow_volumes {
                    // The volumes follow the new positions by the pivot approximation.
                    return Ok(());
                }
                self.graph.update_shadows(ctx, &self.scene_buffers, lights)
            },
        )?;
        if let Some(ibr) = self.ibr.as_ref().filter(|_| self.components.radiance_maps) {
            ibr.add(ctx, &self.graph, &self.inputs(camera))?;
        }
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the frame")?;
        Ok(())
    }

    /// GPU milliseconds of each pass of the last frame drawn (`None` where the adapter has no timestamps).
    pub fn pass_times(&self) -> anyhow::Result<Option<PassTimes>> {
        Ok(self.graph.pass_times(&self.ctx)?)
    }

    /// The HDR image of the last frame drawn.
    pub fn read_hdr(&self) -> anyhow::Result<Image> {
        let hdr = lustre_mpr::readback::read_rgba_f32(&self.ctx, &self.targets.hdr.texture)?;
        Ok(Image::from_rgba(
            self.targets.width,
            self.targets.height,
            &hdr,
        )?)
    }

    /// Sets the tone mapping of the sRGB output (the window shows it; the HDR target is unchanged).
    pub fn set_tonemap(&mut self, tonemap: Tonemap) {
        self.tonemap = tonemap;
    }

    /// The sRGB output's texture.
    pub fn output(&self) -> &wgpu::Texture {
        &self.output
    }

    /// The frame's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.targets.width, self.targets.height)
    }

    /// New targets and output at `width` × `height` (a resized window); the lighting and the graph are kept.
    pub fn resize(&mut self, width: u32, height: u32) -> anyhow::Result<()> {
        if (width, height) == self.size() {
            return Ok(());
        }
        self.targets = RenderTargets::new(&self.ctx, width, height)?;
        (self.output, self.output_view) = output_texture(&self.ctx, width, height);
        Ok(())
    }

    /// Sets the splats' resolution (`auto` resolved for `camera` at the current height).
    pub fn set_splat_resolution(&mut self, args: &RenderArgs, camera: &Camera) {
        let height = self.targets.height;
        let restriction = self.restriction;
        self.splat_resolution = self
            .splats
            .as_ref()
            .map(|b| resolve_resolution(args, restriction, &b.supports, camera, height));
    }
}

/// The most bytes of shadow volumes (with their virtual lights' volumes)
/// that `--jittered-volumes auto` stores for the jittered lights of section
/// 4.4 (64 MiB); beyond it the jittered lights pivot about the volumes of
/// their area light's centre.
pub const STORED_VOLUME_BUDGET: usize = 64 << 20;

/// The bytes of shadow volumes storing every light position of `sets` would
/// take, from the bytes per position of `volumes` (an upper bound: positions
/// shared by several sets are counted once per set).
fn stored_volume_bytes(volumes: &ShadowVolumes, sets: &[Vec<Light>]) -> usize {
    let bytes = volumes.set().byte_size() + volumes.virtual_lights().map_or(0, |v| v.byte_size());
    let positions = volumes.positions().0.len().max(1);
    let stored: usize = sets.iter().map(Vec::len).sum();
    bytes.div_ceil(positions) * stored
}

/// The point lights `aa` accumulation samples draw for `lights` with `k`
/// jittered lights per area light (Diefenbach & Badler 1997, section 4.4):
/// the unrotated set every frame starts from and, with paired light jitter,
/// each sample's rotated set ([`GpuFrame::draw`]'s order).
fn sample_light_sets(lights: &[Light], k: u32, aa: u32, paired: bool) -> Vec<Vec<Light>> {
    let mut sets = vec![jittered_point_lights(lights, k, Vec2::ZERO)];
    if paired && aa > 1 {
        sets.extend((0..aa).map(|s| jittered_point_lights(lights, k, paired_rotation(s, aa, k))));
    }
    sets
}

/// `--splat-resolution`, with `auto` chosen from the splats' projected size through `camera`.
pub fn resolve_resolution(
    args: &RenderArgs,
    restriction: Restriction,
    supports: &[[f32; 4]],
    camera: &Camera,
    height: u32,
) -> SplatResolution {
    match args.splat_resolution {
        SplatResolutionArg::Auto if restriction == Restriction::Stencil => SplatResolution::Full,
        SplatResolutionArg::Auto => SplatResolution::auto(supports, camera, height),
        SplatResolutionArg::Full => SplatResolution::Full,
        SplatResolutionArg::Half => SplatResolution::Half,
        SplatResolutionArg::Quarter => SplatResolution::Quarter,
        SplatResolutionArg::Eighth => SplatResolution::Eighth,
    }
}

/// The sRGB output texture (a render attachment, copied from for read-back, sampled by the window).
pub fn output_texture(
    ctx: &GpuContext,
    width: u32,
    height: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("lustre-output"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: OUTPUT_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        // The window samples the encoded bytes as they are (egui works in gamma space).
        view_formats: &[wgpu::TextureFormat::Rgba8Unorm],
    });
    let view = output.create_view(&wgpu::TextureViewDescriptor::default());
    (output, view)
}
