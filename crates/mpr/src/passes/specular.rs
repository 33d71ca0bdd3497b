//! Specular images of planar mirror faces, glass slabs and single
//! refracting interfaces (Diefenbach & Badler 1997, sections 3 and 7.1,
//! 7.3; the virtual cameras of Heckbert & Hanrahan's beam tracing, in
//! [`crate::view`]): `mask_face` draws a face with the depth test
//! into the stencil (level `k` → `k + 1`), the depth inside the mask is
//! reset to far, the whole scene is drawn again from the virtual camera of
//! the mirror transform only where the stencil holds `k + 1` (recursively,
//! depth first, the recursion depth kept in the stencil values), and the
//! face is restored: its depth and surface id written back, the stencil
//! popped to `k`, the image inside multiplied by the mirror's reflectance.
//! Geometry on the far side of the face is clipped ([`crate::view`]).
//!
//! At the recursion limit a face shows `R · L_lim` rather than black:
//! [`SpecularSettings::limit_radiance`], by default the radiance of a white
//! Lambertian surface under the scene's mean first-bounce irradiance
//! ([`mean_radiance`]) — the paper's constant ambient term (section 7.4)
//! standing in for the images not drawn.
//!
//! A single interface passes its image times `1 − F₀` and the radiance
//! law's `(n_eye / n_beyond)²` ([`image_factor`]; the record tells the eye's
//! side by the face's plane). A curved dielectric whose triangles lean at
//! most [`MAX_INTERFACE_TILT_DEGREES`] from their mean plane (the pool's
//! wavy water) is one interface at that plane ([`nearly_planar`], beyond
//! the paper, which images planar faces only), each side's plane moved to
//! the corner farthest behind it so that the view through it clips all of
//! its triangles: the waves do not distort the view.
//!
//! CPU twin: the views of [`ViewTree`] are checked against ray casts through
//! the mirrors (`tests/specular.rs`).

use std::ops::Range;

use glam::Vec3;

use crate::light_group::GlossyLights;
use crate::passes::glossy_image::{
    GlossyImagePass, GlossySample, GlossySettings, ShearModel, frosted, glossy_faces,
    microfacet_shears, shear_slopes,
};
use lustre_geometry::SurfaceKind;
use lustre_geometry::material::MaterialModel;
use lustre_geometry::{Plane, Scene};
use wgpu::util::DeviceExt;

use crate::passes::redraw::{additive_target, scene_module, stencil_equal, view_stencil};
use crate::scene_buffers::{GpuVertex, SceneBuffers};
use crate::shaders::with_view;
use crate::target::{RenderTargets, SURFACE_ID_FORMAT};
use crate::view::{ClipMethod, View, ViewBuffer, ViewSlot};
use crate::{GpuContext, MprError, Result};

/// The specular pass's own WGSL (`src/passes/specular.wgsl`); compiled after the view block.
pub const SPECULAR_WGSL: &str = include_str!("specular.wgsl");

/// The most views one frame may hold (`n^d` grows fast, equation 8).
pub const MAX_VIEWS: usize = 4096;

/// How deep specular images recurse and what a face shows at the limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecularSettings {
    /// Recursion depth `d` (section 8.2): 0 draws no specular image.
    pub max_depth: u32,
    /// `L_lim`, the radiance a face reflects at the limit (W/(m² sr), RGB).
    pub limit_radiance: Vec3,
    /// The clip method; `None` takes the device's ([`GpuContext::clip_method`]).
    pub clip: Option<ClipMethod>,
}

impl Default for SpecularSettings {
    fn default() -> Self {
        Self {
            max_depth: 2,
            limit_radiance: Vec3::ZERO,
            clip: None,
        }
    }
}

/// The radiance `Φ / (π A)` of a white Lambertian surface receiving the
/// scene's emitted power `Φ` spread over its total surface area `A`: the
/// default [`SpecularSettings::limit_radiance`].
pub fn mean_radiance(scene: &Scene) -> Vec3 {
    let area: f32 = scene.surfaces().iter().map(|s| s.area).sum();
    if area <= 0.0 {
        return Vec3::ZERO;
    }
    let power = scene.total_power();
    Vec3::new(power.x, power.y, power.z) / (std::f32::consts::PI * area)
}

