//! The frame graph (DESIGN.md "Data flow", step 3; Diefenbach & Badler 1997,
//! section 7): one command encoder per frame runs the passes in order (clear
//! HDR, depth pre-pass, specular images, emitters, Gouraud vertex radiance,
//! direct light, diffuse textures, photon splats, tone map) into any
//! `TextureView`. Every scene pass draws under a [`View`]; the views of a
//! frame sit in one [`ViewBuffer`] at dynamic offsets, so the specular
//! recursion of section 7.1 (`draw_window` → `draw_spec_objects` →
//! `draw_window` from the virtual camera) is the same passes recorded again
//! under a deeper view ([`crate::passes::specular`]).
//! [`FrameGraph::render_accumulated`] averages jittered frames for
//! antialiasing (section 7). Shadow maps are rendered per light pose, not per
//! frame ([`FrameGraph::update_shadows`]); shadow volumes, which replace them
//! when the graph has [`FrameGraph::with_shadow_volumes`] (section 4.1), are
//! rebuilt only for moved objects or lights ([`FrameGraph::update_shadow_volumes`]).

use std::sync::Mutex;

use lustre_geometry::Camera;
use lustre_geometry::light::hammersley_centred;

use crate::diffuse_map::DiffuseMaps;
use crate::light_group::LightGroup;
use crate::passes::accumulate::AccumulatePass;
use crate::passes::beams::{BeamPass, Traversal};

use crate::pass_timing::{PassTimer, PassTimes};
use crate::passes::depth::DepthPass;
use crate::passes::diffuse_texture::{DiffuseTexturePass, DiffuseTextures};
use crate::passes::direct::{DirectLights, DirectPass};
use crate::passes::emission::EmissionPass;
use crate::passes::gouraud::GouraudPass;
use crate::passes::shadowed_direct::{ShadowVolumes, ShadowedDirect};
use crate::passes::specular::{SpecularPass, SpecularSettings, ViewTree};
use crate::passes::splat::{KernelFiltering, Restriction, SplatBuffers, SplatPass};
use crate::passes::splat_lowres::SplatResolution;
use crate::passes::tonemap::{Tonemap, TonemapPass};
use crate::scene_buffers::SceneBuffers;
use crate::target::RenderTargets;
use crate::view::{View, ViewBuffer, ViewSlot};
use crate::{GpuContext, Result};

/// One pass that adds light into the HDR target under a view (section 7.2):
/// the interface the frame records every such pass through, at every level
/// of the specular recursion.
pub trait LightPass {
    /// The pass's name in the per-pass GPU times ([`crate::pass_timing`]).
    fn name(&self) -> &'static str;

    /// Records the pass for the view in `slot` (its stencil reference bound with it).
    fn encode_view(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()>;
}

impl LightPass for SplatPass {
    fn name(&self) -> &'static str {
        "splats"
    }

    fn encode_view(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        let Some(inputs) = frame.splats else {
            return Ok(());
        };
        self.encode_at(
            ctx,
            encoder,
            frame.scene,
            inputs.buffers,
            frame.targets,
            inputs.restriction,
            inputs.resolution,
            views,
            slot,
        )
        .map(|_| ())
    }
}

impl LightPass for EmissionPass {
    fn name(&self) -> &'static str {
        "emission"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        self.encode(encoder, frame.scene, frame.targets, views, slot);
        Ok(())
    }
}

impl LightPass for GouraudPass {
    fn name(&self) -> &'static str {
        "per-vertex (Gouraud)"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        self.encode(encoder, frame.scene, frame.targets, views, slot)
    }
}

impl LightPass for DirectPass {
    fn name(&self) -> &'static str {
        "direct light"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        if let Some(lights) = frame.direct {
            self.encode(encoder, frame.scene, frame.targets, lights, views, slot);
        }
        Ok(())
    }
}

impl LightPass for BeamPass {
    fn name(&self) -> &'static str {
        "beams"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        self.encode(encoder, frame.scene, frame.targets, views, slot);
        Ok(())
    }
}

impl LightPass for DiffuseTexturePass {
    fn name(&self) -> &'static str {
        "diffuse textures"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        if let Some(textures) = frame.diffuse {
            self.encode(encoder, frame.scene, frame.targets, textures, views, slot);
        }
        Ok(())
    }
}

/// What one frame reads and writes.
#[derive(Debug, Clone, Copy)]
pub struct FrameInputs<'a> {
    /// The scene's triangles on the GPU.
    pub scene: &'a SceneBuffers,
    /// The viewpoint (its aspect should match the targets').
    pub camera: &'a Camera,
    /// Exposure and tone operator.
    pub tonemap: &'a Tonemap,
    /// HDR, depth and surface-id targets.
    pub targets: &'a RenderTargets,
    /// Where the tone-mapped image goes: a window surface, a capture texture, a test texture.
    pub output: &'a wgpu::TextureView,
    /// Photon splats to add (Stürzlinger & Bastos 1997, section 2.2), if any.
    pub splats: Option<SplatInputs<'a>>,
    /// Point lights whose direct light to add with shadow maps (section 2.2.1), if any.
    pub direct: Option<&'a DirectLights>,
    /// Diffuse surfaces' precomputed photon radiance (section 2.2.1), if any.
    pub diffuse: Option<&'a DiffuseTextures>,
    /// Which of the terms the graph holds itself are drawn.
    pub graph_terms: GraphTerms,
}

