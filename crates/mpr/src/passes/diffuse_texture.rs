//! Precomputed textures of diffuse surfaces (Stürzlinger & Bastos 1997,
//! section 2.2.1: "Because the appearance of a diffuse surface does not
//! depend on the viewing direction such surfaces are handled by precomputing
//! the effects of the photons hits in the preprocessing phase and displaying
//! the surface using a Gouraud shaded mesh or textured surfaces"), with its
//! CPU twin.
//!
//! **Preprocessing** ([`DiffuseAtlas::build`]). Every *planar* surface whose
//! material is purely Lambertian ([`GpuMaterial::is_diffuse`]) gets a regular
//! grid of samples over its `(u, v)` bounding rectangle
//! ([`PlanarFrame::min`]..[`PlanarFrame::max`]); sample `(i, j)` lies at
//! `min + (i tᵤ, j tᵥ)`, the outer rows and columns on the rectangle's edges
//! (the vertices of the paper's regular mesh, so the bilinear reconstruction
//! covers the surface without extrapolation). Each sample holds the outgoing
//! radiance of equation 2 for a Lambertian BRDF,
//! `L = ρ/π Σ φ K(·/h)/h²` ([`SplatEstimator::flux_density`] times
//! [`GpuMaterial::diffuse_reflectance`]`/π`), in f32.
//!
//! **Lambertian lobes** ([`DiffuseTextureOptions::lambertian_lobes`],
//! beyond the paper, which textures only diffuse surfaces): a planar surface
//! whose material blends Lambertian lobes with others (the glossy floor:
//! 0.7 Lambert + 0.3 rough mirror) gets a texture of its Lambertian part
//! `Σ w ρ/π` too, and its splats are shaded without those lobes
//! ([`GpuMaterial::without_lambert`]); the sum is the whole material, and the
//! view-independent part is drawn antialiased with a diffuse surface's support.
//!
//! **Sides.** Surfaces are two-sided: the splat pass flips each splat's
//! normal to the viewer and its BRDF is zero for photons that arrived on the
//! other side, so a viewer in front of the plane sees the photons that
//! arrived in front and one behind sees those that arrived behind. Each
//! surface therefore has up to two *layers*, front (the winding side,
//! [`PlanarFrame::normal`]) and back, each `flux_density` evaluated on that
//! side; a side on which no photon arrived has no layer and renders black,
//! as the splats do. Closed scenes store one layer per surface.
//!
//! **Texel size** ([`TexelSize`]): by default a quarter of the surface's
//! kernel support `h` (equation 3). The estimate is a sum of kernels of
//! radius `h`, so it varies on the scale of `h`; bilinear interpolation
//! between samples `t` apart errs by about `t²/8 |L''|`, largest within `h`
//! of a surface's edge where the estimate falls off. Against the splat pass
//! on `cornell` (20k photons, C = 8, 96², `tests/diffuse_texture.rs`) the
//! relative rms difference is 2.1 % at `h/2`, 0.60 % at `h/4` and 0.15 % at
//! `h/8`. The sample count goes as `(A/t²)` per surface, i.e. about
//! `n/(C f)²` for `t = f h` and `n` photons, and the preprocessing as that
//! times the `π C²` photons within `h` of each sample. Per surface the
//! samples per side are capped ([`DiffuseTextureOptions::max_samples_per_side`],
//! the spacing grows to fit), and the atlas side is capped
//! ([`DiffuseTextureOptions::max_atlas_side`], and at upload the device's
//! 2D limit); an atlas that does not fit is an [`MprError::InvalidSetting`].
//!
//! **Atlas.** All layers are packed in shelves into one
//! [`DIFFUSE_ATLAS_FORMAT`] texture (`Rgba32Float`: full precision, read
//! with `textureLoad` and interpolated in the shader, so no sampler, no
//! filterable-float feature and no gutter between layers are needed). A
//! storage buffer of [`GpuDiffuseSurface`], indexed by `SurfaceId`, gives
//! each surface's frame, sample grid and layer origins, or marks it as not
//! textured.
//!
//! **Rendering** ([`DiffuseTexturePass`]). The scene's textured surfaces are
//! redrawn with depth test `Equal` against the depth pre-pass (read-only
//! depth, the `@invariant` position of `depth.wgsl`), each fragment computes
//! `(u, v)` from its world position and adds the bilinear lookup One/One into
//! HDR. A material with a diffuse map ([`crate::diffuse_map`]) is stored
//! with its untextured `ρ` and the lookup is multiplied by the map at the
//! fragment's texture coordinates (irradiance times albedo, as a light map
//! is drawn), so the map stays as sharp as it is, not blurred by the kernel. The splat pass must then leave those surfaces out:
//! [`SplatBuffers::new_excluding`] with [`DiffuseAtlas::textured`].
//!
//! A frame: once, [`DiffuseAtlas::build`] and [`DiffuseTextures::new`]; per
//! view, after the depth pre-pass, [`DiffuseTexturePass::encode`] (in any
//! order with the splat and direct passes, which also add into HDR).
//!
//! [`SplatBuffers::new_excluding`]: crate::passes::splat::SplatBuffers::new_excluding