/// How a specular face makes its image (section 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpecularKind {
    /// A planar mirror: the mirror transform of its plane.
    Mirror,
    /// One face of a glass slab (in-out refraction, section 2): seen through
    /// it, a point beyond the slab appears moved towards the viewer along the
    /// face's normal by `shift = t (1 - 1/η)`, the paraxial limit of Heckbert &
    /// Hanrahan's refraction at both faces; geometry nearer than the far face
    /// (`thickness` t behind this one) is clipped.
    Slab {
        /// Apparent displacement `t (1 - 1/η)` in m.
        shift: f32,
        /// Thickness t of the slab in m.
        thickness: f32,
    },
    /// A single refracting interface (section 3, Heckbert & Hanrahan's
    /// paraxial refraction): seen from the normal's side, what lies beyond
    /// appears at `ratio` of its depth, `ratio = n_eye / n_beyond`.
    Interface {
        /// `n` on the normal's side over `n` beyond.
        ratio: f32,
    },
    /// A planar glossy face (section 3, "glossy marble"): `samples` mirror
    /// views sheared about its normal, averaged ([`crate::passes::glossy_image`]).
    Glossy(GlossyImage),
    /// A stained-glass window of thin panes seen from one side (section
    /// 4.5): light passes straight through, modulated by the projective
    /// texture of window `window` of [`crate::projective_texture::windows`].
    /// Only virtual lights pass it; it makes no image of its own.
    Pane {
        /// Index of its window.
        window: u32,
    },
}

/// How a glossy face makes its image (section 3, `shear_view` and `accbuf`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlossyImage {
    /// The lobe's roughness α (RMS slope): the shear samples' RMS length is 2α.
    pub alpha: f32,
    /// Sheared images `N`.
    pub samples: u32,
    /// Images are made only from views of level below this; deeper the face shows `R · L_lim`.
    pub depth: u32,
    /// `f_max` in m (infinite: no fog).
    pub fog_distance: f32,
    /// Whether the sheared views hide emitters.
    pub hide_emitters: bool,
    /// How the shears are drawn from the lobe.
    pub shear: ShearModel,
    /// `None` for a glossy reflection; `Some((shift, thickness))` for a
    /// frosted glass slab ([`SpecularKind::Slab`]'s), whose images are
    /// sheared slab views (section 3's frosted glass).
    pub through_slab: Option<(f32, f32)>,
    /// Which jittered lights its sheared views draw ([`crate::light_group`]).
    pub lights: GlossyLights,
}

/// One planar specular face: a mirror, or a face of a glass slab.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecularFace {
    /// Its `SurfaceId`.
    pub surface: u32,
    /// Its plane; the face makes its image for eyes on the side its normal points to.
    pub plane: Plane,
    /// Mirror or slab.
    pub kind: SpecularKind,
    /// What it passes of its image: the mirror's reflectance, or the slab's
    /// transmittance times `(1 - F0)²` (Fresnel at normal incidence, both faces).
    pub factor: Vec3,
    /// The corners of its triangles in world space, for culling against a view.
    pub corners: Vec<Vec3>,
}