/// The light terms a [`FrameGraph`] holds itself, switched per frame; the
/// terms a frame's inputs carry (direct light, diffuse textures, splats)
/// are switched by leaving the input out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GraphTerms {
    /// The emitters' radiance with the specular recursion's constant terms
    /// (the limit faces' radiance and the glossy images' fog radiance).
    pub emission: bool,
    /// The beams' light.
    pub beams: bool,
}

impl GraphTerms {
    /// Every term the graph was built with.
    pub const ALL: Self = Self {
        emission: true,
        beams: true,
    };
}

/// What the splat pass of a frame reads.
#[derive(Debug, Clone, Copy)]
pub struct SplatInputs<'a> {
    /// The splats and their materials.
    pub buffers: &'a SplatBuffers,
    /// How splats are limited to their visible surface.
    pub restriction: Restriction,
    /// How the kernel texture is filtered.
    pub filtering: KernelFiltering,
    /// The resolution the camera view's splats are accumulated at ([`crate::passes::splat_lowres`]).
    pub resolution: SplatResolution,
}

/// The passes of a frame, in the order they run.
#[derive(Debug)]
pub struct FrameGraph {
    /// The depth pre-pass.
    pub depth: DepthPass,
    /// The emitters' own radiance, when the graph was built for a scene ([`FrameGraph::with_emission`]).
    pub emission: Option<EmissionPass>,
    /// Per-vertex radiance with Gouraud interpolation (García et al. 2003, section 2.4; [`FrameGraph::with_gouraud`]).
    pub gouraud: Option<GouraudPass>,
    /// The direct light pass ([`FrameGraph::with_direct`]).
    pub direct: Option<DirectPass>,
    /// The precomputed diffuse textures' pass ([`FrameGraph::with_diffuse_textures`]).
    pub diffuse: Option<DiffuseTexturePass>,
    /// The splat pass ([`FrameGraph::with_splats`]).
    pub splat: Option<SplatPass>,
    /// The accumulation of jittered frames ([`FrameGraph::with_accumulation`]).
    pub accumulate: Option<AccumulatePass>,
    /// Stencilled specular images of mirror faces ([`FrameGraph::with_specular`]).
    pub specular: Option<SpecularPass>,
    /// Shadow volumes replacing the direct pass's shadow maps ([`FrameGraph::with_shadow_volumes`]).
    pub shadow_volumes: Option<ShadowVolumes>,
    /// Caustic and glossy light beams on receivers ([`FrameGraph::with_beams`]).
    pub beams: Option<BeamPass>,
    /// The final tone map.
    pub tonemap: TonemapPass,
    /// The frame's views (camera, virtual cameras), rewritten every frame.
    views: Mutex<ViewBuffer>,
    /// Timestamps between the passes ([`FrameGraph::with_pass_timing`]).
    timer: Option<PassTimer>,
    /// Jittered samples of the emitters' own radiance drawn apart from the
    /// accumulated frames ([`FrameGraph::with_emission_samples`]; 0: none apart).
    emission_samples: u32,
}

