//! Direct light from point lights with cube shadow maps (Stürzlinger &
//! Bastos 1997, section 2.2.1, "Optimized Rendering Phase": for each light,
//! activate its shadow map and add its direct illumination by redrawing the
//! surfaces with per-pixel Phong-style shading), with its CPU twin.
//!
//! Per pixel and light, `L = f_r(wi, wo) I(wi) cos θi / d² · V`: the BRDF of
//! the pixel's material ([`GpuMaterial`], exact or Diefenbach's fitted Phong,
//! [`GlossyModel`]), the intensity `I` of the light towards the pixel as
//! `Light::sample_direct` defines it (isotropic `I`, cosine `I₀ max(cos, 0)`,
//! Mitsuba's spot fall-off), and the visibility `V` from the light's
//! [`ShadowCube`] with the bias of [`ShadowSettings::bias`]. Surfaces are
//! two-sided: the interpolated shading normal is flipped to the viewer's
//! side, as the CPU estimators do. The scene is redrawn with depth test
//! `Equal` against the depth pre-pass (read-only depth) and added One/One
//! into the HDR target; the vertex stage computes its position exactly as
//! `depth.wgsl` does and both mark it `@invariant`, which keeps the depths
//! bit-identical (checked on lavapipe by the tests).
//!
//! Area lights are not rendered here as such: the paper replaces small area
//! lights by point lights of equal power (section 3), which
//! `AreaLight::to_oriented_point` does, and Diefenbach & Badler 1997 (section
//! 4.4) by `K` jittered point lights of power `Φ/K` each, which soften the
//! shadows (`lustre_geometry::light::jittered_point_lights`,
//! [`DirectLights::jittered`], [`direct_pixels_cpu_with_lights`]); passing an
//! area light itself is an error.
//!
//! A frame: [`DirectPass::encode_shadows`] once per light or scene pose,
//! then per view, after the depth pre-pass, [`DirectPass::encode`].

use std::cell::Cell;

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Vec2, Vec3};
use lustre_brdf::models::{DiefenbachPhong, Mixture};
use lustre_brdf::{BoxedBrdf, Fresnel};
use lustre_geometry::light::{Light, jittered_point_lights};
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, Camera, Ray, Rgb, Scene};

use crate::diffuse_map::{DiffuseMaps, WHITE_LAYER};
use crate::material::{GlossyModel, GpuMaterial, scene_materials};
use crate::passes::redraw::{
    ScenePipeline, scene_module, scene_pipeline, weighted_additive_target,
};
use crate::passes::shadow::{ShadowCube, ShadowPass, ShadowSettings};
use crate::passes::shadow_volume::SHAD_ZERO;
use crate::scene_buffers::SceneBuffers;
use crate::shaders::direct_wgsl;
use crate::target::{NO_SURFACE, RenderTargets};
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// `GpuLight::kind` of an isotropic point light.
pub const LIGHT_POINT: u32 = 0;
/// `GpuLight::kind` of a cosine (oriented) point light.
pub const LIGHT_ORIENTED_POINT: u32 = 1;
/// `GpuLight::kind` of a spot light.
pub const LIGHT_SPOT: u32 = 2;

/// One point light and its shadow lookup (`DirectLight` in `direct.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Light position in m.
    pub position: [f32; 3],
    /// [`LIGHT_POINT`], [`LIGHT_ORIENTED_POINT`] or [`LIGHT_SPOT`].
    pub kind: u32,
    /// Intensity in W/sr: `I`, `I₀` along the normal, or the spot's on-axis intensity.
    pub intensity: [f32; 3],
    /// Spot cut-off half-angle in radians.
    pub cutoff_angle: f32,
    /// Unit emission axis (oriented point normal, spot direction).
    pub axis: [f32; 3],
    /// Spot beam-width half-angle in radians.
    pub beam_width: f32,
    /// [`ShadowSettings::constant_bias`].
    pub constant_bias: f32,
    /// [`ShadowSettings::slope_bias`] times [`ShadowSettings::texel_angle`].
    pub slope_bias: f32,
    /// [`ShadowSettings::max_slope`].
    pub max_slope: f32,
    /// Padding to 16 bytes.
    pub pad: f32,
    /// The window this light passes, if any (Diefenbach & Badler 1997,
    /// section 4.5): its slide projector and the window's frame.
    pub window: GpuWindow,
}

