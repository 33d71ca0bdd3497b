//! Direct light under shadow volumes instead of shadow maps (Diefenbach &
//! Badler 1997, sections 4.1 and 7.2): per view and per point light, the
//! view's area is set to `SHAD_ZERO`, the light's volumes are counted into
//! the stencil with the depth-fail rule, the light is added without its
//! shadow map where the count left the stencil at `SHAD_ZERO`, and the area
//! is given back to the view (section 7.3); every light of a view, and
//! its virtual lights ([`crate::passes::light_volume`]), in one render pass
//! over the HDR target. As a [`LightPass`] it runs at every level of the
//! specular recursion.
//!
//! The volumes ([`ShadowVolumeSet`]) are built for the lights' positions
//! when [`ShadowVolumes`] is made and rebuilt, and re-uploaded, only for the
//! objects or lights that moved ([`ShadowVolumes::refresh`], section 4.3).
//! Every frame [`ShadowVolumes::prepare`] writes the direct lights' current
//! positions as the points the far vertices are extruded from: equal to the
//! built positions, the volumes are exact; moved by a jitter (the paired
//! light jitter of section 4.4 between accumulation samples), they follow
//! the pivot approximation without a rebuild ([`VolumeJitter::Pivot`]).
//! Section 4.4 names the two exact alternatives it turns down for speed:
//! recomputing the volumes at each jitter iteration, or storing the entire
//! set of jittered volumes at the start. [`ShadowVolumes::store_jittered`]
//! is the second ([`VolumeJitter::Stored`]): volumes for every jittered
//! position the frames draw, each light then drawn with its own position's
//! volumes, so a face that one jittered light sees and another does not
//! (cornell's large box's front face, whose plane passes through the area
//! light) shadows each light as it should.

use std::sync::Mutex;

use glam::Vec3;
use lustre_geometry::Light;
use lustre_geometry::Scene;
use lustre_geometry::shadow_volume::{ShadowVolumeSet, light_position};

use crate::frame::{FrameInputs, LightPass};
use crate::passes::direct::{DirectLights, DirectPass};
use crate::passes::light_volume::VirtualLights;
use crate::passes::shadow_volume::{ShadowVolumeBuffers, ShadowVolumePass, VolumeLights};
use crate::passes::specular::SpecularFace;
use crate::projective_texture::Window;
use crate::view::{ViewBuffer, ViewSlot};
use crate::virtual_light::VirtualLightSettings;
use crate::{GpuContext, MprError, Result};

/// How the volumes follow the jittered point lights that stand for an area
/// light (Diefenbach & Badler 1997, section 4.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VolumeJitter {
    /// Each light keeps the volumes it was built for, and only their far
    /// vertices follow its jittered position (figure 7's jitter
    /// approximation: the silhouette of the built position is the pivot).
    #[default]
    Pivot,
    /// Volumes for every jittered position drawn, stored at the start (the
    /// paper's "initial storage of the entire set of jittered faces"), each
    /// light drawn with the volumes of its own position: exact.
    Stored,
}

/// The shadow volumes of a scene for a list of point lights, on the GPU
/// (sections 4.1 and 4.3), with the pass that counts them.
#[derive(Debug)]
pub struct ShadowVolumes {
    pass: ShadowVolumePass,
    set: ShadowVolumeSet,
    /// One vertex buffer per distinct light position.
    buffers: Vec<ShadowVolumeBuffers>,
    /// Per light, the index of its volumes in `buffers`: the jittered lights
    /// of one area light share the volumes of its centre (section 4.4).
    volume_of: Vec<usize>,
    /// How the volumes follow jittered lights.
    jitter: VolumeJitter,
    /// Per light, the volumes [`ShadowVolumes::prepare`] chose for this
    /// frame: `volume_of` under [`VolumeJitter::Pivot`], the volumes of each
    /// light's own position under [`VolumeJitter::Stored`].
    drawn: Mutex<Vec<usize>>,
    /// The positions the far vertices are extruded from, written per frame.
    lights: Mutex<VolumeLights>,
    /// The distinct light positions the volumes were built for.
    positions: Vec<Vec3>,
    /// The lights reflected and refracted by specular faces (sections 4.2, 4.3).
    virtual_lights: Option<VirtualLights>,
    /// Per surface, its world box: each view's lit redraws draw the
    /// surfaces that may show in its region, and the virtual lights find
    /// their receivers among them.
    surface_boxes: Vec<[Vec3; 2]>,
}