use std::f32::consts::FRAC_1_PI;
use std::ops::Range;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{UVec2, Vec2, Vec3};
use lustre_geometry::{Bvh, Camera, Rgb, Scene, SurfaceId, Texture};
use lustre_photon::{PlanarFrame, SplatEstimator, SurfaceParam, SurfaceParams};
use rayon::prelude::*;

use crate::diffuse_map::{DiffuseMaps, WHITE_LAYER, diffuse_map_layers};
use crate::material::{GlossyModel, GpuMaterial};
use crate::passes::redraw::{ScenePipeline, additive_target, scene_module, scene_pipeline};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::with_view;
use crate::target::{RenderTargets, check_size};
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The diffuse texture WGSL (`src/passes/diffuse_texture.wgsl`), self-contained.
pub const DIFFUSE_TEXTURE_WGSL: &str = include_str!("diffuse_texture.wgsl");

/// Format of the atlas: f32 RGB radiance (alpha unused), read with `textureLoad`.
pub const DIFFUSE_ATLAS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `GpuDiffuseSurface::layers` entry of a side without a layer.
pub const NO_LAYER: u32 = u32::MAX;

/// How far apart the samples of a diffuse texture are (section 2.2.1 leaves the resolution open).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TexelSize {
    /// This fraction of the surface's kernel support `h` (equation 3).
    Support(f32),
    /// The same spacing on every surface, in metres.
    Metres(f32),
}

/// Settings of the diffuse textures (section 2.2.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseTextureOptions {
    /// Spacing of the samples; default `h/4` (module documentation: 0.6 % rms from the splat image).
    pub texel_size: TexelSize,
    /// Most samples along either side of one surface's texture (at least 2); the spacing grows to fit. Default 1024.
    pub max_samples_per_side: u32,
    /// Largest atlas side in texels; default 4096 (256 MiB of `Rgba32Float` at most).
    pub max_atlas_side: u32,
    /// Also texture the Lambertian lobes of planar surfaces whose material has other lobes too (the glossy floor's diffuse part), leaving the splats of those surfaces their other lobes ([`GpuMaterial::without_lambert`]); `false`, the default, textures only purely Lambertian surfaces as the paper does.
    pub lambertian_lobes: bool,
}

impl Default for DiffuseTextureOptions {
    fn default() -> Self {
        Self {
            texel_size: TexelSize::Support(0.25),
            max_samples_per_side: 1024,
            max_atlas_side: 4096,
            lambertian_lobes: false,
        }
    }
}