/// A virtual light's projective texture (section 4.5, `WindowProjector` in
/// `direct.wgsl`): texture coordinates `(s q, t q, ·, q) = projector · P`
/// for a shaded point `P`, and the window's frame in the space where it
/// lies, where the light crossing it at `X = origin + s u + t v` came from
/// `source` (for the slab's Fresnel transmittance at that angle).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuWindow {
    /// [`crate::projective_texture::Projector::matrix`] after the later
    /// faces' transforms are undone, column major.
    pub projector: [[f32; 4]; 4],
    /// The rectangle's corner; `w` the panes' index of refraction.
    pub origin: [f32; 4],
    /// The edge along `s`; `w` the texture layer, negative without a window.
    pub u: [f32; 4],
    /// The edge along `t`.
    pub v: [f32; 4],
    /// The (virtual) light the window is lit from.
    pub source: [f32; 4],
}

impl GpuWindow {
    /// No window: the light is not modulated.
    pub const NONE: Self = Self {
        projector: [[0.0; 4]; 4],
        origin: [0.0; 4],
        u: [0.0, 0.0, 0.0, -1.0],
        v: [0.0; 4],
        source: [0.0; 4],
    };
}

/// The error for an area light handed to a point-light pass.
fn area_light_error(index: usize) -> MprError {
    MprError::InvalidSetting {
        what: "direct light",
        message: format!(
            "light #{index} is an area light; the direct pass takes point lights only: \
             convert it with AreaLight::to_oriented_point (a point light of equal power, \
             Stürzlinger & Bastos 1997, section 3)"
        ),
    }
}

impl GpuLight {
    /// The GPU form of a point, oriented point or spot light; an area light is [`MprError::InvalidSetting`].
    pub fn new(index: usize, light: &Light, settings: &ShadowSettings) -> Result<Self> {
        let mut out = Self {
            constant_bias: settings.constant_bias,
            slope_bias: settings.slope_bias * settings.texel_angle(),
            max_slope: settings.max_slope,
            window: GpuWindow::NONE,
            ..Self::zeroed()
        };
        match light {
            Light::Point(p) => {
                out.kind = LIGHT_POINT;
                out.position = p.position.to_array();
                out.intensity = p.intensity.to_array();
            }
            Light::OrientedPoint(p) => {
                out.kind = LIGHT_ORIENTED_POINT;
                out.position = p.position.to_array();
                out.intensity = p.intensity.to_array();
                out.axis = p.normal.normalize().to_array();
            }
            Light::Spot(s) => {
                out.kind = LIGHT_SPOT;
                out.position = s.position.to_array();
                out.intensity = s.intensity.to_array();
                out.axis = s.direction.normalize().to_array();
                out.cutoff_angle = s.cutoff_angle;
                out.beam_width = s.beam_width;
            }
            Light::Area(_) => return Err(area_light_error(index)),
        }
        Ok(out)
    }

    /// The light's position.
    pub fn position(&self) -> Vec3 {
        Vec3::from_array(self.position)
    }

    /// The virtual light seen through specular faces whose transforms compose
    /// to `m` (Diefenbach & Badler 1997, section 4.2: a reflected or
    /// refracted light): position mapped by `m`, emission axis by its linear
    /// part, intensity times `factor` (the faces' reflectance or transmittance).
    pub fn through(&self, m: Affine3A, factor: Vec3) -> Self {
        let axis = m.matrix3 * Vec3::from_array(self.axis);
        Self {
            position: m.transform_point3(self.position()).to_array(),
            intensity: (Vec3::from_array(self.intensity) * factor).to_array(),
            axis: axis.normalize_or_zero().to_array(),
            ..*self
        }
    }
}

/// Fails when a material's diffuse map layer is not in `maps`.
pub(crate) fn check_layers(materials: &[GpuMaterial], maps: &DiffuseMaps) -> Result<()> {
    let layers = maps.layers().iter().copied().max().unwrap_or(WHITE_LAYER);
    match materials.iter().position(|m| m.diffuse_map[0] > layers) {
        Some(i) => Err(MprError::InvalidSetting {
            what: "direct materials",
            message: format!(
                "material {i} reads diffuse map layer {}, the maps have {}",
                materials[i].diffuse_map[0],
                layers + 1
            ),
        }),
        None => Ok(()),
    }
}

/// One light's uniform block, shadow cube and bind group.
#[derive(Debug)]
struct LightSlot {
    light: Cell<GpuLight>,
    uniforms: wgpu::Buffer,
    cube: ShadowCube,
    bind_group: wgpu::BindGroup,
}

/// The lights and materials the direct pass shades with: per light a
/// [`GpuLight`] and its [`ShadowCube`], and the scene's [`GpuMaterial`]s.
#[derive(Debug)]
pub struct DirectLights {
    slots: Vec<LightSlot>,
    materials: wgpu::Buffer,
    material_count: usize,
    settings: ShadowSettings,
    maps: DiffuseMaps,
}