/// The specular faces of `scene`: planar surfaces of a mirror material;
/// planar faces of a dielectric whose mesh has a parallel face of the same
/// material facing the other way behind them (a slab); and planar
/// dielectric faces without such a partner, single interfaces, twice: as
/// wound (the normal on the outside, ratio `1/η`) and turned round (seen
/// from inside the medium, ratio `η`), each passing `1 − F₀` times the
/// transmittance.
pub fn specular_faces(scene: &Scene) -> Vec<SpecularFace> {
    let surfaces = scene.surfaces();
    let slabs = lustre_geometry::slab::slab_faces(scene);
    let planar = |s: &lustre_geometry::Surface| match s.kind {
        SurfaceKind::Planar(plane) => Some(plane),
        SurfaceKind::Curved => None,
    };
    let corners = |surface: &lustre_geometry::Surface| -> Vec<Vec3> {
        let positions = scene.world_positions(surface.mesh);
        let mesh = &scene.meshes()[surface.mesh as usize];
        surface
            .triangles
            .iter()
            .flat_map(|&t| mesh.indices[t as usize])
            .map(|i| positions[i as usize])
            .collect()
    };
    surfaces
        .iter()
        .enumerate()
        .flat_map(|(id, surface)| {
            let material = &scene.materials()[surface.material as usize];
            // A wavy dielectric (the pool's water) is one interface at its
            // mean plane where it is nearly flat; other curved surfaces make
            // no image. The corners are gathered once, for specular surfaces.
            let curved_interface =
                matches!(material.model, MaterialModel::Dielectric { .. }) && slabs[id].is_none();
            let specular = matches!(
                material.model,
                MaterialModel::Mirror { .. } | MaterialModel::Dielectric { .. }
            );
            if !specular || (planar(surface).is_none() && !curved_interface) {
                return Vec::new();
            }
            let corners = corners(surface);
            let Some(plane) = planar(surface).or_else(|| nearly_planar(&corners)) else {
                return Vec::new();
            };
            match material.model {
                MaterialModel::Mirror { reflectance } => vec![SpecularFace {
                    surface: id as u32,
                    plane,
                    kind: SpecularKind::Mirror,
                    factor: Vec3::new(reflectance.x, reflectance.y, reflectance.z),
                    corners,
                }],
                MaterialModel::Dielectric { ior, transmittance } => {
                    let thickness = slabs[id].map(|slab| slab.thickness);
                    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
                    let tint = Vec3::new(transmittance.x, transmittance.y, transmittance.z);
                    match thickness {
                        Some(thickness) => vec![SpecularFace {
                            surface: id as u32,
                            plane,
                            kind: SpecularKind::Slab {
                                shift: thickness * (1.0 - 1.0 / ior),
                                thickness,
                            },
                            factor: tint * (1.0 - f0) * (1.0 - f0),
                            corners,
                        }],
                        None => {
                            // A curved face's plane on each side moved to its
                            // farthest corner behind it, so that the view
                            // through it clips every one of its triangles away.
                            let behind = |plane: Plane| match surface.kind {
                                SurfaceKind::Planar(_) => plane,
                                SurfaceKind::Curved => Plane {
                                    offset: plane.offset
                                        + corners
                                            .iter()
                                            .map(|&c| plane.signed_distance(c))
                                            .fold(0.0, f32::min),
                                    ..plane
                                },
                            };
                            let face = |plane: Plane, ratio: f32| SpecularFace {
                                surface: id as u32,
                                plane: behind(plane),
                                kind: SpecularKind::Interface { ratio },
                                factor: tint * (1.0 - f0),
                                corners: corners.clone(),
                            };
                            vec![face(plane, 1.0 / ior), face(plane.flipped(), ior)]
                        }
                    }
                }
                _ => Vec::new(),
            }
        })
        .collect()
}

/// Largest angle between a triangle's normal and the fitted plane's normal
/// for a curved dielectric to count as one interface ([`nearly_planar`]).
pub const MAX_INTERFACE_TILT_DEGREES: f32 = 20.0;

/// The plane of a curved surface's triangles (`corners`, three per
/// triangle) where they are nearly flat: the area-weighted mean normal
/// through the area-weighted centroid, or `None` when a triangle's normal
/// leans more than [`MAX_INTERFACE_TILT_DEGREES`] from it or a corner lies
/// farther from it than a tenth of the surface's extent across.
pub fn nearly_planar(corners: &[Vec3]) -> Option<Plane> {
    let triangles = corners.chunks_exact(3);
    let (mut weighted, mut centroid, mut area) = (Vec3::ZERO, Vec3::ZERO, 0.0);
    for t in triangles.clone() {
        let n = (t[1] - t[0]).cross(t[2] - t[0]) * 0.5;
        let a = n.length();
        weighted += n;
        centroid += (t[0] + t[1] + t[2]) / 3.0 * a;
        area += a;
    }
    if !(area > 0.0) || weighted.length() <= 0.0 {
        return None;
    }
    let plane = Plane::from_point_normal(centroid / area, weighted);
    let cos_tilt = MAX_INTERFACE_TILT_DEGREES.to_radians().cos();
    let (lo, hi) = corners
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &c| {
            (lo.min(c), hi.max(c))
        });
    let extent = (hi - lo).length();
    let flat = triangles.clone().all(|t| {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        n.dot(plane.normal) >= cos_tilt
    }) && corners
        .iter()
        .all(|&c| plane.signed_distance(c).abs() <= 0.1 * extent);
    flat.then_some(plane)
}

/// The views of one frame in depth-first order and, per view, the faces
/// recursed into with the index of the child view (section 7.1,
/// `draw_spec_objects`), or the faces at the recursion limit.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewTree {
    /// Every view; index 0 is the camera. A view exists for each face
    /// that may be seen (turned towards the eye, inside the frustum, not
    /// wholly clipped: [`View::may_see`]).
    pub views: Vec<View>,
    /// Per view: `(face index, child view index)` for each face it recurses into.
    pub children: Vec<Vec<(usize, usize)>>,
    /// Per view: faces it sees at the recursion limit.
    pub limit_faces: Vec<Vec<usize>>,
    /// Per view: which sheared image of a glossy face it draws, if it is one.
    pub samples: Vec<Option<GlossySample>>,
    /// Per view: the sample path of the outermost glossy image it lies in
    /// (itself or an ancestor), which [`crate::light_group::LightGroup::for_path`]
    /// pairs with a group of the jittered lights; `None` outside glossy images.
    pub paths: Vec<Option<GlossyPath>>,
}