/// `stored` followed by the positions of `positions` it lacks (distinct, in
/// first-seen order), and per position of `positions` its index there.
fn including(stored: &[Vec3], positions: &[Vec3]) -> (Vec<Vec3>, Vec<usize>) {
    let mut all = stored.to_vec();
    let index = positions
        .iter()
        .map(|p| match all.iter().position(|u| u == p) {
            Some(i) => i,
            None => {
                all.push(*p);
                all.len() - 1
            }
        })
        .collect();
    (all, index)
}

fn geometry_error(e: lustre_geometry::GeometryError) -> MprError {
    MprError::InvalidSetting {
        what: "shadow volumes",
        message: e.to_string(),
    }
}

impl ShadowVolumes {
    /// Builds the volumes of every object of `scene` for each of `lights` (at
    /// [`light_position`]; the point lights the direct pass draws, in the
    /// same order) and uploads them, for HDR targets of `hdr_format` (section
    /// 4.1). Fails without a stencil, or on a light position that is not finite.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &Scene,
        lights: &[Light],
    ) -> Result<Self> {
        let pass = ShadowVolumePass::new(ctx, hdr_format)?;
        let positions: Vec<Vec3> = lights.iter().map(light_position).collect();
        let (unique, volume_of) = including(&[], &positions);
        let set = ShadowVolumeSet::new(scene, &unique).map_err(geometry_error)?;
        let buffers = (0..unique.len())
            .map(|i| ShadowVolumeBuffers::upload(ctx, set.volumes_for_light(i)))
            .collect::<Result<Vec<_>>>()?;
        let mut volume_lights = VolumeLights::new(ctx, &pass, positions.len());
        volume_lights.write(ctx, &pass, &positions)?;
        Ok(Self {
            pass,
            set,
            buffers,
            drawn: Mutex::new(volume_of.clone()),
            volume_of,
            jitter: VolumeJitter::Pivot,
            lights: Mutex::new(volume_lights),
            positions: unique,
            virtual_lights: None,
            surface_boxes: crate::view::surface_boxes(scene),
        })
    }

    /// Adds the virtual lights of `faces` (the specular pass's faces, and
    /// the faces of `windows`, section 4.5) for these lights, with their
    /// light and shadow volumes (sections 4.2, 4.3); `settings.depth == 0`
    /// removes them.
    pub fn with_virtual_lights(
        mut self,
        ctx: &GpuContext,
        scene: &Scene,
        faces: &[SpecularFace],
        windows: &[Window],
        settings: VirtualLightSettings,
    ) -> Result<Self> {
        self.virtual_lights = if settings.depth == 0 || faces.is_empty() {
            None
        } else {
            Some(VirtualLights::new(
                ctx,
                &self.pass,
                scene,
                &self.set,
                faces,
                windows,
                &self.positions,
                settings,
            )?)
        };
        Ok(self)
    }

    /// Shadow-volume generations per image over all lights: per light 1,
    /// plus its virtual lights' drawn stretches (equation 7's count, section 8.1).
    pub fn shadow_generations(&self) -> usize {
        self.volume_of
            .iter()
            .map(|&c| {
                self.virtual_lights
                    .as_ref()
                    .map_or(1, |v| v.shadow_generations(c))
            })
            .sum()
    }

    /// The virtual lights, if any.
    pub fn virtual_lights(&self) -> Option<&VirtualLights> {
        self.virtual_lights.as_ref()
    }

    /// The distinct light positions the volumes are built for, and per
    /// light the index of its position.
    pub fn positions(&self) -> (&[Vec3], &[usize]) {
        (&self.positions, &self.volume_of)
    }

    /// Rebuilds the volumes of the objects and lights that moved since they
    /// were built (section 4.3) and re-uploads the buffers of the lights
    /// whose volumes changed; nothing is uploaded when nothing moved. Returns
    /// the number of volumes rebuilt.
    pub fn refresh(&mut self, ctx: &GpuContext, scene: &Scene, lights: &[Light]) -> Result<usize> {
        let all_positions: Vec<Vec3> = lights.iter().map(light_position).collect();
        // The stored jittered positions stay, with the lights' own added.
        let (positions, volume_of) = including(self.stored_positions(), &all_positions);
        self.volume_of = volume_of;
        self.rebuild(ctx, scene, positions)
    }

    /// Stores volumes for every light position of `sets` beside those built
    /// already, and draws each light from now on with the volumes of its own
    /// position ([`VolumeJitter::Stored`], section 4.4's initial storage of
    /// the jittered volumes): `sets` are the point lights of the frame's
    /// accumulation samples (the direct lights of each, in their order), and
    /// a later [`ShadowVolumes::prepare`] fails for a light whose position is
    /// in none of the sets stored. Returns the number of volumes built (0
    /// when every position was stored already). Fails when the sets differ
    /// in length from the lights the volumes were made for, or on a light
    /// position that is not finite.
    pub fn store_jittered(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        sets: &[Vec<Light>],
    ) -> Result<usize> {
        if let Some(set) = sets.iter().find(|set| set.len() != self.volume_of.len()) {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!(
                    "a jittered set of {} lights for volumes of {} lights",
                    set.len(),
                    self.volume_of.len()
                ),
            });
        }
        let all_positions: Vec<Vec3> = sets.iter().flatten().map(light_position).collect();
        let (positions, index) = including(self.stored_positions(), &all_positions);
        self.jitter = VolumeJitter::Stored;
        if !sets.is_empty() {
            // The first set's own volumes until `prepare` chooses a frame's.
            self.volume_of = index[..self.volume_of.len()].to_vec();
            *self.drawn.lock().unwrap_or_else(|e| e.into_inner()) = self.volume_of.clone();
        }
        if positions == self.positions {
            return Ok(0);
        }
        self.rebuild(ctx, scene, positions)
    }

    /// How the volumes follow jittered lights.
    pub fn jitter(&self) -> VolumeJitter {
        self.jitter
    }

    /// The positions whose volumes a rebuild keeps: the stored jittered ones under [`VolumeJitter::Stored`], none under [`VolumeJitter::Pivot`].
    fn stored_positions(&self) -> &[Vec3] {
        match self.jitter {
            VolumeJitter::Pivot => &[],
            VolumeJitter::Stored => &self.positions,
        }
    }

    /// Rebuilds and re-uploads the volumes for `positions` (the distinct
    /// light positions, in the order of `buffers`): only those of moved
    /// objects and lights when the count is unchanged (section 4.3).
    fn rebuild(&mut self, ctx: &GpuContext, scene: &Scene, positions: Vec<Vec3>) -> Result<usize> {
        let old = self.set.lights().to_vec();
        let rebuilt = self
            .set
            .refresh(scene, &positions)
            .map_err(geometry_error)?;
        if rebuilt == 0 {
            return Ok(0);
        }
        self.surface_boxes = crate::view::surface_boxes(scene);
        self.positions = positions.clone();
        if let Some(v) = self.virtual_lights.take() {
            // Virtual lights depend on every caster and light: rebuilt whole.
            let (faces, windows, settings) =
                (v.faces().to_vec(), v.windows().to_vec(), v.settings());
            self.virtual_lights = Some(VirtualLights::new(
                ctx, &self.pass, scene, &self.set, &faces, &windows, &positions, settings,
            )?);
        }
        let moved: Vec<usize> = (0..positions.len())
            .filter(|&i| old.get(i) != Some(&positions[i]))
            .collect();
        // Only the moved lights' volumes were rebuilt unless an object moved too.
        let all = positions.len() != old.len() || rebuilt > moved.len() * self.set.casters().len();
        let upload: Vec<usize> = if all {
            (0..positions.len()).collect()
        } else {
            moved
        };
        self.buffers.truncate(positions.len());
        for i in upload {
            let buffers = ShadowVolumeBuffers::upload(ctx, self.set.volumes_for_light(i))?;
            if i < self.buffers.len() {
                self.buffers[i] = buffers;
            } else {
                self.buffers.push(buffers);
            }
        }
        Ok(rebuilt)
    }

    /// Writes the current positions of `direct`'s lights as the points the
    /// volumes are extruded from this frame (section 4.4: a jittered light
    /// pivots the volumes built for its unjittered position). Fails when
    /// `direct` has another number of lights than the volumes.
    pub fn prepare(
        &self,
        ctx: &GpuContext,
        direct_pass: &DirectPass,
        direct: &DirectLights,
    ) -> Result<()> {
        if direct.len() != self.volume_of.len() {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!(
                    "{} direct lights for shadow volumes built for {} lights",
                    direct.len(),
                    self.volume_of.len()
                ),
            });
        }
        let positions: Vec<Vec3> = direct.lights().map(|l| l.position()).collect();
        let drawn = match self.jitter {
            VolumeJitter::Pivot => self.volume_of.clone(),
            VolumeJitter::Stored => positions
                .iter()
                .map(|p| {
                    self.positions.iter().position(|q| q == p).ok_or_else(|| {
                        MprError::InvalidSetting {
                            what: "shadow volumes",
                            message: format!(
                                "no stored volumes for the light at {p} \
                                 (ShadowVolumes::store_jittered with this frame's jittered lights)"
                            ),
                        }
                    })
                })
                .collect::<Result<Vec<_>>>()?,
        };
        let mut lights = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        lights.write(ctx, &self.pass, &positions)?;
        if let Some(v) = &self.virtual_lights {
            v.prepare(
                ctx,
                &self.pass,
                direct_pass,
                direct,
                &drawn,
                &self.surface_boxes,
            )?;
        }
        *self.drawn.lock().unwrap_or_else(|e| e.into_inner()) = drawn;
        Ok(())
    }

    /// The volumes on the CPU.
    pub fn set(&self) -> &ShadowVolumeSet {
        &self.set
    }

    /// The pass that counts them.
    pub fn pass(&self) -> &ShadowVolumePass {
        &self.pass
    }

    /// Records, for the view of `slot`, every light of `direct` under its
    /// volumes (sections 4.1, 7.2, 7.3), in one render pass over the HDR
    /// target: per light the begin, the volume count, the light without its
    /// shadow map where the stencil is `SHAD_ZERO`, the restore of the view's
    /// reference, then its virtual lights. Run after [`ShadowVolumes::prepare`]
    /// in the same submission.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: &DirectPass,
        frame: &FrameInputs<'_>,
        direct: &DirectLights,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        let lights = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        if direct.len() != self.volume_of.len() || lights.len() != self.volume_of.len() {
            return Err(MprError::InvalidSetting {
                what: "shadow volumes",
                message: format!(
                    "{} direct lights and {} prepared positions for volumes of {} lights \
                     (call ShadowVolumes::prepare)",
                    direct.len(),
                    lights.len(),
                    self.volume_of.len()
                ),
            });
        }
        // One render pass for every light of the view: the stencil steps of
        // each light follow one another in it.
        let mut render = ShadowVolumePass::begin_pass(
            encoder,
            frame.targets,
            &frame.targets.hdr.view,
            "shadowed-direct",
        );
        // Every step stays inside the view's region (its stencil area's bound).
        let (width, height) = (frame.targets.width, frame.targets.height);
        let region = slot.scissor_in(width, height);
        let [x, y, w, h] = region;
        if w == 0 || h == 0 {
            return Ok(());
        }
        render.set_scissor_rect(x, y, w, h);
        let visible = crate::view::surfaces_in_region(
            &self.surface_boxes,
            slot.view_projection,
            region,
            width,
            height,
        );
        let drawn = self.drawn.lock().unwrap_or_else(|e| e.into_inner());
        for (i, &volume) in drawn.iter().enumerate() {
            // Inside a glossy image, only the view's group of lights
            // (weighted by the blend constant, `crate::light_group`).
            if !slot.lights.draws(i) {
                continue;
            }
            let buffers = &self.buffers[volume];
            self.pass
                .record_begin(&mut render, slot.stencil_reference)?;
            self.pass
                .record_volumes(&mut render, views, slot, &lights, i, buffers)?;
            pass.record_light_on_surfaces_under_stencil(
                &mut render,
                frame.scene,
                direct,
                i,
                views,
                slot,
                &visible,
            )?;
            self.pass.record_end(&mut render, slot.stencil_reference)?;
            if let Some(v) = &self.virtual_lights {
                v.record_view(
                    &mut render,
                    &self.pass,
                    pass,
                    frame,
                    views,
                    slot,
                    i,
                    volume,
                    &visible,
                )?;
            }
        }
        Ok(())
    }
}

/// The direct pass with shadow volumes in place of shadow maps, as one
/// [`LightPass`] of the frame (Diefenbach & Badler 1997, sections 4.1, 7.1–7.3).
#[derive(Debug, Clone, Copy)]
pub struct ShadowedDirect<'a> {
    /// The direct pass whose unshadowed pipeline adds each light.
    pub direct: &'a DirectPass,
    /// The volumes and their pass.
    pub volumes: &'a ShadowVolumes,
}

impl LightPass for ShadowedDirect<'_> {
    fn name(&self) -> &'static str {
        "direct light (shadow volumes)"
    }

    fn encode_view(
        &self,
        _ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        match frame.direct {
            Some(lights) => {
                self.volumes
                    .encode_view(encoder, self.direct, frame, lights, views, slot)
            }
            None => Ok(()),
        }
    }
}