impl DirectLights {
    /// The scene's lights and materials (flattened with `glossy`), default [`ShadowSettings`].
    pub fn new(
        ctx: &GpuContext,
        pass: &DirectPass,
        scene: &Scene,
        glossy: GlossyModel,
    ) -> Result<Self> {
        Self::with_settings_and_maps(
            ctx,
            pass,
            scene.lights(),
            &scene_materials(scene, glossy)?,
            ShadowSettings::default(),
            DiffuseMaps::upload(ctx, scene)?,
        )
    }

    /// The scene's lights with each area light as `k` jittered point lights
    /// (Diefenbach & Badler 1997, section 4.4; `k = 1`: one point light of
    /// equal power, Stürzlinger & Bastos 1997, section 3), default [`ShadowSettings`].
    pub fn jittered(
        ctx: &GpuContext,
        pass: &DirectPass,
        scene: &Scene,
        glossy: GlossyModel,
        k: u32,
    ) -> Result<Self> {
        Self::jittered_with_maps(
            ctx,
            pass,
            scene,
            glossy,
            k,
            DiffuseMaps::upload(ctx, scene)?,
        )
    }

    /// [`DirectLights::jittered`] with the scene's diffuse maps already uploaded ([`DiffuseMaps::upload`] of `scene`), to share them with other passes.
    pub fn jittered_with_maps(
        ctx: &GpuContext,
        pass: &DirectPass,
        scene: &Scene,
        glossy: GlossyModel,
        k: u32,
        maps: DiffuseMaps,
    ) -> Result<Self> {
        Self::with_settings_and_maps(
            ctx,
            pass,
            &jittered_point_lights(scene.lights(), k, Vec2::ZERO),
            &scene_materials(scene, glossy)?,
            ShadowSettings::default(),
            maps,
        )
    }

    /// Explicit point lights, materials (in `MaterialId` order) and shadow settings, without diffuse maps (materials' map layers are ignored).
    pub fn with_settings(
        ctx: &GpuContext,
        pass: &DirectPass,
        lights: &[Light],
        materials: &[GpuMaterial],
        settings: ShadowSettings,
    ) -> Result<Self> {
        let mut materials = materials.to_vec();
        for m in &mut materials {
            m.diffuse_map[0] = WHITE_LAYER;
        }
        Self::with_settings_and_maps(
            ctx,
            pass,
            lights,
            &materials,
            settings,
            DiffuseMaps::white(ctx)?,
        )
    }