impl DiffuseTextureOptions {
    /// Rejects a non-positive or non-finite texel size and caps below their minimum.
    pub fn validate(&self) -> Result<()> {
        let (TexelSize::Support(t) | TexelSize::Metres(t)) = self.texel_size;
        if !(t > 0.0 && t.is_finite()) {
            return Err(MprError::InvalidSetting {
                what: "diffuse texel size",
                message: format!("{t} must be positive and finite"),
            });
        }
        if self.max_samples_per_side < 2 {
            return Err(MprError::InvalidSetting {
                what: "diffuse texture samples per side",
                message: format!("{} must be at least 2", self.max_samples_per_side),
            });
        }
        if self.max_atlas_side == 0 {
            return Err(MprError::InvalidSetting {
                what: "diffuse atlas side",
                message: "0 must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// The side of a two-sided planar surface a viewer is on (section 2.2: the BRDF is evaluated on the viewer's side).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The winding side, [`PlanarFrame::normal`].
    Front,
    /// The other side.
    Back,
}

impl Side {
    /// Both sides, in layer order.
    pub const BOTH: [Side; 2] = [Side::Front, Side::Back];

    /// The side of `frame`'s plane that `eye` sees at `x` (front when `(eye - x) · n ≥ 0`, as the shader and the splat pass decide).
    pub fn seen(frame: &PlanarFrame, x: Vec3, eye: Vec3) -> Self {
        if (eye - x).dot(frame.normal) >= 0.0 {
            Self::Front
        } else {
            Self::Back
        }
    }

    /// Index of the layer of this side (0 front, 1 back).
    pub fn index(self) -> usize {
        match self {
            Self::Front => 0,
            Self::Back => 1,
        }
    }

    /// A direction on this side of `frame`'s plane (the `side` argument of [`SplatEstimator::flux_density`]).
    pub fn direction(self, frame: &PlanarFrame) -> Vec3 {
        match self {
            Self::Front => frame.normal,
            Self::Back => -frame.normal,
        }
    }
}

/// The texture of one diffuse planar surface: its frame, sample grid, reflectance and the atlas position of each side's layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseSurfaceTexture {
    /// The surface's `(u, v)` frame and bounds (section 3.1).
    pub frame: PlanarFrame,
    /// Lambertian reflectance `ρ`.
    pub reflectance: Rgb,
    /// Samples along u and v (1 along a degenerate axis, else at least 2).
    pub size: UVec2,
    /// Distance between samples along u and v in m (positive).
    pub spacing: Vec2,
    /// Atlas texel of sample `(0, 0)` of the front and back layers ([`Side::index`]); `None` where no photon arrived on that side.
    pub layers: [Option<UVec2>; 2],
    /// The layer of the material's diffuse map ([`crate::diffuse_map::diffuse_map_layers`]; [`WHITE_LAYER`]: none), which scales the stored radiance where it is drawn.
    pub diffuse_map: u32,
}

impl DiffuseSurfaceTexture {
    /// `(u, v)` of sample `(i, j)`.
    pub fn sample_uv(&self, i: u32, j: u32) -> Vec2 {
        self.frame.min + Vec2::new(i as f32, j as f32) * self.spacing
    }

    /// World position of sample `(i, j)`.
    pub fn sample_point(&self, i: u32, j: u32) -> Vec3 {
        self.frame.to_world(self.sample_uv(i, j))
    }
}

/// The diffuse textures of a scene on the CPU: the atlas texels and each surface's record (the preprocessing of section 2.2.1).
#[derive(Debug, Clone)]
pub struct DiffuseAtlas {
    /// Atlas width in texels.
    pub width: u32,
    /// Atlas height in texels.
    pub height: u32,
    /// RGB radiance (alpha 0) per texel, row-major; texels outside every layer are zero.
    pub texels: Vec<[f32; 4]>,
    /// Per `SurfaceId`: the texture of a diffuse planar surface, `None` for surfaces left to the splat pass.
    pub surfaces: Vec<Option<DiffuseSurfaceTexture>>,
    /// The scene's distinct diffuse maps: layer `i + 1` of [`DiffuseSurfaceTexture::diffuse_map`] is map `i`.
    pub maps: Vec<Arc<Texture>>,
    /// Options used.
    pub options: DiffuseTextureOptions,
}

/// Samples per side along an extent of `extent` m at spacing about `t`, capped at `max`, and the exact spacing.
fn sample_grid(extent: f32, t: f32, max: u32) -> (u32, f32) {
    if !(extent > 0.0) || !(t > 0.0) {
        return (1, 1.0);
    }
    let intervals = (extent / t).ceil().clamp(1.0, (max - 1) as f32) as u32;
    (intervals + 1, extent / intervals as f32)
}

/// Shelf packing of `sizes` into an atlas at most `max_side` wide and high: (width, height, corner of each).
fn pack_shelves(sizes: &[UVec2], max_side: u32) -> Result<(u32, u32, Vec<UVec2>)> {
    if sizes.is_empty() {
        return Ok((1, 1, Vec::new()));
    }
    let too_big = |message: String| MprError::InvalidSetting {
        what: "diffuse atlas",
        message,
    };
    let widest = sizes.iter().map(|s| s.x).max().unwrap_or(1);
    let tallest = sizes.iter().map(|s| s.y).max().unwrap_or(1);
    if widest > max_side || tallest > max_side {
        return Err(too_big(format!(
            "a texture of {widest}x{tallest} samples exceeds the atlas side {max_side}; \
             lower max_samples_per_side"
        )));
    }
    let area: u64 = sizes.iter().map(|s| u64::from(s.x) * u64::from(s.y)).sum();
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(sizes[i].y), std::cmp::Reverse(sizes[i].x)));
    let mut width = widest.max((area as f64).sqrt().ceil() as u32).min(max_side);
    loop {
        let mut corners = vec![UVec2::ZERO; sizes.len()];
        let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
        for &i in &order {
            if x + sizes[i].x > width {
                y += shelf;
                x = 0;
                shelf = 0;
            }
            corners[i] = UVec2::new(x, y);
            x += sizes[i].x;
            shelf = shelf.max(sizes[i].y);
        }
        let height = y + shelf;
        if height <= max_side {
            return Ok((width, height, corners));
        }
        if width == max_side {
            return Err(too_big(format!(
                "{area} texels do not fit in {max_side}x{max_side}; \
                 choose a larger texel size or a larger max_atlas_side"
            )));
        }
        width = width.saturating_mul(2).min(max_side);
    }
}

/// The atlas layers in (surface, side) order: one per lit side of each textured surface.
fn layers_of(surfaces: &[Option<DiffuseSurfaceTexture>]) -> Vec<(usize, Side)> {
    surfaces
        .iter()
        .enumerate()
        .filter_map(|(id, s)| s.as_ref().map(|s| (id, s)))
        .flat_map(|(id, s)| {
            Side::BOTH
                .into_iter()
                .filter(|side| s.layers[side.index()].is_some())
                .map(move |side| (id, side))
        })
        .collect()
}

/// Whether each side of each surface received a photon (by `SurfaceId`, [`Side::index`]); goes through [`SplatEstimator::splats`], one pass over the photons.
fn lit_sides(estimator: &SplatEstimator, surfaces: usize) -> Vec<[bool; 2]> {
    let mut lit = vec![[false; 2]; surfaces];
    let params = estimator.params();
    for s in estimator.splats() {
        if let (Some(SurfaceParam::Planar(frame)), Some(l)) =
            (params.get(s.surface), lit.get_mut(s.surface as usize))
        {
            // The test of `flux_density`: the incoming direction above the side's frame.
            for side in Side::BOTH {
                if s.incoming.dot(side.direction(frame)) > 0.0 {
                    l[side.index()] = true;
                }
            }
        }
    }
    lit
}

impl DiffuseAtlas {
    /// Evaluates the textures of every planar Lambertian surface of `scene` (with [`DiffuseTextureOptions::lambertian_lobes`], of every planar surface's Lambertian lobes) from `estimator`'s photons and packs them (section 2.2.1 preprocessing; rayon over samples).
    ///
    /// A material the GPU cannot flatten ([`GpuMaterial::from_model`] fails) is treated as not diffuse: its surfaces stay with the splat pass, which reports it.
    pub fn build(
        scene: &Scene,
        estimator: &SplatEstimator,
        options: DiffuseTextureOptions,
    ) -> Result<Self> {
        let lit = lit_sides(estimator, scene.surfaces().len());
        let mut atlas = Self::layout(
            scene,
            estimator.params(),
            &|id| estimator.support(id),
            &lit,
            options,
        )?;
        atlas.accumulate(estimator)?;
        Ok(atlas)
    }

