//! The per-frame render targets: linear HDR radiance (f32 when blendable,
//! f16 otherwise), reverse-Z depth and surface ids (DESIGN.md "Data flow", step 3).

use crate::{GpuContext, MprError, Result};

/// Depth format without stencil: 32-bit float, reverse Z (see [`REVERSE_Z_CLEAR`]); [`GpuContext::depth_format`] adds an 8-bit stencil where the device has one.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Depth clear value with reverse Z: 0 is infinitely far, 1 the near plane.
pub const REVERSE_Z_CLEAR: f32 = 0.0;
/// Depth test with reverse Z: nearer is greater.
pub const REVERSE_Z_COMPARE: wgpu::CompareFunction = wgpu::CompareFunction::Greater;
/// Format of the surface-id target: one scene `SurfaceId` per pixel.
pub const SURFACE_ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Surface id of a pixel that sees no surface (its clear value).
pub const NO_SURFACE: u32 = u32::MAX;

/// One texture and its default view.
#[derive(Debug)]
pub struct Target {
    /// The texture.
    pub texture: wgpu::Texture,
    /// A view of the whole texture.
    pub view: wgpu::TextureView,
}

impl Target {
    /// A 2D render attachment that can also be sampled and copied out.
    pub(crate) fn new(
        ctx: &GpuContext,
        label: &str,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Self {
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Self { texture, view }
    }
}

/// Checks a requested image size against the device's 2D limit.
pub(crate) fn check_size(
    ctx: &GpuContext,
    what: &'static str,
    width: u32,
    height: u32,
) -> Result<()> {
    let max = ctx.device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(MprError::InvalidSize {
            what,
            width,
            height,
            max,
        });
    }
    Ok(())
}

/// The frame's targets: HDR radiance, reverse-Z depth and surface ids, all `width`×`height`.
#[derive(Debug)]
pub struct RenderTargets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear HDR radiance in W/(m² sr), RGBA.
    pub hdr: Target,
    /// Reverse-Z depth ([`GpuContext::depth_format`]: with stencil where available).
    pub depth: Target,
    /// Scene surface id per pixel ([`SURFACE_ID_FORMAT`], [`NO_SURFACE`] where none).
    pub surface_id: Target,
    /// The accumulation buffer of jittered frames, in the HDR format
    /// (Diefenbach & Badler 1997, section 7; [`crate::passes::accumulate`]).
    pub accumulation: Target,
}

impl RenderTargets {
    /// Targets in the device's HDR format ([`GpuContext::hdr_format`]).
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self> {
        Self::with_hdr_format(ctx, width, height, ctx.hdr_format())
    }

    /// Targets with an explicit HDR format: `Rgba32Float` or `Rgba16Float`.
    pub fn with_hdr_format(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        hdr_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        check_size(ctx, "render targets", width, height)?;
        if !matches!(
            hdr_format,
            wgpu::TextureFormat::Rgba32Float | wgpu::TextureFormat::Rgba16Float
        ) {
            return Err(MprError::UnsupportedFormat {
                what: "HDR render target",
                format: hdr_format,
            });
        }
        Ok(Self {
            width,
            height,
            hdr: Target::new(ctx, "hdr", width, height, hdr_format),
            depth: Target::new(ctx, "depth", width, height, ctx.depth_format()),
            surface_id: Target::new(ctx, "surface-id", width, height, SURFACE_ID_FORMAT),
            accumulation: Target::new(ctx, "accumulation", width, height, hdr_format),
        })
    }

    /// The HDR format in use.
    pub fn hdr_format(&self) -> wgpu::TextureFormat {
        self.hdr.texture.format()
    }

    /// The depth format in use.
    pub fn depth_format(&self) -> wgpu::TextureFormat {
        self.depth.texture.format()
    }

    /// Width over height, for [`lustre_geometry::Camera::with_aspect`].
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }
}