    /// [`DirectLights::with_settings`] with the scene's diffuse maps, which the materials' layers index ([`crate::material::scene_materials`]).
    pub fn with_settings_and_maps(
        ctx: &GpuContext,
        pass: &DirectPass,
        lights: &[Light],
        materials: &[GpuMaterial],
        settings: ShadowSettings,
        maps: DiffuseMaps,
    ) -> Result<Self> {
        settings.validate(ctx)?;
        check_layers(materials, &maps)?;
        let gpu_lights = lights
            .iter()
            .enumerate()
            .map(|(i, l)| GpuLight::new(i, l, &settings))
            .collect::<Result<Vec<_>>>()?;
        let mut material_data = materials.to_vec();
        if material_data.is_empty() {
            // A zero-sized storage buffer cannot be bound; no triangle indexes this one.
            material_data.push(GpuMaterial::zeroed());
        }
        let materials_buffer = ctx.checked("direct material upload", || {
            wgpu::util::DeviceExt::create_buffer_init(
                &ctx.device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("direct-materials"),
                    contents: bytemuck::cast_slice(&material_data),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                },
            )
        })?;
        let slots = gpu_lights
            .into_iter()
            .map(|light| Self::slot(ctx, pass, &materials_buffer, light, &settings, None, &maps))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            slots,
            materials: materials_buffer,
            material_count: materials.len(),
            settings,
            maps,
        })
    }

    /// Point lights given in GPU form that share `self`'s materials and have
    /// no shadow map (a one-texel cube that no pass draws): the virtual
    /// lights of Diefenbach & Badler 1997, section 4.2, drawn only under the
    /// stencil of their light and shadow volumes
    /// ([`DirectPass::record_light_under_stencil`]). Lights with a
    /// [`GpuWindow`] read their layer of `windows` (a 2-D array texture of
    /// the windows' transmittance, section 4.5).
    pub fn unshadowed_like(
        &self,
        ctx: &GpuContext,
        pass: &DirectPass,
        lights: &[GpuLight],
        windows: Option<&wgpu::TextureView>,
    ) -> Result<Self> {
        let settings = ShadowSettings {
            size: 1,
            ..self.settings
        };
        let slots = lights
            .iter()
            .map(|&light| {
                Self::slot(
                    ctx,
                    pass,
                    &self.materials,
                    light,
                    &settings,
                    windows,
                    &self.maps,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            slots,
            materials: self.materials.clone(),
            material_count: self.material_count,
            settings,
            maps: self.maps.clone(),
        })
    }

    /// Whether `other` reads the same material buffer (see [`DirectLights::unshadowed_like`]).
    pub fn shares_materials(&self, other: &DirectLights) -> bool {
        self.materials == other.materials
    }

    /// Rewrites the lights (same count) from their GPU form, applied at the
    /// next submit; their shadow cubes are not redrawn (for
    /// [`DirectLights::unshadowed_like`] lights, which have none).
    pub fn set_gpu_lights(&self, queue: &wgpu::Queue, lights: &[GpuLight]) -> Result<()> {
        if lights.len() != self.slots.len() {
            return Err(MprError::InvalidSetting {
                what: "direct lights",
                message: format!(
                    "{} lights given for {} slots",
                    lights.len(),
                    self.slots.len()
                ),
            });
        }
        for (slot, &light) in self.slots.iter().zip(lights) {
            slot.light.set(light);
            queue.write_buffer(&slot.uniforms, 0, bytemuck::bytes_of(&light));
        }
        Ok(())
    }

    /// One light's uniform block, shadow cube of `settings.size` and bind group.
    fn slot(
        ctx: &GpuContext,
        pass: &DirectPass,
        materials_buffer: &wgpu::Buffer,
        light: GpuLight,
        settings: &ShadowSettings,
        windows: Option<&wgpu::TextureView>,
        maps: &DiffuseMaps,
    ) -> Result<LightSlot> {
        let cube = pass.shadow.create_cube(ctx, settings.size)?;
        let (uniforms, bind_group) = ctx.checked("direct light creation", || {
            let uniforms = wgpu::util::DeviceExt::create_buffer_init(
                &ctx.device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("direct-light"),
                    contents: bytemuck::bytes_of(&light),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                },
            );
            let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("direct-light"),
                layout: &pass.light_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: materials_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: uniforms.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&cube.view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Sampler(&pass.shadow_sampler),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(
                            windows.unwrap_or(&pass.no_windows),
                        ),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::Sampler(&pass.window_sampler),
                    },
                    maps.entries(6)[0].clone(),
                    maps.entries(6)[1].clone(),
                ],
            });
            (uniforms, bind_group)
        })?;
        pass.shadow
            .prepare(&ctx.queue, &cube, light.position(), settings.near);
        Ok(LightSlot {
            light: Cell::new(light),
            uniforms,
            cube,
            bind_group,
        })
    }

    /// Moves or changes the lights (same count as before); their shadow cubes
    /// must then be redrawn with [`DirectPass::encode_shadows`]. Takes `&self`
    /// so that a frame in progress can move its jittered lights between
    /// accumulation samples (Diefenbach & Badler 1997, section 4.4).
    pub fn set_lights(
        &self,
        pass: &DirectPass,
        queue: &wgpu::Queue,
        lights: &[Light],
    ) -> Result<()> {
        if lights.len() != self.slots.len() {
            return Err(MprError::InvalidSetting {
                what: "direct lights",
                message: format!(
                    "{} lights given for {} shadow cubes; build new DirectLights to change the count",
                    lights.len(),
                    self.slots.len()
                ),
            });
        }
        let gpu_lights = lights
            .iter()
            .enumerate()
            .map(|(i, l)| GpuLight::new(i, l, &self.settings))
            .collect::<Result<Vec<_>>>()?;
        for (slot, light) in self.slots.iter().zip(gpu_lights) {
            slot.light.set(light);
            queue.write_buffer(&slot.uniforms, 0, bytemuck::bytes_of(&light));
            pass.shadow
                .prepare(queue, &slot.cube, light.position(), self.settings.near);
        }
        Ok(())
    }

    /// The diffuse maps the materials' layers index.
    pub fn diffuse_maps(&self) -> &DiffuseMaps {
        &self.maps
    }

    /// Replaces the materials (same count), e.g. with another [`GlossyModel`]'s [`scene_materials`]; their map layers must exist in [`DirectLights::diffuse_maps`].
    pub fn set_materials(&self, queue: &wgpu::Queue, materials: &[GpuMaterial]) -> Result<()> {
        check_layers(materials, &self.maps)?;
        if materials.len() != self.material_count {
            return Err(MprError::InvalidSetting {
                what: "direct materials",
                message: format!(
                    "{} materials given for a buffer of {}",
                    materials.len(),
                    self.material_count
                ),
            });
        }
        if !materials.is_empty() {
            queue.write_buffer(&self.materials, 0, bytemuck::cast_slice(materials));
        }
        Ok(())
    }

    /// Number of lights.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether there is no light.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The lights as the GPU sees them.
    pub fn lights(&self) -> impl Iterator<Item = GpuLight> + '_ {
        self.slots.iter().map(|s| s.light.get())
    }

    /// The shadow cube of light `index`.
    pub fn shadow_cube(&self, index: usize) -> Option<&ShadowCube> {
        self.slots.get(index).map(|s| &s.cube)
    }

    /// The shadow settings in use.
    pub fn settings(&self) -> &ShadowSettings {
        &self.settings
    }
}