    /// The textures' layout with every texel black: a texture per planar Lambertian surface (as [`DiffuseAtlas::build`]), its texel size from `support` (the kernel support of equation 3 per surface), a layer per side where `lit` (by `SurfaceId`, [`Side::index`]) says photons arrive. With [`DiffuseAtlas::accumulate`], the atlas of a photon map streamed in batches ([`lustre_photon::SplatTally`] gives `lit` and, through the estimators, `support`).
    pub fn layout(
        scene: &Scene,
        params: &SurfaceParams,
        support: &dyn Fn(SurfaceId) -> f32,
        lit: &[[bool; 2]],
        options: DiffuseTextureOptions,
    ) -> Result<Self> {
        options.validate()?;
        if params.len() != scene.surfaces().len() || lit.len() != scene.surfaces().len() {
            return Err(MprError::InvalidSetting {
                what: "diffuse textures",
                message: format!(
                    "{} parameterised and {} tallied surfaces, scene `{}` has {}",
                    params.len(),
                    lit.len(),
                    scene.name,
                    scene.surfaces().len()
                ),
            });
        }
        let reflectances: Vec<Option<Rgb>> = scene
            .materials()
            .iter()
            .map(|m| {
                GpuMaterial::from_model(&m.name, &m.model, GlossyModel::Exact)
                    .ok()
                    .filter(|g| g.is_diffuse() || (options.lambertian_lobes && g.has_lambert()))
                    .map(|g| g.diffuse_reflectance())
            })
            .collect();
        let (map_layers, maps) = diffuse_map_layers(scene);
        let mut surfaces: Vec<Option<DiffuseSurfaceTexture>> = Vec::new();
        for (id, surface) in scene.surfaces().iter().enumerate() {
            let reflectance = reflectances
                .get(surface.material as usize)
                .copied()
                .flatten();
            let (Some(SurfaceParam::Planar(frame)), Some(reflectance)) =
                (params.get(id as SurfaceId), reflectance)
            else {
                surfaces.push(None);
                continue;
            };
            let extent = frame.max - frame.min;
            let t = match options.texel_size {
                TexelSize::Support(f) => f * support(id as SurfaceId),
                TexelSize::Metres(m) => m,
            };
            let (nu, tu) = sample_grid(extent.x, t, options.max_samples_per_side);
            let (nv, tv) = sample_grid(extent.y, t, options.max_samples_per_side);
            surfaces.push(Some(DiffuseSurfaceTexture {
                frame: *frame,
                reflectance,
                size: UVec2::new(nu, nv),
                spacing: Vec2::new(tu, tv),
                // Placeholders: a layer per lit side, placed by the packing below.
                layers: lit[id].map(|l| l.then_some(UVec2::ZERO)),
                diffuse_map: map_layers
                    .get(surface.material as usize)
                    .copied()
                    .unwrap_or(WHITE_LAYER),
            }));
        }
        let layers = layers_of(&surfaces);
        let sizes: Vec<UVec2> = layers
            .iter()
            .map(|&(id, _)| surfaces[id].as_ref().map_or(UVec2::ONE, |s| s.size))
            .collect();
        let (width, height, corners) = pack_shelves(&sizes, options.max_atlas_side)?;
        for (&(id, side), &corner) in layers.iter().zip(&corners) {
            if let Some(s) = surfaces[id].as_mut() {
                s.layers[side.index()] = Some(corner);
            }
        }
        Ok(Self {
            width,
            height,
            texels: vec![[0.0f32; 4]; width as usize * height as usize],
            surfaces,
            maps,
            options,
        })
    }

    /// Adds the radiance of `estimator`'s photons to every texel (section 2.2.1: the flux density times `ρ/π`; rayon over samples). The estimators of a map's batches, built with the whole map's supports ([`SplatEstimator::build_tallied`]), add up to the map's textures.
    pub fn accumulate(&mut self, estimator: &SplatEstimator) -> Result<()> {
        if estimator.params().len() != self.surfaces.len() {
            return Err(MprError::InvalidSetting {
                what: "diffuse textures",
                message: format!(
                    "the estimator has {} surfaces, the atlas {}",
                    estimator.params().len(),
                    self.surfaces.len()
                ),
            });
        }
        let surfaces = &self.surfaces;
        let layers = layers_of(surfaces);
        // Evaluate every layer's samples in parallel, then add them in place.
        let values: Vec<Vec<[f32; 4]>> = layers
            .par_iter()
            .map(|&(id, side)| {
                let s = surfaces[id]
                    .as_ref()
                    .expect("layers list textured surfaces");
                let n = (s.size.x * s.size.y) as usize;
                let scale = s.reflectance * FRAC_1_PI;
                let direction = side.direction(&s.frame);
                (0..n)
                    .into_par_iter()
                    .map(|k| {
                        let (i, j) = ((k as u32) % s.size.x, (k as u32) / s.size.x);
                        let flux = estimator.flux_density(
                            id as SurfaceId,
                            s.sample_point(i, j),
                            s.frame.normal,
                            direction,
                        );
                        (flux * scale).extend(0.0).to_array()
                    })
                    .collect()
            })
            .collect();
        for (&(id, side), layer) in layers.iter().zip(values) {
            let Some(s) = self.surfaces[id].as_ref() else {
                continue;
            };
            let Some(corner) = s.layers[side.index()] else {
                continue;
            };
            for (j, row) in layer.chunks_exact(s.size.x as usize).enumerate() {
                let start = (corner.y as usize + j) * self.width as usize + corner.x as usize;
                for (texel, value) in self.texels[start..start + row.len()].iter_mut().zip(row) {
                    for c in 0..4 {
                        texel[c] += value[c];
                    }
                }
            }
        }
        Ok(())
    }