/// Sample path `index` of the `of` shears of the outermost glossy image a
/// view lies in (section 3): the shear index that image drew it with, which
/// images nested in it inherit ([`nested_shear_index`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GlossyPath {
    /// The outer image's shear index, `0..of`.
    pub index: u32,
    /// Its shear count `N`.
    pub of: u32,
    /// Which jittered lights the path's views draw.
    pub lights: GlossyLights,
}

impl ViewTree {
    /// Per view, the pixels of a `width × height` target its stencil area
    /// can hold, `[x, y, w, h]`: the whole target for the camera, and for a
    /// face's view the bounding rectangle of the face's corners projected
    /// through the view that sees it (a pixel added all round), within that
    /// view's own rectangle; that view's rectangle where a corner lies
    /// behind its eye. Views follow their parents, so one pass suffices.
    pub fn regions(&self, faces: &[SpecularFace], width: u32, height: u32) -> Vec<[u32; 4]> {
        let full = [0, 0, width, height];
        let mut out = vec![full; self.views.len()];
        for (index, children) in self.children.iter().enumerate() {
            let m = self.views[index].view_projection();
            let parent = out[index];
            for &(f, child) in children {
                let Some(face) = faces.get(f) else {
                    continue;
                };
                let mut lo = glam::DVec2::splat(f64::INFINITY);
                let mut hi = glam::DVec2::splat(f64::NEG_INFINITY);
                let mut behind = face.corners.is_empty();
                for c in &face.corners {
                    let p = m * c.extend(1.0);
                    if p.w <= 1e-6 {
                        behind = true;
                        break;
                    }
                    let ndc = glam::Vec2::new(p.x / p.w, p.y / p.w).as_dvec2();
                    lo = lo.min(ndc);
                    hi = hi.max(ndc);
                }
                out[child] = if behind {
                    parent
                } else {
                    crate::view::intersect_rects(
                        crate::view::ndc_to_pixels(lo, hi, width, height),
                        parent,
                    )
                };
            }
        }
        out
    }

    /// The tree of a frame without specular faces: the camera alone.
    pub fn single(root: View) -> Self {
        Self {
            views: vec![root],
            children: vec![Vec::new()],
            limit_faces: vec![Vec::new()],
            samples: vec![None],
            paths: vec![None],
        }
    }

    /// The tree of `faces` seen from `root` to depth `max_depth`: a face
    /// recurses where its mirror side faces the view's eye (the eye of a
    /// virtual view lies behind its own face, so no face recurses into itself).
    pub fn build(
        root: View,
        faces: &[SpecularFace],
        max_depth: u32,
        clip: ClipMethod,
    ) -> Result<Self> {
        Self::build_interleaved(root, faces, max_depth, clip, None)
    }

    /// [`ViewTree::build`] for frame `s` of `n` accumulated ones: each glossy
    /// image takes only its shears `s, s + n, s + 2n, …` (all of them when it
    /// has fewer than `n`), so the `n` frames' accumulation buffer averages
    /// every shear once (section 3's `accbuf` shared with section 7's).
    pub fn build_interleaved(
        root: View,
        faces: &[SpecularFace],
        max_depth: u32,
        clip: ClipMethod,
        frame: Option<(u32, u32)>,
    ) -> Result<Self> {
        let mut tree = Self::single(root);
        tree.grow(0, faces, max_depth, clip, frame, None)?;
        Ok(tree)
    }