/// The line of `direct.wgsl` that switches the shadow-map lookup on.
const SHADOW_MAPS_ON: &str = "const SHADOW_MAPS: bool = true;";

/// The line of `direct.wgsl` that switches the window's projective texture on.
const WINDOWS_ON: &str = "const WINDOWS: bool = true;";

/// `direct.wgsl` with `line` (one of its switches) set to `false`: without
/// [`SHADOW_MAPS_ON`] `V = 1`, for lights drawn under the stencil of shadow
/// volumes (Diefenbach & Badler 1997, section 4.1); without [`WINDOWS_ON`]
/// for lights that pass no window.
fn switched_off(source: String, line: &str) -> Result<String> {
    crate::shaders::switched_off(source, line, "direct pass", "direct.wgsl")
}

/// The pipelines of one window switch: shadow-mapped, and under the
/// shadow volumes' stencil.
#[derive(Debug)]
struct DirectPipelines {
    shadow_mapped: wgpu::RenderPipeline,
    /// The same redraw without the shadow-map lookup, drawn where the stencil
    /// equals `SHAD_ZERO` (Diefenbach & Badler 1997, sections 4.1 and 7.2).
    under_stencil: wgpu::RenderPipeline,
}

/// The GPU direct light pass: its pipelines, light layout and shadow pass.
#[derive(Debug)]
pub struct DirectPass {
    /// For lights that pass a window (section 4.5).
    windowed: DirectPipelines,
    /// For the others: compiled without the window's projective texture.
    unwindowed: DirectPipelines,
    light_layout: wgpu::BindGroupLayout,
    shadow_sampler: wgpu::Sampler,
    /// A one-texel white array texture bound where no light has a window.
    no_windows: wgpu::TextureView,
    /// Bilinear, clamped: the windows' projective textures.
    window_sampler: wgpu::Sampler,
    shadow: ShadowPass,
}

