//! The scene's diffuse texture maps on the GPU ([`Material::diffuse_map`]:
//! MTL `map_Kd`, glTF `baseColorTexture`), uploaded once per scene as one
//! [`DIFFUSE_MAP_FORMAT`] `texture_2d_array` with a full mip chain, read by
//! `shaders/common/diffuse_map.wgsl` ([`DIFFUSE_MAP_WGSL`]).
//!
//! Layer [`WHITE_LAYER`] is white: untextured materials point at it and the
//! shaders skip the lookup for them, so untextured scenes render exactly as
//! without maps. Each distinct map (one `Arc<Texture>` shared by several
//! materials is one map) gets the next layer, in `MaterialId` order of first
//! use ([`diffuse_map_layers`]); [`crate::material::scene_materials`] writes
//! each material's layer into [`GpuMaterial::diffuse_map`].
//!
//! All layers share one size: the largest width and height among the maps,
//! halved while the array would exceed [`MAX_DIFFUSE_MAP_BYTES`] and capped
//! by the device's 2D texture limit. A map of another size is resampled to
//! it ([`resample`]: bilinear where it is magnified, box-averaged bilinear
//! samples where it is minified), so a map larger than the device allows is
//! drawn smaller, never refused. A map of the common size is uploaded texel
//! for texel, and a `Repeat`, linearly filtered sampler at `(u, 1 − v)`
//! reads [`Texture::sample`] from level 0 (within `Rgba16Float`'s rounding,
//! relative 2⁻¹¹). Each mip level is the 2×2 box average of the one above
//! (the last row or column repeated on odd sides).
//!
//! [`Material::diffuse_map`]: lustre_geometry::Material::diffuse_map
//! [`GpuMaterial::diffuse_map`]: crate::material::GpuMaterial::diffuse_map

use std::sync::Arc;

use glam::Vec2;
use half::f16;
use lustre_geometry::{Rgb, Scene, Texture};
use rayon::prelude::*;

use crate::{GpuContext, MprError, Result};

/// Format of the diffuse map array (filterable on every device).
pub const DIFFUSE_MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The white layer that untextured materials point at.
pub const WHITE_LAYER: u32 = 0;

/// Most bytes the diffuse map array may take with its mip chain (the common size is halved until it fits).
pub const MAX_DIFFUSE_MAP_BYTES: u64 = 1 << 30;

/// The WGSL lookups of the diffuse maps (`src/shaders/common/diffuse_map.wgsl`), after [`crate::shaders::with_materials`] in a pass that declares `diffuse_maps` and `diffuse_map_sampler`.
pub const DIFFUSE_MAP_WGSL: &str = include_str!("shaders/common/diffuse_map.wgsl");

/// The layer of each material's diffuse map ([`WHITE_LAYER`] without one), in `MaterialId` order, and the distinct maps in layer order (layer `i + 1` is map `i`).
pub fn diffuse_map_layers(scene: &Scene) -> (Vec<u32>, Vec<Arc<Texture>>) {
    let mut maps: Vec<Arc<Texture>> = Vec::new();
    let layers = scene
        .materials()
        .iter()
        .map(|m| match &m.diffuse_map {
            None => WHITE_LAYER,
            Some(map) => {
                let index = maps
                    .iter()
                    .position(|t| Arc::ptr_eq(t, map))
                    .unwrap_or_else(|| {
                        maps.push(map.clone());
                        maps.len() - 1
                    });
                index as u32 + 1
            }
        })
        .collect();
    (layers, maps)
}

/// Number of mip levels of a `width × height` texture down to 1×1.
pub fn mip_level_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// Bytes of `layers` layers of `width × height` RGBA16F texels with their mip chains.
fn array_bytes(width: u32, height: u32, layers: u32) -> u64 {
    (0..mip_level_count(width, height))
        .map(|l| u64::from((width >> l).max(1)) * u64::from((height >> l).max(1)) * 8)
        .sum::<u64>()
        * u64::from(layers)
}

/// The common layer size of `maps`: their largest width and height, each at most `max_side`, halved together while `layers` layers exceed `max_bytes`; 1×1 without maps.
pub fn common_size(maps: &[Arc<Texture>], max_side: u32, max_bytes: u64) -> (u32, u32) {
    let max_side = max_side.max(1);
    let mut w = maps
        .iter()
        .map(|t| t.width())
        .max()
        .unwrap_or(1)
        .min(max_side);
    let mut h = maps
        .iter()
        .map(|t| t.height())
        .max()
        .unwrap_or(1)
        .min(max_side);
    let layers = maps.len() as u32 + 1;
    while (w > 1 || h > 1) && array_bytes(w, h, layers) > max_bytes {
        w = (w / 2).max(1);
        h = (h / 2).max(1);
    }
    (w, h)
}