    /// Per `SurfaceId`, whether this pass renders the surface (the `exclude` mask of [`crate::passes::splat::SplatBuffers::new_excluding`]).
    pub fn textured(&self) -> Vec<bool> {
        self.surfaces.iter().map(Option::is_some).collect()
    }

    /// Number of stored samples over all layers.
    pub fn sample_count(&self) -> usize {
        self.surfaces
            .iter()
            .flatten()
            .map(|s| {
                (s.size.x * s.size.y) as usize * s.layers.iter().filter(|l| l.is_some()).count()
            })
            .sum()
    }

    /// The stored radiance of sample `(i, j)` of `surface`'s layer on `side`; `None` when there is no such sample.
    pub fn sample(&self, surface: SurfaceId, side: Side, i: u32, j: u32) -> Option<Rgb> {
        let s = self.surfaces.get(surface as usize)?.as_ref()?;
        let corner = s.layers[side.index()]?;
        if i >= s.size.x || j >= s.size.y {
            return None;
        }
        Some(self.texel(corner + UVec2::new(i, j)))
    }

    /// The RGB of atlas texel `p`.
    fn texel(&self, p: UVec2) -> Rgb {
        let t = self.texels[p.y as usize * self.width as usize + p.x as usize];
        Vec3::new(t[0], t[1], t[2])
    }

    /// [`DiffuseAtlas::radiance`] times the surface's diffuse map at texture coordinates `uv` (irradiance times albedo, as a light map is drawn: the map stays sharp); what the GPU pass adds at a fragment.
    pub fn radiance_at(&self, surface: SurfaceId, x: Vec3, eye: Vec3, uv: Vec2) -> Option<Rgb> {
        let l = self.radiance(surface, x, eye)?;
        let layer = self.surfaces.get(surface as usize)?.as_ref()?.diffuse_map;
        Some(
            match layer.checked_sub(1).and_then(|i| self.maps.get(i as usize)) {
                Some(map) => l * map.sample(uv),
                None => l,
            },
        )
    }

    /// The radiance stored for point `x` of `surface` seen from `eye` (the untextured `ρ`): the bilinear lookup of `diffuse_texture.wgsl`; `None` for a surface this pass does not render, zero on a side without a layer.
    pub fn radiance(&self, surface: SurfaceId, x: Vec3, eye: Vec3) -> Option<Rgb> {
        let s = self.surfaces.get(surface as usize)?.as_ref()?;
        let Some(corner) = s.layers[Side::seen(&s.frame, x, eye).index()] else {
            return Some(Rgb::ZERO);
        };
        let d = x - s.frame.origin;
        let uv = Vec2::new(d.dot(s.frame.u_axis), d.dot(s.frame.v_axis));
        let last = s.size - UVec2::ONE;
        let p = ((uv - s.frame.min) / s.spacing).clamp(Vec2::ZERO, last.as_vec2());
        let i0 = p.floor().as_uvec2().min(last);
        let i1 = (i0 + UVec2::ONE).min(last);
        let f = p - i0.as_vec2();
        let l00 = self.texel(corner + i0);
        let l10 = self.texel(corner + UVec2::new(i1.x, i0.y));
        let l01 = self.texel(corner + UVec2::new(i0.x, i1.y));
        let l11 = self.texel(corner + i1);
        Some(l00.lerp(l10, f.x).lerp(l01.lerp(l11, f.x), f.y))
    }
}

/// One surface's texture record as the shader reads it (`DiffuseSurface` in `diffuse_texture.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuDiffuseSurface {
    /// Frame origin in m.
    pub origin: [f32; 3],
    /// 1 when this pass renders the surface, 0 when the splat pass does.
    pub textured: u32,
    /// Unit u axis.
    pub u_axis: [f32; 3],
    /// Samples along u.
    pub columns: u32,
    /// Unit v axis.
    pub v_axis: [f32; 3],
    /// Samples along v.
    pub rows: u32,
    /// Unit plane normal (front side).
    pub normal: [f32; 3],
    /// The layer of the surface's diffuse map ([`WHITE_LAYER`]: none).
    pub diffuse_map: u32,
    /// `(u, v)` of sample `(0, 0)` in m.
    pub uv_min: [f32; 2],
    /// Sample spacing along u and v in m.
    pub spacing: [f32; 2],
    /// Atlas texel of sample `(0, 0)`: front layer in `xy`, back in `zw`; [`NO_LAYER`] where none.
    pub layers: [u32; 4],
}