impl DirectPass {
    /// Builds the pipeline for HDR targets of `hdr_format` (which must be blendable):
    /// cull none, depth `Equal` without writes, One/One blending.
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.is_blendable(hdr_format) {
            return Err(MprError::UnsupportedFormat {
                what: "direct pass HDR target (additive blending)",
                format: hdr_format,
            });
        }
        let shadow = ShadowPass::new(ctx)?;
        // Each window switch's sources: (under the stencil, shadow-mapped).
        let with_and_without_shadow_maps = |source: String| {
            Ok::<_, MprError>((switched_off(source.clone(), SHADOW_MAPS_ON)?, source))
        };
        let windowed_sources = with_and_without_shadow_maps(direct_wgsl())?;
        let unwindowed_sources =
            with_and_without_shadow_maps(switched_off(direct_wgsl(), WINDOWS_ON)?)?;
        ctx.checked("direct pass creation", || {
            let device = &ctx.device;
            let maps = DiffuseMaps::layout_entries(6, wgpu::ShaderStages::FRAGMENT);
            let light_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("direct-light"),
                    entries: &[
                        wgpu::BindGroupLayoutEntry {
                            binding: 0,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Buffer {
                                ty: wgpu::BufferBindingType::Storage { read_only: true },
                                has_dynamic_offset: false,
                                min_binding_size: wgpu::BufferSize::new(
                                    size_of::<GpuMaterial>() as u64
                                ),
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 1,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Buffer {
                                ty: wgpu::BufferBindingType::Uniform,
                                has_dynamic_offset: false,
                                min_binding_size: wgpu::BufferSize::new(
                                    size_of::<GpuLight>() as u64
                                ),
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 2,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                                view_dimension: wgpu::TextureViewDimension::Cube,
                                multisampled: false,
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 3,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 4,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                                view_dimension: wgpu::TextureViewDimension::D2Array,
                                multisampled: false,
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 5,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                            count: None,
                        },
                        maps[0],
                        maps[1],
                    ],
                });
            let pipelines = |(under_stencil, shadow_mapped): &(String, String)| {
                let pipeline = |label: &'static str, source: &str| {
                    let module = scene_module(ctx, label, source);
                    scene_pipeline(
                        ctx,
                        &ScenePipeline {
                            label,
                            module: &module,
                            layouts: &[&light_layout],
                            extra_vertex_buffers: &[],
                            target: weighted_additive_target(hdr_format),
                            depth_compare: wgpu::CompareFunction::Equal,
                            depth_write: false,
                        },
                    )
                };
                // Under the stencil: the same stencil state (Equal, no
                // writes); its reference is SHAD_ZERO instead of the view's,
                // set after the view is bound.
                DirectPipelines {
                    under_stencil: pipeline("direct-under-stencil", under_stencil),
                    shadow_mapped: pipeline("direct", shadow_mapped),
                }
            };
            let windowed = pipelines(&windowed_sources);
            let unwindowed = pipelines(&unwindowed_sources);
            let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow-nearest"),
                ..Default::default()
            });
            let window_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("window-bilinear"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            });
            let no_windows = crate::projective_texture::upload_layers(
                device,
                &ctx.queue,
                1,
                1,
                &[vec![[1.0; 4]]],
            );
            Self {
                windowed,
                unwindowed,
                light_layout,
                shadow_sampler,
                no_windows,
                window_sampler,
                shadow,
            }
        })
    }

    /// The shadow pass that draws the lights' cubes.
    pub fn shadow_pass(&self) -> &ShadowPass {
        &self.shadow
    }

    /// Records the shadow cube of every light (section 2.2.1, "construct a
    /// shadow map for each light source"): once per light or scene pose.
    pub fn encode_shadows(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        lights: &DirectLights,
    ) {
        for slot in &lights.slots {
            self.shadow.encode(encoder, scene, &slot.cube);
        }
    }

    /// Records the direct light: one render pass that loads the HDR target
    /// and the depth pre-pass's depth (read only), then per light binds its
    /// shadow cube and adds its light over every scene triangle. Run after
    /// the depth pre-pass and [`DirectPass::encode_shadows`].
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        lights: &DirectLights,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) {
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "direct");
        if scene.vertex_count == 0 || lights.is_empty() {
            return;
        }
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return;
        }
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_blend_constant(slot.lights.blend_constant());
        for (i, light) in lights.slots.iter().enumerate() {
            if !slot.lights.draws(i) {
                continue;
            }
            pass.set_pipeline(&self.pipelines(light).shadow_mapped);
            pass.set_bind_group(1, &light.bind_group, &[]);
            pass.draw(0..scene.vertex_count, 0..1);
        }
    }
}

impl DirectPass {
    /// The pipelines for `light`: without the window's texture unless it passes one.
    fn pipelines(&self, light: &LightSlot) -> &DirectPipelines {
        if light.light.get().window.u[3] >= 0.0 {
            &self.windowed
        } else {
            &self.unwindowed
        }
    }

    /// Records the direct light of light `light_index` alone, without its
    /// shadow map, where the stencil equals [`SHAD_ZERO`] (Diefenbach &
    /// Badler 1997, sections 4.1 and 7.2: a light is added only where the
    /// shadow-volume count left the stencil at zero), into `pass`, which has
    /// the HDR target and the depth pre-pass's depth-stencil attached. The
    /// view of `slot` is bound, then the reference replaced by [`SHAD_ZERO`].
    /// Fails when `light_index` is out of range.
    pub fn record_light_under_stencil(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        scene: &SceneBuffers,
        lights: &DirectLights,
        light_index: usize,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        let Some(light) = lights.slots.get(light_index) else {
            return Err(MprError::InvalidSetting {
                what: "direct light",
                message: format!("light #{light_index} of {}", lights.slots.len()),
            });
        };
        if scene.vertex_count == 0 {
            return Ok(());
        }
        pass.set_pipeline(&self.pipelines(light).under_stencil);
        views.bind(pass, 0, slot);
        pass.set_stencil_reference(SHAD_ZERO);
        pass.set_blend_constant(slot.lights.blend_constant());
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_bind_group(1, &light.bind_group, &[]);
        pass.draw(0..scene.vertex_count, 0..1);
        Ok(())
    }