/// `texture` at `width × height` texels, row 0 at the top: its own texels at its own size, else bilinear samples at the new texel centres, averaged over each new texel's footprint where it shrinks.
pub fn resample(texture: &Texture, width: u32, height: u32) -> Vec<Rgb> {
    if (texture.width(), texture.height()) == (width, height) {
        return texture.texels().to_vec();
    }
    let nx = texture.width().div_ceil(width).max(1);
    let ny = texture.height().div_ceil(height).max(1);
    let weight = 1.0 / (nx * ny) as f32;
    (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..width).map(move |x| {
                let mut sum = Rgb::ZERO;
                for j in 0..ny {
                    for i in 0..nx {
                        let s = (x as f32 + (i as f32 + 0.5) / nx as f32) / width as f32;
                        let t = (y as f32 + (j as f32 + 0.5) / ny as f32) / height as f32;
                        sum += texture.sample(Vec2::new(s, 1.0 - t));
                    }
                }
                sum * weight
            })
        })
        .collect()
}

/// The mip chain of a `width × height` level 0, each level the 2×2 box average of the one above (last row or column repeated on odd sides), row-major.
pub fn mip_chain(level0: Vec<Rgb>, width: u32, height: u32) -> Vec<Vec<Rgb>> {
    let mut mips = vec![level0];
    let (mut w, mut h) = (width as usize, height as usize);
    while w > 1 || h > 1 {
        let above = mips.last().unwrap();
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let at = |x: usize, y: usize| above[y.min(h - 1) * w + x.min(w - 1)];
        let next = (0..nh)
            .flat_map(|j| {
                (0..nw).map(move |i| {
                    0.25 * (at(2 * i, 2 * j)
                        + at(2 * i + 1, 2 * j)
                        + at(2 * i, 2 * j + 1)
                        + at(2 * i + 1, 2 * j + 1))
                })
            })
            .collect();
        mips.push(next);
        (w, h) = (nw, nh);
    }
    mips
}

/// The diffuse maps of a scene on the GPU, with the sampler the passes read them with.
#[derive(Debug, Clone)]
pub struct DiffuseMaps {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    layers: Vec<u32>,
    size: (u32, u32),
}