impl GpuDiffuseSurface {
    /// The record of a surface (`None`: not textured).
    pub fn new(texture: Option<&DiffuseSurfaceTexture>) -> Self {
        let Some(s) = texture else {
            return Self::zeroed();
        };
        let layer = |l: Option<UVec2>| l.map_or([NO_LAYER; 2], |c| c.to_array());
        let [fx, fy] = layer(s.layers[0]);
        let [bx, by] = layer(s.layers[1]);
        Self {
            origin: s.frame.origin.to_array(),
            textured: 1,
            u_axis: s.frame.u_axis.to_array(),
            columns: s.size.x,
            v_axis: s.frame.v_axis.to_array(),
            rows: s.size.y,
            normal: s.frame.normal.to_array(),
            diffuse_map: s.diffuse_map,
            uv_min: s.frame.min.to_array(),
            spacing: s.spacing.to_array(),
            layers: [fx, fy, bx, by],
        }
    }
}

/// The diffuse textures on the GPU: the atlas, the per-surface records and their bind group.
#[derive(Debug)]
pub struct DiffuseTextures {
    /// The atlas ([`DIFFUSE_ATLAS_FORMAT`]).
    pub atlas: wgpu::Texture,
    records: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// Per `SurfaceId`, whether the pass renders it.
    pub textured: Vec<bool>,
}

impl DiffuseTextures {
    /// Uploads `atlas` for `pass` with its diffuse maps ([`DiffuseAtlas::maps`]); an atlas larger than the device's 2D limit is [`MprError::InvalidSize`].
    pub fn new(ctx: &GpuContext, pass: &DiffuseTexturePass, atlas: &DiffuseAtlas) -> Result<Self> {
        let maps = DiffuseMaps::from_textures(ctx, Vec::new(), &atlas.maps)?;
        Self::with_maps(ctx, pass, atlas, &maps)
    }

    /// [`DiffuseTextures::new`] reading the diffuse maps from `maps`, uploaded for the same scene (e.g. [`crate::passes::direct::DirectLights::diffuse_maps`]).
    pub fn with_maps(
        ctx: &GpuContext,
        pass: &DiffuseTexturePass,
        atlas: &DiffuseAtlas,
        maps: &DiffuseMaps,
    ) -> Result<Self> {
        check_size(ctx, "diffuse atlas", atlas.width, atlas.height)?;
        if atlas.texels.len() != atlas.width as usize * atlas.height as usize {
            return Err(MprError::PixelCount {
                what: "diffuse atlas",
                got: atlas.texels.len(),
                width: atlas.width,
                height: atlas.height,
            });
        }
        let mut records: Vec<GpuDiffuseSurface> = atlas
            .surfaces
            .iter()
            .map(|s| GpuDiffuseSurface::new(s.as_ref()))
            .collect();
        if records.is_empty() {
            // A zero-sized storage buffer cannot be bound; no fragment reads this one.
            records.push(GpuDiffuseSurface::zeroed());
        }
        ctx.checked("diffuse texture upload", || {
            use wgpu::util::DeviceExt;
            let size = wgpu::Extent3d {
                width: atlas.width,
                height: atlas.height,
                depth_or_array_layers: 1,
            };
            let texture = ctx.device.create_texture_with_data(
                &ctx.queue,
                &wgpu::TextureDescriptor {
                    label: Some("diffuse-atlas"),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: DIFFUSE_ATLAS_FORMAT,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                bytemuck::cast_slice(&atlas.texels),
            );
            let buffer = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("diffuse-surfaces"),
                    contents: bytemuck::cast_slice(&records),
                    usage: wgpu::BufferUsages::STORAGE,
                });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("diffuse-textures"),
                layout: &pass.textures_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                    maps.entries(2)[0].clone(),
                    maps.entries(2)[1].clone(),
                ],
            });
            Self {
                atlas: texture,
                records: buffer,
                bind_group,
                textured: atlas.textured(),
            }
        })
    }

    /// The per-surface records buffer ([`GpuDiffuseSurface`] by `SurfaceId`).
    pub fn records(&self) -> &wgpu::Buffer {
        &self.records
    }
}

/// The GPU diffuse texture pass: its pipeline and camera block.
#[derive(Debug)]
pub struct DiffuseTexturePass {
    pipeline: wgpu::RenderPipeline,
    textures_layout: wgpu::BindGroupLayout,
}