impl FrameGraph {
    /// Builds every pass; `output_format` is the format of the views [`FrameGraph::render`] will be given.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self> {
        Ok(Self {
            depth: DepthPass::new(ctx)?,
            emission: None,
            gouraud: None,
            direct: None,
            diffuse: None,
            splat: None,
            accumulate: None,
            specular: None,
            shadow_volumes: None,
            beams: None,
            tonemap: TonemapPass::new(ctx, output_format)?,
            views: Mutex::new(ViewBuffer::new(ctx, 8)),
            timer: None,
            emission_samples: 0,
        })
    }

    /// Under [`FrameGraph::render_accumulated`] with fewer jittered frames
    /// than `samples`, the emitters seen directly are drawn apart from them,
    /// through `samples` jittered cameras of their own (each a depth
    /// pre-pass and the emission pass, added with weight `1/samples`): an
    /// emitter's edge is the frame's sharpest contrast, and the box filter
    /// of section 7's accumulation over `N` offsets leaves its edge pixels'
    /// coverage quantised to `1/N`. Only where no view of the frame but the
    /// camera's shows an emitter (no mirror, slab or interface faces, every
    /// glossy image hiding emitters, [`crate::View::shows_emitters`]);
    /// otherwise the emitters stay in the jittered frames. 0 (the default)
    /// keeps them there always.
    pub fn with_emission_samples(mut self, samples: u32) -> Self {
        self.emission_samples = samples;
        self
    }

    /// Whether `render_accumulated` with `samples` frames draws the emitters
    /// apart ([`FrameGraph::with_emission_samples`]): more emission samples
    /// than frames, an emission pass, and only the camera's view showing emitters.
    fn emission_apart(&self, terms: GraphTerms, samples: u32) -> Option<&EmissionPass> {
        let only_camera_shows_emitters = self.specular.as_ref().is_none_or(|specular| {
            specular.faces().iter().all(|f| {
                matches!(
                    f.kind,
                    crate::passes::specular::SpecularKind::Glossy(g) if g.hide_emitters
                )
            })
        });
        (self.emission_samples > samples
            && samples > 1
            && terms.emission
            && only_camera_shows_emitters)
            .then_some(self.emission.as_ref())
            .flatten()
    }

    /// The jittered samples the emitters seen directly get under
    /// [`FrameGraph::render_accumulated`] with `samples` frames of `terms`:
    /// [`FrameGraph::with_emission_samples`]' count where they are drawn apart, else `samples`.
    pub fn emission_samples(&self, terms: GraphTerms, samples: u32) -> u32 {
        if self.emission_apart(terms, samples).is_some() {
            self.emission_samples
        } else {
            samples
        }
    }

    /// Times every pass of each frame on the GPU where the device writes timestamps inside encoders (else unchanged); [`FrameGraph::pass_times`] reads the last frame's.
    pub fn with_pass_timing(mut self, ctx: &GpuContext) -> Self {
        self.timer = PassTimer::new(ctx);
        self
    }

    /// GPU milliseconds of each pass of the last frame, summed over its views and samples; `None` without timing.
    pub fn pass_times(&self, ctx: &GpuContext) -> Result<Option<PassTimes>> {
        self.timer.as_ref().map(|t| t.read(ctx)).transpose()
    }

    /// Records `f` as the pass `name` (timed when timing is on).
    fn timed<R>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        name: &'static str,
        f: impl FnOnce(&mut wgpu::CommandEncoder) -> R,
    ) -> R {
        match &self.timer {
            Some(timer) => timer.span(encoder, name, f),
            None => f(encoder),
        }
    }

    /// Starts a frame's timing.
    fn reset_timing(&self) {
        if let Some(timer) = &self.timer {
            timer.reset();
        }
    }

    /// Adds specular images (section 3, 7.1): every planar mirror face of
    /// `scene` masked in the stencil and the scene redrawn from its virtual
    /// camera, recursively to `settings.max_depth`.
    pub fn with_specular(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &lustre_geometry::Scene,
        settings: SpecularSettings,
    ) -> Result<Self> {
        self.specular = Some(SpecularPass::new(ctx, hdr_format, scene, settings)?);
        Ok(self)
    }

    /// Adds the beam pass (Duvenhage et al. 2010, sections 3.1, 4.3): the light of `beams` added on every surface under every view, with `scene`'s materials flattened with `glossy` and its diffuse `maps` ([`DiffuseMaps::upload`], or [`DiffuseMaps::white`] for none), each fragment finding its beams by `traversal`.
    pub fn with_beams(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &lustre_geometry::Scene,
        glossy: crate::material::GlossyModel,
        maps: &DiffuseMaps,
        beams: &lustre_beams::BeamSet,
        traversal: Traversal,
    ) -> Result<Self> {
        self.beams = Some(BeamPass::new(
            ctx, hdr_format, scene, glossy, maps, beams, traversal,
        )?);
        Ok(self)
    }

    /// Adds the emission pass for `scene`'s emitters and HDR targets of `hdr_format`.
    pub fn with_emission(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &lustre_geometry::Scene,
    ) -> Result<Self> {
        self.emission = Some(EmissionPass::new(ctx, hdr_format, scene)?);
        Ok(self)
    }

    /// Adds the Gouraud pass for `scene`'s triangle corners and HDR targets of `hdr_format`; its radiance is zero until [`FrameGraph::set_gouraud_radiance`].
    pub fn with_gouraud(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &SceneBuffers,
    ) -> Result<Self> {
        self.gouraud = Some(GouraudPass::new(ctx, hdr_format, scene)?);
        Ok(self)
    }

    /// Replaces the Gouraud pass's per-corner radiance (section 2.4.2: once per frame of the quasi-static method).
    pub fn set_gouraud_radiance(&self, ctx: &GpuContext, radiance: &[[f32; 3]]) -> Result<()> {
        let Some(gouraud) = &self.gouraud else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "vertex radiance needs the Gouraud pass (FrameGraph::with_gouraud)".into(),
            });
        };
        gouraud.set_radiance(&ctx.queue, radiance)
    }

    /// Scales the Gouraud pass's fragments by `maps` at their UVs, per corner layer ([`GouraudPass::set_diffuse_maps`], [`crate::passes::gouraud::corner_layers`]).
    pub fn set_gouraud_diffuse_maps(
        &mut self,
        ctx: &GpuContext,
        maps: &DiffuseMaps,
        layers: &[u32],
    ) -> Result<()> {
        let Some(gouraud) = &mut self.gouraud else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "diffuse maps need the Gouraud pass (FrameGraph::with_gouraud)".into(),
            });
        };
        gouraud.set_diffuse_maps(ctx, maps, layers)
    }

    /// Adds the direct light pass for HDR targets of `hdr_format`.
    pub fn with_direct(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        self.direct = Some(DirectPass::new(ctx, hdr_format)?);
        Ok(self)
    }

    /// Shadows the direct light with shadow volumes instead of shadow maps
    /// (Diefenbach & Badler 1997, sections 4.1 and 7.2): the volumes of every
    /// object of `scene` for each of `lights` (the point lights the frame's
    /// [`DirectLights`] hold, in order), for HDR targets of `hdr_format`. Each
    /// view's direct light is then, per light, the volume count in the
    /// stencil and the light added where it is zero ([`ShadowedDirect`]).
    /// Needs [`FrameGraph::with_direct`] for the frame's direct light.
    pub fn with_shadow_volumes(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &lustre_geometry::Scene,
        lights: &[lustre_geometry::Light],
    ) -> Result<Self> {
        self.shadow_volumes = Some(ShadowVolumes::new(ctx, hdr_format, scene, lights)?);
        Ok(self)
    }

    /// Adds the virtual lights of the scene's specular faces to the shadow
    /// volumes (Diefenbach & Badler 1997, sections 4.2, 4.3): every point
    /// light reflected and refracted through chains of at most
    /// `settings.depth` faces, bounded by light volumes and shadowed by
    /// transformed shadow volumes. Fails without
    /// [`FrameGraph::with_shadow_volumes`].
    pub fn with_virtual_lights(
        mut self,
        ctx: &GpuContext,
        scene: &lustre_geometry::Scene,
        settings: crate::virtual_light::VirtualLightSettings,
    ) -> Result<Self> {
        let Some(volumes) = self.shadow_volumes.take() else {
            return Err(crate::MprError::InvalidSetting {
                what: "virtual lights",
                message: "they need shadow volumes (with_shadow_volumes first)".into(),
            });
        };
        let passed = crate::virtual_light::PassedFaces::new(scene, settings.panes)?;
        self.shadow_volumes = Some(volumes.with_virtual_lights(
            ctx,
            scene,
            &passed.faces,
            &passed.windows,
            settings,
        )?);
        Ok(self)
    }

    /// Rebuilds and re-uploads the shadow volumes of the objects and lights
    /// that moved (section 4.3; [`ShadowVolumes::refresh`]); returns the
    /// number of volumes rebuilt, 0 without shadow volumes.
    pub fn update_shadow_volumes(
        &mut self,
        ctx: &GpuContext,
        scene: &lustre_geometry::Scene,
        lights: &[lustre_geometry::Light],
    ) -> Result<usize> {
        match &mut self.shadow_volumes {
            Some(volumes) => volumes.refresh(ctx, scene, lights),
            None => Ok(0),
        }
    }

    /// Stores shadow volumes for every light position of `sets` (the point
    /// lights of each accumulation sample) and draws each light with its
    /// own position's volumes from now on (section 4.4's stored jittered
    /// volumes, [`ShadowVolumes::store_jittered`]); returns the number of
    /// volumes built, 0 without shadow volumes.
    pub fn store_jittered_volumes(
        &mut self,
        ctx: &GpuContext,
        scene: &lustre_geometry::Scene,
        sets: &[Vec<lustre_geometry::Light>],
    ) -> Result<usize> {
        match &mut self.shadow_volumes {
            Some(volumes) => volumes.store_jittered(ctx, scene, sets),
            None => Ok(0),
        }
    }

    /// Writes the direct lights' positions for the shadow volumes, before a submission.
    fn prepare_shadow_volumes(&self, ctx: &GpuContext, passes: &ResolvedPasses<'_>) -> Result<()> {
        match (&self.shadow_volumes, passes.direct) {
            (Some(volumes), Some((lights, pass))) => volumes.prepare(ctx, pass, lights),
            _ => Ok(()),
        }
    }

    /// Adds the pass drawing precomputed diffuse textures into HDR targets of `hdr_format`.
    pub fn with_diffuse_textures(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        self.diffuse = Some(DiffuseTexturePass::new(ctx, hdr_format)?);
        Ok(self)
    }

    /// Renders the shadow cube maps of `lights` for the scene's current pose (once per light or object move, not per frame).
    pub fn update_shadows(
        &self,
        ctx: &GpuContext,
        scene: &SceneBuffers,
        lights: &DirectLights,
    ) -> Result<()> {
        let Some(direct) = &self.direct else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "shadow maps need the direct pass (FrameGraph::with_direct)".into(),
            });
        };
        ctx.checked("shadow maps", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("shadows"),
                });
            direct.encode_shadows(&mut encoder, scene, lights);
            ctx.queue.submit([encoder.finish()]);
        })
    }

    /// Adds the splat pass for HDR targets of `hdr_format` with the kernel `kernel`.
    pub fn with_splats(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        kernel: lustre_photon::Kernel,
    ) -> Result<Self> {
        self.splat = Some(SplatPass::new(ctx, hdr_format, kernel)?);
        Ok(self)
    }

    /// Adds the accumulation pass of [`FrameGraph::render_accumulated`] for HDR targets of `hdr_format`.
    pub fn with_accumulation(
        mut self,
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        self.accumulate = Some(AccumulatePass::new(ctx, hdr_format)?);
        Ok(self)
    }

    /// Records and submits one frame in one command encoder: clear HDR to
    /// black (passes add light into it), then `draw_window` of the camera's
    /// view (depth pre-pass, specular images recursively, emitters, Gouraud
    /// vertex radiance, direct light, diffuse textures), splats, tone map to
    /// `output`. Returns the views drawn (scene passes, table 3).
    pub fn render(&self, ctx: &GpuContext, frame: &FrameInputs<'_>) -> Result<usize> {
        self.render_view(ctx, frame, View::from_camera(frame.camera))
    }

    /// [`FrameGraph::render`] from `root` instead of `frame.camera`'s own
    /// view: a view with a clip plane, a mirrored frame or emitters hidden
    /// (a radiance map's sample camera, [`crate::ibr`]).
    pub fn render_view(
        &self,
        ctx: &GpuContext,
        frame: &FrameInputs<'_>,
        root: View,
    ) -> Result<usize> {
        self.reset_timing();
        self.tonemap.prepare(&ctx.queue, frame.tonemap)?;
        let passes = self.resolve(frame)?;
        let mut views = self.views.lock().unwrap_or_else(|e| e.into_inner());
        let tree = match &self.specular {
            Some(specular) => specular.view_tree(root, ctx.clip_method())?,
            None => ViewTree::single(root),
        };
        let slots = self.write_views(ctx, &mut views, &tree, frame)?;
        if let Some((inputs, pass)) = passes.splat {
            pass.prepare(&ctx.queue, inputs.filtering);
        }
        self.prepare_shadow_volumes(ctx, &passes)?;
        let shadowed = self.shadowed(&passes);
        let light = self.light_passes(frame.graph_terms, &passes, shadowed.as_ref());
        ctx.checked_result("frame", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
            self.encode_light(
                ctx,
                &mut encoder,
                frame,
                &light,
                &views,
                &tree,
                &slots,
                true,
            )?;
            self.timed(&mut encoder, "tone map", |encoder| {
                self.tonemap
                    .encode(&ctx.device, encoder, &frame.targets.hdr.view, frame.output);
            });
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })?;
        Ok(tree.views.len())
    }

    /// The views of a frame through `camera`: the camera alone, or with the
    /// virtual cameras of the specular recursion ([`crate::passes::specular::ViewTree`]).
    pub fn view_tree(&self, ctx: &GpuContext, camera: &Camera) -> Result<ViewTree> {
        let root = View::from_camera(camera);
        match &self.specular {
            Some(specular) => specular.view_tree(root, ctx.clip_method()),
            None => Ok(ViewTree::single(root)),
        }
    }

    /// Antialiasing by jittered accumulation (Diefenbach & Badler 1997,
    /// section 7): the frame rendered `samples` times, each through
    /// `frame.camera` shifted to sample every pixel at the next offset of
    /// [`hammersley_centred`] (a box filter over the pixel), each added with
    /// weight `1/samples` into [`RenderTargets::accumulation`], whose average
    /// is copied into the HDR target and tone mapped to `output`. Before
    /// sample `s`, `before_sample(s)` may change the scene's lights (paired
    /// light jitter, section 4.4). With `Splats::Once` the fill-bound splat
    /// pass runs once, unjittered, after the average (over a fresh depth
    /// pre-pass through the pixel centres): its kernels are smooth, only the
    /// surface edges it is restricted to stay point sampled. `samples <= 1`
    /// is [`FrameGraph::render`], bit for bit.
    pub fn render_accumulated(
        &self,
        ctx: &GpuContext,
        frame: &FrameInputs<'_>,
        samples: u32,
        splats: AccumulatedSplats,
        before_sample: &mut dyn FnMut(u32) -> Result<()>,
    ) -> Result<()> {
        if samples <= 1 {
            before_sample(0)?;
            return self.render(ctx, frame).map(|_| ());
        }
        let Some(accumulate) = &self.accumulate else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "jittered accumulation needs the accumulation pass \
                          (FrameGraph::with_accumulation)"
                    .into(),
            });
        };
        self.reset_timing();
        self.tonemap.prepare(&ctx.queue, frame.tonemap)?;
        let passes = self.resolve(frame)?;
        let (width, height) = (frame.targets.width, frame.targets.height);
        let weight = 1.0 / samples as f32;
        let splat_once = splats == AccumulatedSplats::Once && passes.splat.is_some();
        let jittered_passes = ResolvedPasses {
            splat: if splat_once { None } else { passes.splat },
            ..passes
        };
        let shadowed = self.shadowed(&jittered_passes);
        // Emitters drawn apart leave the jittered frames' passes (their
        // constant terms stay: `draw_window` switches them with the frame's terms).
        let emission_apart = self.emission_apart(frame.graph_terms, samples);
        let jittered_terms = GraphTerms {
            emission: frame.graph_terms.emission && emission_apart.is_none(),
            ..frame.graph_terms
        };
        let jittered_light = self.light_passes(jittered_terms, &jittered_passes, shadowed.as_ref());
        let mut views = self.views.lock().unwrap_or_else(|e| e.into_inner());
        for s in 0..samples {
            before_sample(s)?;
            let camera =
                frame
                    .camera
                    .with_pixel_offset(hammersley_centred(s, samples), width, height);
            let tree = self.view_tree_interleaved(ctx, &camera, s, samples)?;
            let slots = self.write_views(ctx, &mut views, &tree, frame)?;
            if let Some((inputs, pass)) = passes.splat {
                pass.prepare(&ctx.queue, inputs.filtering);
            }
            self.prepare_shadow_volumes(ctx, &jittered_passes)?;
            ctx.checked_result("accumulated frame", || {
                let mut encoder =
                    ctx.device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("accumulated-frame"),
                        });
                self.encode_light(
                    ctx,
                    &mut encoder,
                    frame,
                    &jittered_light,
                    &views,
                    &tree,
                    &slots,
                    true,
                )?;
                self.timed(&mut encoder, "accumulate", |encoder| {
                    accumulate.encode(&ctx.device, encoder, frame.targets, weight, s == 0);
                });
                if s + 1 == samples {
                    if let Some(emission) = emission_apart {
                        // Ordered after this submit's views (write_buffer
                        // applies at submit): the samples' views replace them.
                        ctx.queue.submit([encoder.finish()]);
                        self.encode_emission_samples(ctx, frame, emission, &mut views, accumulate)?;
                        encoder =
                            ctx.device
                                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                                    label: Some("after-emission"),
                                });
                    }
                    if splat_once {
                        // The splats once through the pixel centres, at every
                        // level of the specular recursion, into a cleared HDR
                        // target that is then added to the average. Ordered
                        // after this submit's jittered views (write_buffer
                        // applies at submit).
                        ctx.queue.submit([encoder.finish()]);
                        encoder =
                            ctx.device
                                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                                    label: Some("splats-once"),
                                });
                        if let Some((_, pass)) = passes.splat {
                            self.encode_added_splats(
                                ctx,
                                &mut encoder,
                                frame,
                                pass,
                                &mut views,
                                accumulate,
                            )?;
                        }
                    }
                    self.timed(&mut encoder, "tone map", |encoder| {
                        self.encode_resolve(ctx, encoder, frame);
                    });
                }
                ctx.queue.submit([encoder.finish()]);
                Ok(())
            })?;
        }
        Ok(())
    }

    /// Adds one batch of splats to the frame that [`FrameGraph::render`] or
    /// [`FrameGraph::render_accumulated`] left in the HDR target, and tone
    /// maps the sum to `frame.output`: the splats of a photon map streamed
    /// from disk in batches (Stürzlinger & Bastos 1997, section 2.1: hits
    /// stored on disk; section 2.2), drawn through the pixel centres at every
    /// level of the specular recursion as [`AccumulatedSplats::Once`] draws
    /// them, so the GPU holds one batch at a time. The sum is kept in
    /// [`RenderTargets::accumulation`]: `first` copies the frame there before
    /// the first batch. `frame.splats` must be given.
    pub fn add_splats(&self, ctx: &GpuContext, frame: &FrameInputs<'_>, first: bool) -> Result<()> {
        let Some(accumulate) = &self.accumulate else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "splat batches are summed by the accumulation pass \
                          (FrameGraph::with_accumulation)"
                    .into(),
            });
        };
        let passes = self.resolve(frame)?;
        let Some((inputs, pass)) = passes.splat else {
            return Err(crate::MprError::InvalidSetting {
                what: "frame",
                message: "add_splats needs a batch of splats (FrameInputs::splats)".into(),
            });
        };
        self.tonemap.prepare(&ctx.queue, frame.tonemap)?;
        pass.prepare(&ctx.queue, inputs.filtering);
        let mut views = self.views.lock().unwrap_or_else(|e| e.into_inner());
        ctx.checked_result("splat batch", || {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("splat-batch"),
                });
            let accumulation = &frame.targets.accumulation.texture;
            if first {
                encoder.copy_texture_to_texture(
                    frame.targets.hdr.texture.as_image_copy(),
                    accumulation.as_image_copy(),
                    accumulation.size(),
                );
            }
            self.encode_added_splats(ctx, &mut encoder, frame, pass, &mut views, accumulate)?;
            self.encode_resolve(ctx, &mut encoder, frame);
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        })
    }

    /// Writes the tree's views and gives each slot its region
    /// ([`ViewTree::regions`]) in the frame's targets and the group of the
    /// frame's direct lights it draws ([`LightGroup::for_path`]).
    fn write_views(
        &self,
        ctx: &GpuContext,
        views: &mut ViewBuffer,
        tree: &ViewTree,
        frame: &FrameInputs<'_>,
    ) -> Result<Vec<ViewSlot>> {
        let targets = frame.targets;
        let lights = frame.direct.map_or(0, DirectLights::len);
        let mut slots = views.write(ctx, &tree.views)?;
        if let Some(specular) = &self.specular {
            let regions = tree.regions(specular.faces(), targets.width, targets.height);
            for (slot, region) in slots.iter_mut().zip(regions) {
                slot.scissor = region;
            }
        }
        for (slot, path) in slots.iter_mut().zip(&tree.paths) {
            slot.lights = LightGroup::for_path(*path, lights);
        }
        Ok(slots)
    }

    /// The emitters' own radiance through [`FrameGraph::with_emission_samples`]
    /// jittered cameras in one submission: per sample a depth pre-pass and
    /// the emission pass weighted `1/samples`, both inside the rectangle the
    /// emitters may cover ([`EmissionPass::screen_rect`]), summed in the
    /// cleared HDR target, then added to [`RenderTargets::accumulation`]
    /// over that rectangle. Only the camera's view:
    /// [`FrameGraph::emission_apart`] holds that no other shows emitters.
    fn encode_emission_samples(
        &self,
        ctx: &GpuContext,
        frame: &FrameInputs<'_>,
        emission: &EmissionPass,
        views: &mut ViewBuffer,
        accumulate: &AccumulatePass,
    ) -> Result<()> {
        let samples = self.emission_samples;
        let targets = frame.targets;
        let (width, height) = (targets.width, targets.height);
        // The pixels the emitters may cover, once through the pixel centres:
        // a sample's jitter moves every projected point by under half a
        // pixel, and the rectangle has a pixel of margin all round.
        let centre = frame
            .camera
            .with_pixel_offset(glam::Vec2::splat(0.5), width, height);
        let Some(rect) =
            emission.screen_rect(View::from_camera(&centre).view_projection(), width, height)
        else {
            return Ok(());
        };
        let cameras: Vec<View> = (0..samples)
            .map(|j| {
                View::from_camera(&frame.camera.with_pixel_offset(
                    hammersley_centred(j, samples),
                    width,
                    height,
                ))
            })
            .collect();
        let slots = views.write(ctx, &cameras)?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("emission-samples"),
            });
        clear_hdr(&mut encoder, targets);
        let weight = 1.0 / samples as f32;
        for mut slot in slots {
            slot.scissor = rect;
            self.timed(&mut encoder, "depth", |encoder| {
                self.depth
                    .encode(encoder, frame.scene, targets, views, slot, true);
            });
            self.timed(&mut encoder, "emission", |encoder| {
                emission.encode_weighted(encoder, frame.scene, targets, views, slot, weight);
            });
        }
        self.timed(&mut encoder, "accumulate", |encoder| {
            accumulate.encode_in(&ctx.device, encoder, targets, 1.0, false, Some(rect));
        });
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The splats alone, through the pixel centres at every level of the
    /// specular recursion, into a cleared HDR target that is then added to
    /// [`RenderTargets::accumulation`] (the limit faces' light is in the
    /// accumulated frame already).
    fn encode_added_splats(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        pass: &SplatPass,
        views: &mut ViewBuffer,
        accumulate: &AccumulatePass,
    ) -> Result<()> {
        let tree = self.view_tree(ctx, frame.camera)?;
        let slots = self.write_views(ctx, views, &tree, frame)?;
        let splat_light: [&dyn LightPass; 1] = [pass];
        self.encode_light(
            ctx,
            encoder,
            frame,
            &splat_light,
            views,
            &tree,
            &slots,
            false,
        )?;
        accumulate.encode(&ctx.device, encoder, frame.targets, 1.0, false);
        Ok(())
    }

    /// The accumulated frame copied into the HDR target and tone mapped to `frame.output`.
    fn encode_resolve(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
    ) {
        let accumulation = &frame.targets.accumulation.texture;
        encoder.copy_texture_to_texture(
            accumulation.as_image_copy(),
            frame.targets.hdr.texture.as_image_copy(),
            accumulation.size(),
        );
        self.tonemap
            .encode(&ctx.device, encoder, &frame.targets.hdr.view, frame.output);
    }

    /// Pairs each input of `frame` with its pass; an input without its pass is an error.
    fn resolve<'a>(&'a self, frame: &FrameInputs<'a>) -> Result<ResolvedPasses<'a>> {
        let splat = match (frame.splats, &self.splat) {
            (Some(inputs), Some(pass)) => Some((inputs, pass)),
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "splats were given but the frame graph has no splat pass \
                              (FrameGraph::with_splats)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        let direct = match (frame.direct, &self.direct) {
            (Some(lights), Some(pass)) => Some((lights, pass)),
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "point lights were given but the frame graph has no direct pass \
                              (FrameGraph::with_direct)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        let diffuse = match (frame.diffuse, &self.diffuse) {
            (Some(textures), Some(pass)) => Some((textures, pass)),
            (Some(_), None) => {
                return Err(crate::MprError::InvalidSetting {
                    what: "frame",
                    message: "diffuse textures were given but the frame graph has no pass for \
                              them (FrameGraph::with_diffuse_textures)"
                        .into(),
                });
            }
            (None, _) => None,
        };
        Ok(ResolvedPasses {
            splat,
            direct,
            diffuse,
        })
    }

    /// The direct pass lit under shadow volumes, where the graph has them (section 4.1).
    fn shadowed<'a>(&'a self, passes: &ResolvedPasses<'a>) -> Option<ShadowedDirect<'a>> {
        match (&self.shadow_volumes, passes.direct) {
            (Some(volumes), Some((_, direct))) => Some(ShadowedDirect { direct, volumes }),
            _ => None,
        }
    }

    /// The passes that add light under a view, in order (section 7.2).
    fn light_passes<'a>(
        &'a self,
        terms: GraphTerms,
        passes: &ResolvedPasses<'a>,
        shadowed: Option<&'a ShadowedDirect<'a>>,
    ) -> Vec<&'a dyn LightPass> {
        let mut list: Vec<&dyn LightPass> = Vec::new();
        if let Some(emission) = self.emission.as_ref().filter(|_| terms.emission) {
            list.push(emission);
        }
        if let Some(gouraud) = &self.gouraud {
            list.push(gouraud);
        }
        if let Some((_, pass)) = passes.direct {
            match shadowed {
                Some(shadowed) => list.push(shadowed),
                None => list.push(pass),
            }
        }
        if let Some((_, pass)) = passes.diffuse {
            list.push(pass);
        }
        if let Some((_, pass)) = passes.splat {
            list.push(pass);
        }
        if let Some(beams) = self.beams.as_ref().filter(|_| terms.beams) {
            list.push(beams);
        }
        list
    }

    /// Records the frame's light into the HDR target, cleared first (section
    /// 7.2): `draw_window` of the camera's view with `light` at every level.
    #[allow(clippy::too_many_arguments)]
    fn encode_light(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        light: &[&dyn LightPass],
        views: &ViewBuffer,
        tree: &ViewTree,
        slots: &[ViewSlot],
        limit: bool,
    ) -> Result<()> {
        clear_hdr(encoder, frame.targets);
        self.draw_window(ctx, encoder, frame, light, views, tree, slots, 0, limit)
    }

    /// `draw_window` of section 7.1 for view `index` of `tree`: its depth
    /// pass (clearing for the camera, inside its mask for a virtual view),
    /// each specular face masked, drawn from its virtual view and restored
    /// (`draw_spec_objects`), the faces at the recursion limit (with
    /// `limit`; a pass that redraws only part of the light leaves them out),
    /// then the light passes under the view.
    #[allow(clippy::too_many_arguments)]
    fn draw_window(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        light: &[&dyn LightPass],
        views: &ViewBuffer,
        tree: &ViewTree,
        slots: &[ViewSlot],
        index: usize,
        limit: bool,
    ) -> Result<()> {
        let slot = slots[index];
        self.timed(encoder, "depth", |encoder| {
            self.depth
                .encode(encoder, frame.scene, frame.targets, views, slot, index == 0);
        });
        // The limit faces' stand-in radiance and the glossy images' fog
        // radiance are constant terms, switched with the emitters'.
        let constant_terms = limit && frame.graph_terms.emission;
        if let Some(specular) = &self.specular {
            for &(face, child) in &tree.children[index] {
                self.timed(encoder, "specular masks", |encoder| {
                    specular.encode_mask(encoder, frame.scene, frame.targets, views, slot, face);
                });
                self.draw_window(ctx, encoder, frame, light, views, tree, slots, child, limit)?;
                self.timed(encoder, "specular masks", |encoder| {
                    specular.encode_restore_child(
                        ctx,
                        encoder,
                        frame.scene,
                        frame.targets,
                        views,
                        slot,
                        slots[child],
                        face,
                        tree.samples[child],
                        constant_terms,
                    );
                });
            }
            if constant_terms {
                self.timed(encoder, "specular masks", |encoder| {
                    specular.encode_limit(
                        encoder,
                        frame.scene,
                        frame.targets,
                        views,
                        slot,
                        &tree.limit_faces[index],
                    );
                });
            }
        }
        for pass in light {
            self.timed(encoder, pass.name(), |encoder| {
                pass.encode_view(ctx, encoder, frame, views, slot)
            })?;
        }
        Ok(())
    }
}

/// Whether [`FrameGraph::render_accumulated`] jitters the splat pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AccumulatedSplats {
    /// Splats drawn in every jittered frame (every edge antialiased, `N` times the fill).
    EverySample,
    /// Splats drawn once through the pixel centres over the average.
    Once,
}

/// A frame's inputs paired with the graph's passes.
#[derive(Clone, Copy)]
struct ResolvedPasses<'a> {
    splat: Option<(SplatInputs<'a>, &'a SplatPass)>,
    direct: Option<(&'a DirectLights, &'a DirectPass)>,
    diffuse: Option<(&'a DiffuseTextures, &'a DiffuseTexturePass)>,
}

/// Clears the HDR target to zero radiance, the start of light accumulation (section 7.2).
pub fn clear_hdr(encoder: &mut wgpu::CommandEncoder, targets: &RenderTargets) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear-hdr"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &targets.hdr.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
}