    /// [`DirectPass::record_light_under_stencil`] over only the triangles of
    /// `surfaces` (the surfaces a light may reach; the rest would add
    /// nothing under the stencil), drawn by their ranges of
    /// [`SceneBuffers::surface_indices`], adjacent ranges merged.
    #[allow(clippy::too_many_arguments)]
    pub fn record_light_on_surfaces_under_stencil(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        scene: &SceneBuffers,
        lights: &DirectLights,
        light_index: usize,
        views: &ViewBuffer,
        slot: ViewSlot,
        surfaces: &[u32],
    ) -> Result<()> {
        let Some(light) = lights.slots.get(light_index) else {
            return Err(MprError::InvalidSetting {
                what: "direct light",
                message: format!("light #{light_index} of {}", lights.slots.len()),
            });
        };
        let ranges = crate::view::surface_draw_ranges(surfaces, &scene.surface_ranges);
        if ranges.is_empty() {
            return Ok(());
        }
        pass.set_pipeline(&self.pipelines(light).under_stencil);
        views.bind(pass, 0, slot);
        pass.set_stencil_reference(SHAD_ZERO);
        pass.set_blend_constant(slot.lights.blend_constant());
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.set_bind_group(1, &light.bind_group, &[]);
        for range in ranges {
            pass.draw_indexed(range, 0, 0..1);
        }
        Ok(())
    }

    /// [`DirectPass::record_light_under_stencil`] in a render pass of its own
    /// over `targets` (HDR loaded, depth and stencil read only): run between
    /// the shadow-volume count of light `light_index` and its restore.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_light_under_stencil(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        lights: &DirectLights,
        light_index: usize,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) -> Result<()> {
        let mut pass =
            crate::passes::redraw::begin_over_depth(encoder, targets, "direct-under-stencil");
        self.record_light_under_stencil(&mut pass, scene, lights, light_index, views, slot)
    }
}

/// [`cpu_brdf`] of every material of `scene`, in `MaterialId` order; errors name the material.
pub fn cpu_brdfs(scene: &Scene, glossy: GlossyModel) -> Result<Vec<BoxedBrdf>> {
    scene
        .materials()
        .iter()
        .map(|m| {
            cpu_brdf(&m.model, glossy).map_err(|e| MprError::UnsupportedMaterial {
                material: m.name.clone(),
                message: e.to_string(),
            })
        })
        .collect()
}

/// The ray through each pixel centre (row 0 at the top) and its closest hit: what the CPU twins shade.
pub fn primary_hits(
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> (Vec<Ray>, Vec<Option<lustre_geometry::Hit>>) {
    let rays: Vec<Ray> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    let hits = bvh.closest_hits(&rays);
    (rays, hits)
}

/// The CPU BRDF of a material model under `glossy`: `lustre_brdf::from_model`,
/// or with Ward and Beckmann lobes replaced by Diefenbach's fitted Phong of the
/// same α (equation 6; a conductor's Fresnel folded into `ks` at normal incidence).
pub fn cpu_brdf(model: &MaterialModel, glossy: GlossyModel) -> lustre_brdf::Result<BoxedBrdf> {
    if glossy == GlossyModel::Exact {
        return lustre_brdf::from_model(model);
    }
    match model {
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha,
            fresnel,
            specular,
        } => {
            let f0 = match fresnel {
                ConductorFresnel::Complex { eta, k } => {
                    Fresnel::Conductor { eta: *eta, k: *k }.eval(1.0)
                }
                ConductorFresnel::None => Rgb::ONE,
            };
            Ok(Box::new(DiefenbachPhong::new(
                Rgb::ZERO,
                *specular * f0,
                *alpha,
            )?))
        }
        MaterialModel::Ward {
            diffuse,
            specular,
            alpha_x,
            alpha_y,
        } if alpha_x == alpha_y => Ok(Box::new(DiefenbachPhong::new(
            *diffuse, *specular, *alpha_x,
        )?)),
        MaterialModel::Blend {
            weight,
            first,
            second,
        } => Ok(Box::new(Mixture::new(vec![
            (1.0 - weight, cpu_brdf(first, glossy)?),
            (*weight, cpu_brdf(second, glossy)?),
        ])?)),
        other => lustre_brdf::from_model(other),
    }
}

/// One pixel of the CPU twin: radiance, the surface seen and which lights reach it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectPixel {
    /// Direct radiance in W/(m² sr).
    pub radiance: [f32; 3],
    /// Surface id of the closest hit ([`NO_SURFACE`] on a miss).
    pub surface: u32,
    /// Bit `j` set when light `j` (`j < 64`) is unoccluded and in front of the shading normal.
    pub visible: u64,
}