impl DiffuseTexturePass {
    /// Builds the pipeline for HDR targets of `hdr_format` (which must be blendable): cull none, depth `Equal` without writes, One/One blending.
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat) -> Result<Self> {
        if !ctx.is_blendable(hdr_format) {
            return Err(MprError::UnsupportedFormat {
                what: "diffuse texture pass HDR target (additive blending)",
                format: hdr_format,
            });
        }
        ctx.checked("diffuse texture pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "diffuse-texture", &diffuse_texture_wgsl());
            let maps = DiffuseMaps::layout_entries(2, wgpu::ShaderStages::FRAGMENT);
            let textures_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("diffuse-textures"),
                    entries: &[
                        wgpu::BindGroupLayoutEntry {
                            binding: 0,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Buffer {
                                ty: wgpu::BufferBindingType::Storage { read_only: true },
                                has_dynamic_offset: false,
                                min_binding_size: wgpu::BufferSize::new(
                                    size_of::<GpuDiffuseSurface>() as u64,
                                ),
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 1,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                                view_dimension: wgpu::TextureViewDimension::D2,
                                multisampled: false,
                            },
                            count: None,
                        },
                        maps[0],
                        maps[1],
                    ],
                });
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "diffuse-texture",
                    module: &module,
                    layouts: &[&textures_layout],
                    extra_vertex_buffers: &[],
                    target: additive_target(hdr_format),
                    depth_compare: wgpu::CompareFunction::Equal,
                    depth_write: false,
                },
            );
            Self {
                pipeline,
                textures_layout,
            }
        })
    }

    /// Records the pass after the depth pre-pass: one render pass that loads
    /// HDR and the pre-pass's depth (read only) and draws the triangles of the
    /// textured surfaces (consecutive surfaces merged into one draw).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        textures: &DiffuseTextures,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) {
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "diffuse-texture");
        let runs = textured_runs(&scene.surface_ranges, &textures.textured);
        if scene.vertex_count == 0 || runs.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return;
        }
        pass.set_bind_group(1, &textures.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        for run in runs {
            pass.draw_indexed(run, 0, 0..1);
        }
    }
}

/// The index ranges of the textured surfaces, adjacent ranges merged.
fn textured_runs(surface_ranges: &[Range<u32>], textured: &[bool]) -> Vec<Range<u32>> {
    let mut runs: Vec<Range<u32>> = Vec::new();
    for (range, _) in surface_ranges
        .iter()
        .zip(textured)
        .filter(|(r, t)| **t && !r.is_empty())
    {
        match runs.last_mut() {
            Some(last) if last.end == range.start => last.end = range.end,
            _ => runs.push(range.clone()),
        }
    }
    runs
}

/// The diffuse texture pass as compiled: its WGSL after the view block and the diffuse map lookups.
pub fn diffuse_texture_wgsl() -> String {
    with_view(&crate::shaders::with_diffuse_maps(DIFFUSE_TEXTURE_WGSL))
}