impl DiffuseMaps {
    /// Uploads the distinct diffuse maps of `scene` (only the white layer for an untextured scene).
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        let (layers, maps) = diffuse_map_layers(scene);
        Self::from_textures(ctx, layers, &maps)
    }

    /// Uploads `maps` as layers 1, 2, ... after the white layer; `layers` is each material's layer, as [`diffuse_map_layers`] gives them.
    pub fn from_textures(
        ctx: &GpuContext,
        layers: Vec<u32>,
        maps: &[Arc<Texture>],
    ) -> Result<Self> {
        let limits = ctx.device.limits();
        if maps.len() as u64 + 1 > u64::from(limits.max_texture_array_layers) {
            return Err(MprError::InvalidSetting {
                what: "diffuse maps",
                message: format!(
                    "{} distinct diffuse maps; the device holds {} layers of an array, one of them white",
                    maps.len(),
                    limits.max_texture_array_layers
                ),
            });
        }
        let (width, height) =
            common_size(maps, limits.max_texture_dimension_2d, MAX_DIFFUSE_MAP_BYTES);
        let mut contents = vec![mip_chain(
            vec![Rgb::ONE; (width * height) as usize],
            width,
            height,
        )];
        contents.extend(
            maps.iter()
                .map(|t| mip_chain(resample(t, width, height), width, height)),
        );
        Self::from_layers(ctx, layers, &contents, width, height)
    }

    /// Only the white layer: for passes drawn without a scene's maps.
    pub fn white(ctx: &GpuContext) -> Result<Self> {
        Self::from_layers(ctx, Vec::new(), &[vec![vec![Rgb::ONE]]], 1, 1)
    }

    fn from_layers(
        ctx: &GpuContext,
        layers: Vec<u32>,
        contents: &[Vec<Vec<Rgb>>],
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let mip_levels = contents[0].len() as u32;
        let (texture, view, sampler) = ctx.checked("diffuse map upload", || {
            let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("diffuse-maps"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: contents.len() as u32,
                },
                mip_level_count: mip_levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DIFFUSE_MAP_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            for (layer, mips) in contents.iter().enumerate() {
                for (level, texels) in mips.iter().enumerate() {
                    let (w, h) = ((width >> level).max(1), (height >> level).max(1));
                    let halves: Vec<f16> = texels
                        .iter()
                        .flat_map(|t| [t.x, t.y, t.z, 1.0].map(f16::from_f32))
                        .collect();
                    ctx.queue.write_texture(
                        wgpu::TexelCopyTextureInfo {
                            texture: &texture,
                            mip_level: level as u32,
                            origin: wgpu::Origin3d {
                                x: 0,
                                y: 0,
                                z: layer as u32,
                            },
                            aspect: wgpu::TextureAspect::All,
                        },
                        bytemuck::cast_slice(&halves),
                        wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(8 * w),
                            rows_per_image: Some(h),
                        },
                        wgpu::Extent3d {
                            width: w,
                            height: h,
                            depth_or_array_layers: 1,
                        },
                    );
                }
            }
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some("diffuse-maps"),
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("diffuse-maps"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                address_mode_w: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            });
            (texture, view, sampler)
        })?;
        Ok(Self {
            texture,
            view,
            sampler,
            layers,
            size: (width, height),
        })
    }

    /// The `texture_2d_array` view (`diffuse_maps` in WGSL).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// The `Repeat`, trilinear sampler (`diffuse_map_sampler` in WGSL).
    pub fn sampler(&self) -> &wgpu::Sampler {
        &self.sampler
    }

    /// The array texture.
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// The layer of each material's map, in `MaterialId` order (empty for [`DiffuseMaps::white`]).
    pub fn layers(&self) -> &[u32] {
        &self.layers
    }

    /// Whether some material has a map.
    pub fn is_textured(&self) -> bool {
        self.layers.iter().any(|&l| l != WHITE_LAYER)
    }

    /// Width and height of every layer.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The two bind group layout entries, the array at `binding` and the sampler at `binding + 1`, visible to `visibility`.
    pub fn layout_entries(
        binding: u32,
        visibility: wgpu::ShaderStages,
    ) -> [wgpu::BindGroupLayoutEntry; 2] {
        [
            wgpu::BindGroupLayoutEntry {
                binding,
                visibility,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: binding + 1,
                visibility,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ]
    }

    /// The two bind group entries matching [`DiffuseMaps::layout_entries`] at `binding`.
    pub fn entries(&self, binding: u32) -> [wgpu::BindGroupEntry<'_>; 2] {
        [
            wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(&self.view),
            },
            wgpu::BindGroupEntry {
                binding: binding + 1,
                resource: wgpu::BindingResource::Sampler(&self.sampler),
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32) -> Arc<Texture> {
        let texels = (0..w * h)
            .map(|i| Rgb::new((i % w) as f32 / w as f32, (i / w) as f32 / h as f32, 0.5))
            .collect();
        Arc::new(Texture::new("t", w, h, texels).unwrap())
    }

    #[test]
    fn mip_chains_end_at_one_texel_and_keep_the_mean_on_powers_of_two() {
        assert_eq!(mip_level_count(1, 1), 1);
        assert_eq!(mip_level_count(8, 3), 4);
        let t = texture(8, 4);
        let mips = mip_chain(t.texels().to_vec(), 8, 4);
        assert_eq!(mips.len(), 4);
        assert_eq!(mips.last().unwrap().len(), 1);
        assert!((mips[3][0] - t.mean()).abs().max_element() < 1e-6);
        let odd = mip_chain(vec![Rgb::ONE; 15], 5, 3);
        assert_eq!(odd.iter().map(Vec::len).collect::<Vec<_>>(), vec![15, 2, 1]);
    }

    #[test]
    fn resampling_keeps_same_sized_maps_and_shrinks_by_averaging() {
        let t = texture(8, 8);
        assert_eq!(resample(&t, 8, 8), t.texels());
        let small = resample(&t, 2, 2);
        let mean = small.iter().copied().sum::<Rgb>() / 4.0;
        assert!((mean - t.mean()).abs().max_element() < 1e-5, "{mean}");
        // Magnified: bilinear samples of the original at the new texel centres.
        let big = resample(&t, 16, 16);
        assert_eq!(
            big[16 * 5 + 3],
            t.sample(Vec2::new(3.5 / 16.0, 1.0 - 5.5 / 16.0))
        );
    }

    #[test]
    fn the_common_size_is_capped_by_the_side_and_the_byte_budget() {
        let maps = [texture(64, 16), texture(8, 32)];
        assert_eq!(common_size(&maps, 8192, u64::MAX), (64, 32));
        assert_eq!(common_size(&maps, 16, u64::MAX), (16, 16));
        assert_eq!(common_size(&[], 8192, u64::MAX), (1, 1));
        let (w, h) = common_size(&maps, 8192, 3 * 16 * 8 * 8 * 2);
        assert!(array_bytes(w, h, 3) <= 3 * 16 * 8 * 8 * 2, "{w}x{h}");
        assert_eq!((w, h), (16, 8));
    }

    #[test]
    fn shared_maps_get_one_layer_and_untextured_materials_the_white_one() {
        use lustre_geometry::Material;
        let a = texture(4, 4);
        let b = texture(2, 2);
        let scene = lustre_geometry::builtin("cornell").unwrap();
        let mut mats = scene.materials().to_vec();
        assert!(mats.len() >= 3);
        mats[0] = Material::diffuse("a", Rgb::ONE).with_diffuse_map(a.clone());
        mats[2] = Material::diffuse("b", Rgb::ONE).with_diffuse_map(b);
        mats[1] = Material::diffuse("a again", Rgb::ONE).with_diffuse_map(a);
        let scene = scene.with_materials(mats).unwrap();
        let (layers, maps) = diffuse_map_layers(&scene);
        assert_eq!(&layers[..3], &[1, 1, 2]);
        assert!(layers[3..].iter().all(|&l| l == WHITE_LAYER));
        assert_eq!(maps.len(), 2);
    }
}