    fn grow(
        &mut self,
        index: usize,
        faces: &[SpecularFace],
        max_depth: u32,
        clip: ClipMethod,
        frame: Option<(u32, u32)>,
        path: Option<GlossyPath>,
    ) -> Result<()> {
        let view = self.views[index];
        for (f, face) in faces.iter().enumerate() {
            // Viewpoint culling (section 8.2): a face turned away from the
            // eye, outside the frustum or wholly clipped makes no image.
            if face.plane.signed_distance(view.eye) <= 0.0 || !view.may_see(&face.corners) {
                continue;
            }
            let glossy_limit =
                matches!(face.kind, SpecularKind::Glossy(g) if view.level >= g.depth);
            if view.level >= max_depth || glossy_limit {
                self.limit_faces[index].push(f);
                continue;
            }
            // (view, its glossy sample, the path index its subtree inherits)
            let children: Vec<(View, Option<GlossySample>, Option<GlossyPath>)> = match face.kind {
                SpecularKind::Mirror => vec![(view.reflected(&face.plane, clip), None, path)],
                SpecularKind::Slab { shift, thickness } => vec![(
                    view.through_slab(&face.plane, shift, thickness, clip),
                    None,
                    path,
                )],
                SpecularKind::Glossy(glossy) => {
                    let n_all = glossy.samples.max(1);
                    // (shear, weight) per sample: the paper's isotropic 2m, or
                    // the microfacet reflection at the face's centroid.
                    let all: Vec<(glam::Vec2, f32)> = match glossy.shear {
                        ShearModel::Isotropic => shear_slopes(glossy.alpha, n_all)
                            .into_iter()
                            .map(|s| (s, 1.0))
                            .collect(),
                        ShearModel::Microfacet => {
                            let centroid = face.corners.iter().copied().sum::<Vec3>()
                                / face.corners.len().max(1) as f32;
                            microfacet_shears(glossy.alpha, n_all, view.eye, &face.plane, centroid)
                        }
                    };
                    let chosen: Vec<(u32, (glam::Vec2, f32))> = match (path, frame) {
                        // Inside another glossy image: one shear per sample of
                        // the outer image, so its N samples are N paths through
                        // both lobes (module docs of `glossy_image`).
                        (Some(p), _) => {
                            let i = nested_shear_index(p.index, n_all);
                            vec![(p.index, all[i as usize])]
                        }
                        (None, Some((s, n))) if n > 1 && n_all >= n => (0..n_all)
                            .skip((s % n) as usize)
                            .step_by(n as usize)
                            .map(|i| (i, all[i as usize]))
                            .collect(),
                        _ => (0..n_all).zip(all).collect(),
                    };
                    // Each drawn sample weighs w / (samples this frame); a sample
                    // whose facet reflects below the face (w = 0) is not drawn.
                    let per = 1.0 / chosen.len().max(1) as f32;
                    let drawn: Vec<(u32, (glam::Vec2, f32))> =
                        chosen.into_iter().filter(|(_, (_, w))| *w > 0.0).collect();
                    let count = drawn.len() as u32;
                    drawn
                        .into_iter()
                        .enumerate()
                        .map(|(i, (global, (slope, weight)))| {
                            let mut sheared = match glossy.through_slab {
                                None => view.sheared_reflection(&face.plane, slope, clip),
                                Some((shift, thickness)) => view.sheared_through_slab(
                                    &face.plane,
                                    shift,
                                    thickness,
                                    slope,
                                    clip,
                                ),
                            };
                            sheared.shows_emitters = !glossy.hide_emitters;
                            let sample = GlossySample {
                                face: f,
                                index: i as u32,
                                count,
                                weight: weight * per,
                            };
                            // The outermost image's path is inherited as is.
                            let child_path = path.unwrap_or(GlossyPath {
                                index: global,
                                of: n_all,
                                lights: glossy.lights,
                            });
                            (sheared, Some(sample), Some(child_path))
                        })
                        .collect()
                }
                SpecularKind::Interface { ratio } => {
                    vec![(view.through_interface(&face.plane, ratio, clip), None, path)]
                }
                // Windows light through their texture only (section 4.5).
                SpecularKind::Pane { .. } => Vec::new(),
            };
            for (child_view, sample, child_path) in children {
                if self.views.len() >= MAX_VIEWS {
                    return Err(MprError::InvalidSetting {
                        what: "specular recursion",
                        message: format!(
                            "more than {MAX_VIEWS} views: lower the recursion depth (now \
                             {max_depth}) or the glossy image samples"
                        ),
                    });
                }
                let child = self.views.len();
                self.views.push(child_view);
                self.children.push(Vec::new());
                self.limit_faces.push(Vec::new());
                self.samples.push(sample);
                self.paths.push(child_path);
                self.children[index].push((f, child));
                self.grow(child, faces, max_depth, clip, frame, child_path)?;
            }
        }
        Ok(())
    }

    /// Scene renderings per frame: one per view (the paper's "scene iterations" of table 3).
    pub fn scene_passes(&self) -> usize {
        self.views.len()
    }
}

