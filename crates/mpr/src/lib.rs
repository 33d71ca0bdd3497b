//! # lustre-mpr
//!
//! Multi-pass pipeline rendering (Diefenbach & Badler 1997) on wgpu: a
//! headless device ([`GpuContext`]), the frame's render targets
//! ([`RenderTargets`]), the [`View`] every scene pass draws under, one module per pass with its WGSL beside it
//! ([`passes`]), the frame graph that runs them in one command encoder into
//! any `TextureView` ([`FrameGraph`]), and synchronous readback
//! ([`readback`]). Every pass has a CPU counterpart computing the same
//! per-pixel quantity, which the tests hold the GPU to.
//!
//! | pass | paper | CPU twin |
//! |---|---|---|
//! | [`passes::depth`]: reverse-Z depth and surface ids | Diefenbach & Badler 1997, 7.2 | BVH ray casts |
//! | [`passes::emission`]: emitters' own radiance | (light sources seen directly) | ray cast + material `Le` |
//! | [`passes::direct`], [`passes::shadow`]: point lights, cube shadow maps, per-pixel BRDF | Stürzlinger & Bastos 1997, 2.2.1 | ray cast + shadow ray |
//! | [`passes::shadow_volume`], [`passes::shadowed_direct`]: shadow volumes counted z-fail in the stencil's upper half, each point light added without its shadow map where the count is zero, under every view | Diefenbach & Badler 1997, 4.1, 4.4, 7.2, 7.3 | BVH shadow rays; `lustre_geometry::shadow_volume::shadow_count` |
//! | [`passes::splat`]: photon splats, 64² kernel texture with mips, surface-id or stencil restriction | Stürzlinger & Bastos 1997, 2.2, 3.2, equation 2 | `SplatEstimator::radiance_splatted` |
//! | [`passes::specular`]: mirror faces masked in the stencil, the scene redrawn from their virtual views, recursively | Diefenbach & Badler 1997, 3, 7.1, 7.3 | mirror ray tracer (`tests/specular.rs`) |
//! | [`passes::glossy_image`] (lobes and shears in [`passes::glossy_lobe`]): planar glossy faces' images from N mirror views sheared about the face normal (`View::sheared_reflection`), fogged with distance from the face, averaged in a float target and added times R inside the face | Diefenbach & Badler 1997, 3 ("glossy marble", `shear_view`, `accbuf`) | analytic shear (`view.rs`), mirror path, fogged mirror ray trace and the lobe's erf integral (`tests/glossy_image.rs`); frosted glass slabs the same way through `View::sheared_through_slab` |
//! | [`passes::beams`]: specular, glossy and shadow polygon beams of point lights evaluated per fragment, linear or hierarchical traversal | Duvenhage et al. 2010, 3.1, 4.2, 4.3, 5.2 | `lustre_beams::Beam::arrival` ([`passes::beams::beam_pixels_cpu`]) |
//! | [`passes::tonemap`]: exposure, clamp or Reinhard, sRGB | — | per-pixel formula |
//!
//! Virtual lights through mirrors, slabs and interfaces ([`virtual_light`],
//! sections 4.2, 4.3) and through stained-glass windows as projective
//! textures ([`projective_texture`], section 4.5) are drawn by
//! [`passes::light_volume`] under every view; their CPU twin unfolds each
//! light path with BVH ray casts.
//!
//! Materials reach the GPU as weighted BRDF lobes ([`material`]) evaluated by
//! the WGSL twins of `lustre-brdf`, their diffuse texture maps as one
//! mip-mapped texture array ([`diffuse_map`]) that scales the lobes' `kd`.
//!
//! ```no_run
//! use lustre_mpr::{AdapterPreference, GpuContext, RenderTargets};
//!
//! let ctx = GpuContext::new(AdapterPreference::Hardware)?;
//! println!("rendering on {}", ctx.adapter());
//! let targets = RenderTargets::new(&ctx, 64, 64)?;
//! assert_eq!(targets.hdr_format(), ctx.hdr_format());
//! # Ok::<(), lustre_mpr::MprError>(())
//! ```

pub mod beam_paths;
mod device;
pub mod diffuse_map;
mod error;
pub mod frame;
pub mod ibr;
pub mod kernel_texture;
pub mod light_group;
pub mod material;
pub mod pass_timing;
pub mod passes;
pub mod projective_texture;
pub mod readback;
pub mod scene_buffers;
pub mod shaders;
pub mod target;
pub mod view;
pub mod virtual_light;

pub use device::{AdapterPreference, AdapterSummary, GpuContext};
pub use error::{MprError, Result};
pub use frame::{FrameGraph, FrameInputs, GraphTerms};
pub use scene_buffers::{GpuVertex, SceneBuffers};
pub use target::{NO_SURFACE, RenderTargets};
pub use view::{ClipMethod, View, ViewBuffer, ViewSlot};