/// CPU counterpart of [`DirectPass`] with per-pixel detail: through each
/// pixel centre, the closest hit; per light, `f_r I cos θi / d²` (the weight
/// of `Light::sample_direct`) times a BVH shadow ray from the hit to the light
/// (both ends shortened by `1e-4` of the scene's extent), in the frame of the
/// shading normal flipped to the viewer's side.
pub fn direct_pixels_cpu(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    glossy: GlossyModel,
) -> Result<Vec<DirectPixel>> {
    direct_pixels_cpu_with_lights(scene, scene.lights(), bvh, camera, width, height, glossy)
}

/// [`direct_pixels_cpu`] lit by `lights` (point lights, e.g. an area light's
/// jittered points, Diefenbach & Badler 1997, section 4.4) instead of the scene's.
pub fn direct_pixels_cpu_with_lights(
    scene: &Scene,
    lights: &[Light],
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    glossy: GlossyModel,
) -> Result<Vec<DirectPixel>> {
    let eps = 1e-4 * scene.bounds().extent().max_element().max(1e-6);
    let shadow_ray = |_: usize, p: Vec3, direction: Vec3, distance: f32| {
        (!bvh.any_hit(&Ray::segment(p, direction, eps, distance - eps))).then_some(Rgb::ONE)
    };
    direct_pixels_cpu_where(
        scene,
        lights,
        bvh,
        camera,
        width,
        height,
        glossy,
        &shadow_ray,
    )
}

/// [`direct_pixels_cpu_with_lights`] with the visibility of light `j` from
/// a hit point decided by `reaches(j, point, direction, distance)` (unit
/// direction and distance to the light) instead of a BVH shadow ray: `None`
/// where it is blocked, else the factor its light arrives with. The CPU
/// twin of lights that reach a point along other paths, such as the
/// virtual lights of specular faces ([`crate::virtual_light::path_visible`])
/// and those through stained glass ([`crate::virtual_light::path_arrival`]).
#[allow(clippy::too_many_arguments)]
pub fn direct_pixels_cpu_where(
    scene: &Scene,
    lights: &[Light],
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    glossy: GlossyModel,
    reaches: &dyn Fn(usize, Vec3, Vec3, f32) -> Option<Rgb>,
) -> Result<Vec<DirectPixel>> {
    if let Some(i) = lights.iter().position(|l| !l.is_delta()) {
        return Err(area_light_error(i));
    }
    let brdfs = cpu_brdfs(scene, glossy)?;
    let (rays, hits) = primary_hits(bvh, camera, width, height);
    Ok(rays
        .iter()
        .zip(hits)
        .map(|(ray, hit)| {
            let Some(hit) = hit else {
                return DirectPixel {
                    radiance: [0.0; 3],
                    surface: NO_SURFACE,
                    visible: 0,
                };
            };
            let wo = -ray.direction;
            let n = if hit.shading_normal.dot(wo) < 0.0 {
                -hit.shading_normal
            } else {
                hit.shading_normal
            };
            let frame = Frame::from_normal(n);
            let wo_local = frame.to_local(wo);
            let brdf = &brdfs[hit.material as usize];
            // A diffuse map scales the diffuse part: f + (tint - 1) ρ_d/π above the surface.
            let tint_term = scene.materials()[hit.material as usize].diffuse_shift(hit.uv);
            let mut radiance = Rgb::ZERO;
            let mut visible = 0u64;
            for (j, light) in lights.iter().enumerate() {
                let Some(sample) = light.sample_direct(hit.position, Vec2::ZERO) else {
                    continue;
                };
                let wi_local = frame.to_local(sample.direction);
                if wi_local.z <= 0.0 {
                    continue;
                }
                let Some(factor) = reaches(j, hit.position, sample.direction, sample.distance)
                else {
                    continue;
                };
                if j < 64 {
                    visible |= 1 << j;
                }
                let mut f = brdf.eval(wi_local, wo_local);
                if let Some(term) = tint_term
                    && wo_local.z > 0.0
                {
                    f += term;
                }
                radiance += f * sample.weight * factor * wi_local.z;
            }
            DirectPixel {
                radiance: radiance.to_array(),
                surface: hit.surface,
                visible,
            }
        })
        .collect())
}

/// CPU counterpart of [`DirectPass`]: the direct radiance per pixel (row 0 at the top), see [`direct_pixels_cpu`].
pub fn direct_pass_cpu(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    glossy: GlossyModel,
) -> Result<Vec<[f32; 3]>> {
    Ok(
        direct_pixels_cpu(scene, bvh, camera, width, height, glossy)?
            .into_iter()
            .map(|p| p.radiance)
            .collect(),
    )
}