/// The shear (of `n`) a glossy image nested in sample `path` of an outer
/// one takes: `path · k mod n`, `k` the first integer from `0.618 n` up
/// that is coprime with `n`, so the inner shears are a permutation of the
/// outer ones that pairs neither large with large nor like angles.
pub fn nested_shear_index(path: u32, n: u32) -> u32 {
    let n = n.max(1);
    let k = crate::light_group::coprime_step(n, 0.618);
    ((u64::from(path % n) * u64::from(k)) % u64::from(n)) as u32
}

/// The range of `face`'s triangles in [`SceneBuffers::surface_indices`].
fn face_indices(scene: &SceneBuffers, face: &SpecularFace) -> Range<u32> {
    scene
        .surface_ranges
        .get(face.surface as usize)
        .cloned()
        .unwrap_or(0..0)
}

/// The per-surface record of `specular.wgsl`: what the face passes of its
/// image to an eye in front of `plane` and to one behind it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuFace {
    reflectance: [f32; 4],
    behind: [f32; 4],
    plane: [f32; 4],
}

impl GpuFace {
    const NONE: Self = Self {
        reflectance: [0.0; 4],
        behind: [0.0; 4],
        plane: [0.0; 4],
    };
}

/// What `face` passes of the radiance of its image to the eye: its factor,
/// and through a single interface also the ratio² = (n_eye / n_beyond)² by
/// which radiance changes across it (`L/n²` is conserved along a refracted
/// ray; the paper's accumulation leaves it out).
pub fn image_factor(face: &SpecularFace) -> Vec3 {
    match face.kind {
        SpecularKind::Interface { ratio } => face.factor * ratio * ratio,
        _ => face.factor,
    }
}

/// The GPU specular pass for one scene's mirror faces.
#[derive(Debug)]
pub struct SpecularPass {
    faces: Vec<SpecularFace>,
    settings: SpecularSettings,
    mask: wgpu::RenderPipeline,
    reset: wgpu::RenderPipeline,
    restore: wgpu::RenderPipeline,
    /// The restore of a glossy image's sample: the image inside cleared to zero.
    restore_zero: wgpu::RenderPipeline,
    limit: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    /// The glossy images' accumulation, when the pass has glossy faces.
    glossy: Option<GlossyImagePass>,
}

impl SpecularPass {
    /// Builds the pipelines for `scene`'s mirror faces and HDR targets of `hdr_format`.
    pub fn new(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &Scene,
        settings: SpecularSettings,
    ) -> Result<Self> {
        Self::with_glossy(ctx, hdr_format, scene, settings, &GlossySettings::default())
    }