/// CPU counterpart of [`DiffuseTexturePass`]: through each pixel centre the
/// closest hit (BVH), then [`DiffuseAtlas::radiance_at`] (at the hit's uv) towards the camera
/// position; zero where no surface or an untextured one is seen. Row 0 is the top.
pub fn diffuse_texture_cpu(
    atlas: &DiffuseAtlas,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<[f32; 3]> {
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    bvh.closest_hits(&rays)
        .iter()
        .map(|hit| {
            hit.and_then(|h| atlas.radiance_at(h.surface, h.position, camera.position, h.uv))
                .map_or([0.0; 3], |l| l.to_array())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;
    use lustre_photon::{EstimatorOptions, NoProgress, Support, TraceOptions, trace_photons};

    fn estimator(name: &str, photons: u64) -> (Scene, SplatEstimator) {
        let scene = builtin(name).unwrap();
        let bvh = Bvh::build(&scene);
        let options = TraceOptions {
            photons,
            seed: 3,
            ..TraceOptions::default()
        };
        let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
        let est = SplatEstimator::build(
            &scene,
            &map,
            EstimatorOptions {
                support: Support::Scaled(8.0),
                ..EstimatorOptions::default()
            },
        )
        .unwrap();
        (scene, est)
    }

    #[test]
    fn samples_are_rho_over_pi_times_the_flux_density_at_their_points() {
        let (scene, est) = estimator("glosbox", 20_000);
        let atlas = DiffuseAtlas::build(&scene, &est, DiffuseTextureOptions::default()).unwrap();
        let mut checked = 0;
        for (id, s) in atlas.surfaces.iter().enumerate() {
            let Some(s) = s else { continue };
            for side in Side::BOTH {
                if s.layers[side.index()].is_none() {
                    continue;
                }
                let last = s.size - UVec2::ONE;
                for (i, j) in [(0, 0), (last.x, last.y), (last.x / 2, last.y / 3), (1, 2)] {
                    let (i, j) = (i.min(last.x), j.min(last.y));
                    let got = atlas.sample(id as SurfaceId, side, i, j).unwrap();
                    let flux = est.flux_density(
                        id as SurfaceId,
                        s.sample_point(i, j),
                        s.frame.normal,
                        side.direction(&s.frame),
                    );
                    let want = s.reflectance / std::f32::consts::PI * flux;
                    assert!(
                        (got - want).abs().max_element() <= 1e-6 * want.max_element().max(1e-6),
                        "surface {id} {side:?} ({i}, {j}): {got} vs {want}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 20, "{checked}");
    }

    #[test]
    fn glosbox_floor_and_gold_box_are_left_to_the_splats() {
        let (scene, est) = estimator("glosbox", 5_000);
        let atlas = DiffuseAtlas::build(&scene, &est, DiffuseTextureOptions::default()).unwrap();
        for (id, surface) in scene.surfaces().iter().enumerate() {
            let model = &scene.materials()[surface.material as usize].model;
            let diffuse = model.is_diffuse();
            assert_eq!(
                atlas.surfaces[id].is_some(),
                diffuse,
                "surface {id}: {model:?}"
            );
        }
        let cornell = estimator("cornell", 5_000);
        let all =
            DiffuseAtlas::build(&cornell.0, &cornell.1, DiffuseTextureOptions::default()).unwrap();
        assert!(all.textured().iter().all(|&t| t));
    }

    #[test]
    fn lookup_reproduces_samples_and_is_bilinear_between_them() {
        let (scene, est) = estimator("cornell", 20_000);
        let atlas = DiffuseAtlas::build(&scene, &est, DiffuseTextureOptions::default()).unwrap();
        let (id, s) = atlas
            .surfaces
            .iter()
            .enumerate()
            .find_map(|(id, s)| {
                s.as_ref()
                    .filter(|s| s.layers[0].is_some())
                    .map(|s| (id, s))
            })
            .unwrap();
        let id = id as SurfaceId;
        let eye = s.sample_point(0, 0) + s.frame.normal;
        let at = |i, j| atlas.sample(id, Side::Front, i, j).unwrap();
        let got = atlas.radiance(id, s.sample_point(1, 1), eye).unwrap();
        assert!((got - at(1, 1)).abs().max_element() <= 1e-5 * at(1, 1).max_element());
        let mid = s
            .frame
            .to_world(s.frame.min + Vec2::new(1.25, 1.5) * s.spacing);
        let want = at(1, 1)
            .lerp(at(2, 1), 0.25)
            .lerp(at(1, 2).lerp(at(2, 2), 0.25), 0.5);
        let got = atlas.radiance(id, mid, eye).unwrap();
        assert!(
            (got - want).abs().max_element() <= 1e-5 * want.max_element(),
            "{got} vs {want}"
        );
        // Outside the rectangle the lookup clamps to the edge samples.
        let outside = s.frame.to_world(s.frame.min - Vec2::splat(0.1));
        let got = atlas.radiance(id, outside, eye).unwrap();
        assert!((got - at(0, 0)).abs().max_element() <= 1e-6 * at(0, 0).max_element());
    }

    #[test]
    fn cornell_walls_have_only_their_inner_layer() {
        let (scene, est) = estimator("cornell", 20_000);
        let atlas = DiffuseAtlas::build(&scene, &est, DiffuseTextureOptions::default()).unwrap();
        let eye = scene.camera().position;
        // The back wall (z = -1) faces the camera from inside the box.
        let (id, s) = atlas
            .surfaces
            .iter()
            .enumerate()
            .find_map(|(id, s)| {
                s.as_ref()
                    .filter(|s| {
                        (s.frame.origin.z + 1.0).abs() < 1e-4 && s.frame.normal.z.abs() > 0.99
                    })
                    .map(|s| (id, s))
            })
            .unwrap();
        let inner = Side::seen(&s.frame, s.frame.origin, eye);
        assert!(s.layers[inner.index()].is_some());
        let outer = Side::BOTH.into_iter().find(|&x| x != inner).unwrap();
        assert!(s.layers[outer.index()].is_none(), "surface {id}");
        let behind = s.frame.origin - 2.0 * (eye - s.frame.origin);
        assert_eq!(
            atlas.radiance(id as SurfaceId, s.frame.origin, behind),
            Some(Rgb::ZERO)
        );
    }

    #[test]
    fn sample_grids_cover_the_extent_and_respect_the_cap() {
        assert_eq!(sample_grid(1.0, 0.25, 1024), (5, 0.25));
        let (n, t) = sample_grid(1.0, 0.3, 1024);
        assert_eq!(n, 5);
        assert!((t * (n - 1) as f32 - 1.0).abs() < 1e-6);
        assert_eq!(sample_grid(10.0, 0.001, 101), (101, 0.1));
        assert_eq!(sample_grid(0.0, 0.1, 16), (1, 1.0));
    }

    #[test]
    fn shelf_packing_places_layers_without_overlap_inside_the_atlas() {
        let sizes: Vec<UVec2> = (0..40)
            .map(|i| UVec2::new(3 + (i * 7) % 29, 2 + (i * 11) % 31))
            .collect();
        let (w, h, corners) = pack_shelves(&sizes, 4096).unwrap();
        let mut used = vec![false; (w * h) as usize];
        for (c, s) in corners.iter().zip(&sizes) {
            assert!(c.x + s.x <= w && c.y + s.y <= h);
            for y in c.y..c.y + s.y {
                for x in c.x..c.x + s.x {
                    assert!(!std::mem::replace(&mut used[(y * w + x) as usize], true));
                }
            }
        }
        assert!(pack_shelves(&sizes, 40).is_err());
        assert_eq!(pack_shelves(&[], 16).unwrap().0, 1);
    }

    #[test]
    fn invalid_options_are_refused() {
        let bad = [
            DiffuseTextureOptions {
                texel_size: TexelSize::Metres(0.0),
                ..Default::default()
            },
            DiffuseTextureOptions {
                texel_size: TexelSize::Support(f32::NAN),
                ..Default::default()
            },
            DiffuseTextureOptions {
                max_samples_per_side: 1,
                ..Default::default()
            },
        ];
        for o in bad {
            assert!(o.validate().is_err(), "{o:?}");
        }
    }

    #[test]
    fn textured_runs_merge_adjacent_surfaces() {
        let ranges = [0..6, 6..12, 12..12, 12..18, 18..24];
        let runs = textured_runs(&ranges, &[true, true, true, false, true]);
        assert_eq!(runs, vec![0..12, 18..24]);
    }
}