    /// [`SpecularPass::new`] with the glossy faces of `glossy` too (section
    /// 3, "glossy marble"; none when `glossy.samples` is 0).
    pub fn with_glossy(
        ctx: &GpuContext,
        hdr_format: wgpu::TextureFormat,
        scene: &Scene,
        settings: SpecularSettings,
        glossy: &GlossySettings,
    ) -> Result<Self> {
        glossy.validate()?;
        if settings.max_depth > 120 {
            return Err(MprError::InvalidSetting {
                what: "specular recursion depth",
                message: format!(
                    "{} exceeds the 120 levels the lower half of the stencil holds (section 7.3)",
                    settings.max_depth
                ),
            });
        }
        if !settings.limit_radiance.is_finite() || settings.limit_radiance.min_element() < 0.0 {
            return Err(MprError::InvalidSetting {
                what: "specular limit radiance",
                message: format!("{} is not a finite radiance", settings.limit_radiance),
            });
        }
        let mut faces = frosted(specular_faces(scene), scene, glossy);
        faces.extend(glossy_faces(scene, glossy));
        let glossy_pass = faces
            .iter()
            .any(|f| matches!(f.kind, SpecularKind::Glossy(_)))
            .then(|| GlossyImagePass::new(ctx, hdr_format, &faces, glossy.fog_radiance))
            .transpose()?;
        let mut records = vec![GpuFace::NONE; scene.surfaces().len()];
        for face in &faces {
            let record = &mut records[face.surface as usize];
            let factor = image_factor(face).extend(1.0).to_array();
            match face.kind {
                // The two sides of a single interface: the first (wound)
                // face's plane tells them apart.
                SpecularKind::Interface { .. } if record.reflectance[3] > 0.0 => {
                    record.behind = factor;
                }
                kind => {
                    *record = GpuFace {
                        reflectance: factor,
                        behind: factor,
                        plane: match kind {
                            SpecularKind::Interface { .. } => face.plane.to_vec4().to_array(),
                            _ => [0.0; 4],
                        },
                    };
                }
            }
        }
        if records.is_empty() {
            records.push(GpuFace::NONE);
        }
        let depth_format = ctx.depth_format();
        ctx.checked("specular pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "specular", &with_view(SPECULAR_WGSL));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("specular"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Storage { read_only: true },
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("specular"),
                bind_group_layouts: &[Some(ctx.view_layout()), Some(&layout)],
                immediate_size: 0,
            });
            let primitive = wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            };
            let vertex = |entry: &'static str, buffers: bool| wgpu::VertexState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                buffers: if buffers {
                    &[Some(GpuVertex::LAYOUT)]
                } else {
                    &[]
                },
            };
            let depth = |compare, write, stencil| {
                Some(wgpu::DepthStencilState {
                    format: depth_format,
                    depth_write_enabled: Some(write),
                    depth_compare: Some(compare),
                    stencil,
                    bias: wgpu::DepthBiasState::default(),
                })
            };
            // mask_face: where the face is the visible surface of level k, k -> k + 1.
            let mask = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("specular-mask"),
                layout: Some(&pipeline_layout),
                vertex: vertex("vs_main", true),
                primitive,
                depth_stencil: depth(
                    wgpu::CompareFunction::Equal,
                    false,
                    stencil_equal(wgpu::StencilOperation::IncrementClamp),
                ),
                multisample: wgpu::MultisampleState::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            });
            // Depth inside the mask back to far, so the virtual view's depth pass starts clean.
            let reset = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("specular-reset"),
                layout: Some(&pipeline_layout),
                vertex: vertex("vs_far", false),
                primitive,
                depth_stencil: depth(
                    wgpu::CompareFunction::Always,
                    true,
                    stencil_equal(wgpu::StencilOperation::Keep),
                ),
                multisample: wgpu::MultisampleState::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            });
            // The face restored at level k: depth and id written back, k + 1 -> k,
            // the image drawn inside scaled by R (blend: dst * src).
            let restore_with = |label: &str, entry: &str| {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pipeline_layout),
                    vertex: vertex("vs_main", true),
                    primitive,
                    depth_stencil: depth(
                        wgpu::CompareFunction::Always,
                        true,
                        stencil_equal(wgpu::StencilOperation::DecrementClamp),
                    ),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets: &[
                            Some(wgpu::ColorTargetState {
                                format: hdr_format,
                                blend: Some(wgpu::BlendState {
                                    color: wgpu::BlendComponent {
                                        src_factor: wgpu::BlendFactor::Zero,
                                        dst_factor: wgpu::BlendFactor::Src,
                                        operation: wgpu::BlendOperation::Add,
                                    },
                                    alpha: wgpu::BlendComponent {
                                        src_factor: wgpu::BlendFactor::Zero,
                                        dst_factor: wgpu::BlendFactor::One,
                                        operation: wgpu::BlendOperation::Add,
                                    },
                                }),
                                write_mask: wgpu::ColorWrites::ALL,
                            }),
                            Some(wgpu::ColorTargetState {
                                format: SURFACE_ID_FORMAT,
                                blend: None,
                                write_mask: wgpu::ColorWrites::ALL,
                            }),
                        ],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let restore = restore_with("specular-restore", "fs_restore");
            // A glossy sample's restore: the image inside multiplied by zero (it was accumulated).
            let restore_zero = restore_with("specular-restore-zero", "fs_restore_zero");
            let limit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("specular-limit"),
                layout: Some(&pipeline_layout),
                vertex: vertex("vs_main", true),
                primitive,
                depth_stencil: depth(wgpu::CompareFunction::Equal, false, view_stencil()),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_limit"),
                    compilation_options: Default::default(),
                    targets: &[Some(additive_target(hdr_format))],
                }),
                multiview_mask: None,
                cache: None,
            });
            let faces_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("specular-faces"),
                contents: bytemuck::cast_slice(&records),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("specular-uniforms"),
                contents: bytemuck::cast_slice(&settings.limit_radiance.extend(0.0).to_array()),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("specular"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: faces_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: uniforms.as_entire_binding(),
                    },
                ],
            });
            Self {
                faces,
                settings,
                mask,
                reset,
                restore,
                restore_zero,
                limit,
                bind_group,
                glossy: glossy_pass,
            }
        })
    }

    /// The mirror faces.
    pub fn faces(&self) -> &[SpecularFace] {
        &self.faces
    }

    /// The settings the pass was built with.
    pub fn settings(&self) -> &SpecularSettings {
        &self.settings
    }

    /// The views of a frame seen from `root` ([`ViewTree::build`]) with `clip` the device's method unless the settings name one.
    pub fn view_tree(&self, root: View, device_clip: ClipMethod) -> Result<ViewTree> {
        self.view_tree_interleaved(root, device_clip, None)
    }

    /// [`SpecularPass::view_tree`] for frame `s` of `n` accumulated ones ([`ViewTree::build_interleaved`]).
    pub fn view_tree_interleaved(
        &self,
        root: View,
        device_clip: ClipMethod,
        frame: Option<(u32, u32)>,
    ) -> Result<ViewTree> {
        ViewTree::build_interleaved(
            root,
            &self.faces,
            self.settings.max_depth,
            self.settings.clip.unwrap_or(device_clip),
            frame,
        )
    }

    fn depth_stencil_pass<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        colour: &[Option<wgpu::RenderPassColorAttachment<'_>>],
        label: &str,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: colour,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// `mask_face` of `face` in the view `outer` (stencil `k` → `k + 1` where
    /// the face is visible), then the depth inside the new mask reset to far.
    pub fn encode_mask(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        face: usize,
    ) {
        let face = &self.faces[face];
        let mut pass = Self::depth_stencil_pass(encoder, targets, &[], "specular-mask");
        pass.set_pipeline(&self.mask);
        views.bind(&mut pass, 0, outer);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(face_indices(scene, face), 0, 0..1);
        pass.set_pipeline(&self.reset);
        pass.set_stencil_reference(outer.stencil_reference + 1);
        pass.draw(0..3, 0..1);
    }

    /// Restores `face` in the view `outer` after its image was drawn: depth
    /// and surface id written back, stencil `k + 1` → `k`, the image scaled by R.
    pub fn encode_restore(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        face: usize,
    ) {
        self.encode_restore_as(encoder, scene, targets, views, outer, face, false);
    }

    /// Restores `face` in the view `outer` after the image of the view in
    /// `child` was drawn in its mask: a mirror or slab as
    /// [`SpecularPass::encode_restore`]; a glossy face's sample (section 3,
    /// `accbuf(ACCUMULATE)`) fogged and accumulated, the face restored with
    /// its image cleared and, after the last sample, the average times R
    /// added on the face (`accbuf(RETURN)`).
    #[allow(clippy::too_many_arguments)]
    pub fn encode_restore_child(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        child: ViewSlot,
        face: usize,
        sample: Option<GlossySample>,
        fog_radiance: bool,
    ) {
        let (Some(sample), Some(glossy)) = (sample, &self.glossy) else {
            self.encode_restore(encoder, scene, targets, views, outer, face);
            return;
        };
        glossy.encode_accumulate(
            ctx,
            encoder,
            scene,
            targets,
            views,
            outer,
            child,
            sample,
            fog_radiance,
        );
        self.encode_restore_as(encoder, scene, targets, views, outer, face, true);
        if sample.index + 1 == sample.count {
            let indices = face_indices(scene, &self.faces[face]);
            glossy.encode_resolve(ctx, encoder, scene, targets, views, outer, face, indices);
        }
    }

    /// The restore of `face`, its image scaled by R or, with `clear`, by zero.
    #[allow(clippy::too_many_arguments)]
    fn encode_restore_as(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        outer: ViewSlot,
        face: usize,
        clear: bool,
    ) {
        let face = &self.faces[face];
        let colour = [
            Some(wgpu::RenderPassColorAttachment {
                view: &targets.hdr.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            }),
            Some(wgpu::RenderPassColorAttachment {
                view: &targets.surface_id.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            }),
        ];
        let mut pass = Self::depth_stencil_pass(encoder, targets, &colour, "specular-restore");
        pass.set_pipeline(if clear {
            &self.restore_zero
        } else {
            &self.restore
        });
        views.bind(&mut pass, 0, outer);
        pass.set_stencil_reference(outer.stencil_reference + 1);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(face_indices(scene, face), 0, 0..1);
    }

    /// Adds `R · L_lim` on the faces a view at the recursion limit sees.
    pub fn encode_limit(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
        faces: &[usize],
    ) {
        if faces.is_empty() || self.settings.limit_radiance == Vec3::ZERO {
            return;
        }
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "specular-limit");
        pass.set_pipeline(&self.limit);
        views.bind(&mut pass, 0, slot);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
        for &f in faces {
            pass.draw_indexed(face_indices(scene, &self.faces[f]), 0, 0..1);
        }
    }
}
