//! The view every pass draws under (Diefenbach & Badler 1997, sections 3 and
//! 7.1): a camera (view and projection, eye), the stencil reference that
//! masks where the view may draw, an optional clip plane that removes the
//! geometry in front of a specular face, and the recursion level. The views
//! of one frame live in one uniform buffer read at dynamic offsets
//! ([`ViewBuffer`]), so a single submission can hold the primary camera and
//! every virtual camera of the specular recursion.

use glam::{Mat4, Vec2, Vec3, Vec4};
use lustre_geometry::Camera;
use lustre_geometry::Plane;

use crate::{GpuContext, MprError, Result};

/// How geometry on the far side of a clip plane is removed (section 3: "clip away geometry").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ClipMethod {
    /// User clip distances in the vertex stage (`CLIP_DISTANCES`), where the adapter has them.
    #[default]
    Hardware,
    /// The projection's near plane replaced by the clip plane (Lengyel's oblique
    /// frustum, derived for reverse Z with an infinite far plane in
    /// [`oblique_near_plane`]); works on every adapter.
    ObliqueNearPlane,
}

/// One camera of a frame and how its passes are masked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// World to view (may be a mirror transform, determinant -1).
    pub view: Mat4,
    /// View to clip, reverse Z ([`Camera::projection_matrix`]), possibly oblique.
    pub projection: Mat4,
    /// The eye the passes shade for (the virtual eye of a specular image).
    pub eye: Vec3,
    /// World-space plane `(n, w)`: a point `p` is kept where `n·p + w >= 0`.
    /// Evaluated by the vertex stage when the clip method is
    /// [`ClipMethod::Hardware`]; already folded into `projection` otherwise.
    pub clip_plane: Option<Vec4>,
    /// Stencil value of the pixels this view may draw (its recursion level,
    /// or `SHAD_ZERO` while lights are added under shadow volumes).
    pub stencil_reference: u32,
    /// Depth of specular recursion: 0 for the camera itself (section 7.1).
    pub level: u32,
    /// Whether the emission pass shows emitters in this view: false in the
    /// sheared views of a glossy image, whose emitters' highlight the direct
    /// pass adds ([`crate::passes::glossy_image`]).
    pub shows_emitters: bool,
}

impl View {
    /// The view of a real camera: level 0, stencil 0, no clip plane.
    pub fn from_camera(camera: &Camera) -> Self {
        Self {
            view: camera.view_matrix(),
            projection: camera.projection_matrix(),
            eye: camera.position,
            clip_plane: None,
            stencil_reference: 0,
            level: 0,
            shows_emitters: true,
        }
    }

    /// The view of a pinhole camera (`lustre_ibr::PinholeView`: axes,
    /// focal lengths and principal point in pixels), level 0, stencil 0, no
    /// clip plane: pixel `(x, y)` of a `width × height` target is the
    /// pinhole's pixel `(x, y)`, with reverse-Z depth `near / z` and the far
    /// plane at infinity. Axes that form a left-handed frame (a pinhole
    /// reflected about a plane) give a mirrored view. Radiance maps' sample
    /// cameras draw through it (Bastos et al. 1999, section 8.1.3).
    pub fn from_pinhole(pinhole: &lustre_ibr::PinholeView, near: f32) -> Self {
        let (r, u, f) = (pinhole.right, pinhole.up, pinhole.forward);
        // World to view: x along `right`, y along `up`, looking down −z.
        let view = Mat4::from_cols(
            Vec4::new(r.x, u.x, -f.x, 0.0),
            Vec4::new(r.y, u.y, -f.y, 0.0),
            Vec4::new(r.z, u.z, -f.z, 0.0),
            Vec4::new(
                -r.dot(pinhole.eye),
                -u.dot(pinhole.eye),
                f.dot(pinhole.eye),
                1.0,
            ),
        );
        let (w, h) = (pinhole.width as f32, pinhole.height as f32);
        // x_ndc = (2 fx / w) xc/zc + (2 cx / w − 1), y_ndc = (2 fy / h) yc/zc + (1 − 2 cy / h), zc = −z_view.
        let (sx, sy) = (2.0 * pinhole.focal.x / w, 2.0 * pinhole.focal.y / h);
        let (ox, oy) = (
            2.0 * pinhole.principal.x / w - 1.0,
            1.0 - 2.0 * pinhole.principal.y / h,
        );
        let projection = Mat4::from_cols(
            Vec4::new(sx, 0.0, 0.0, 0.0),
            Vec4::new(0.0, sy, 0.0, 0.0),
            Vec4::new(-ox, -oy, 0.0, -1.0),
            Vec4::new(0.0, 0.0, near, 0.0),
        );
        Self {
            view,
            projection,
            eye: pinhole.eye,
            clip_plane: None,
            stencil_reference: 0,
            level: 0,
            shows_emitters: true,
        }
    }

    /// World to clip.
    pub fn view_projection(&self) -> Mat4 {
        self.projection * self.view
    }

    /// Whether the view matrix mirrors (determinant < 0): triangles wind the other way.
    pub fn is_mirrored(&self) -> bool {
        self.view.determinant() < 0.0
    }

    /// The virtual view behind the planar mirror `plane` (section 3, the
    /// beam-tracing reflection of Heckbert & Hanrahan): the view matrix
    /// composed with the mirror transform, the eye reflected, one level
    /// deeper with stencil reference `level + 1`, and everything on the eye's
    /// side of the mirror clipped away by `method`.
    pub fn reflected(&self, plane: &Plane, method: ClipMethod) -> Self {
        // World points are drawn through `view * R`, so the image shows `R p`.
        // What the mirror reflects lies on the eye's side of it; anything on the
        // far side would land between the virtual eye and the face once mirrored.
        let distance = plane.signed_distance(self.eye);
        let side = if distance >= 0.0 { 1.0 } else { -1.0 };
        // The face itself lies on the plane and would hide its own image: the
        // kept half space starts a hair in front of it (1e-4 of the eye's distance).
        let keep = plane.to_vec4() * side - Vec4::W * (1e-4 * distance.abs());
        Self {
            view: self.view * plane.reflection_matrix(),
            projection: self.projection,
            eye: plane.reflect_point(self.eye),
            clip_plane: None,
            stencil_reference: self.stencil_reference + 1,
            level: self.level + 1,
            shows_emitters: true,
        }
        .with_clip_plane(keep, method)
    }

    /// The virtual view through a glass slab whose near face is `plane` (its
    /// normal towards the eye), `thickness` deep, in paraxial in-out
    /// refraction (section 2; Heckbert & Hanrahan's paraxial refraction at
    /// both faces): the world drawn moved by `shift` along the normal, the
    /// eye moved back by as much, one level deeper, and everything nearer
    /// than the far face clipped.
    pub fn through_slab(
        &self,
        plane: &Plane,
        shift: f32,
        thickness: f32,
        method: ClipMethod,
    ) -> Self {
        let translation = Mat4::from_translation(plane.normal * shift);
        // Keep n·p - d <= -t - ε: beyond the far face, seen from the eye's side.
        let epsilon = 1e-4 * plane.signed_distance(self.eye).abs();
        let keep = -plane.to_vec4() - Vec4::W * (thickness + epsilon);
        Self {
            view: self.view * translation,
            projection: self.projection,
            eye: self.eye - plane.normal * shift,
            clip_plane: None,
            stencil_reference: self.stencil_reference + 1,
            level: self.level + 1,
            shows_emitters: true,
        }
        .with_clip_plane(keep, method)
    }

    /// The reflected view of `plane` ([`View::reflected`]) sheared about the
    /// face's normal (section 3, `shear_view`): the world transform
    /// `W = F · S(−Δ) · F⁻¹` (`S` the (x, y) shear in the face's frame `F`,
    /// `z` along the normal, [`face_frame`]) pushed after the mirror
    /// transform, `p ↦ p − z(p) Δ_w` with `z(p)` the signed distance from the
    /// plane and `Δ_w = Δ.x t + Δ.y b`. Points on the face stay put, so the
    /// image stays registered to the face, and every ray leaving the face
    /// with slope `r_t / r_z` (tangential over normal component) leaves with
    /// slope `r_t / r_z + Δ` instead; the sheared view is the mirror view
    /// from the eye `W⁻¹ e' = e' − d_e Δ_w` (`e'` the reflected eye, `d_e`
    /// the eye's distance from the face), whose rays through the face are
    /// straight lines, so every pass shades for that eye. Emitters are hidden
    /// ([`View::shows_emitters`]).
    pub fn sheared_reflection(&self, plane: &Plane, slope: Vec2, method: ClipMethod) -> Self {
        let distance = plane.signed_distance(self.eye);
        let side = if distance >= 0.0 { 1.0 } else { -1.0 };
        let keep = plane.to_vec4() * side - Vec4::W * (1e-4 * distance.abs());
        let shear = face_shear(plane, slope);
        Self {
            view: self.view * plane.reflection_matrix() * shear,
            projection: self.projection,
            eye: shear
                .inverse()
                .transform_point3(plane.reflect_point(self.eye)),
            clip_plane: None,
            stencil_reference: self.stencil_reference + 1,
            level: self.level + 1,
            shows_emitters: false,
        }
        .with_clip_plane(keep, method)
    }

    /// The view through a frosted glass slab (section 3, figure 3): the view
    /// of [`View::through_slab`] with the same shear about the near face as
    /// [`View::sheared_reflection`] pushed first (`V · T · W`), so every ray
    /// through the face leaves with its slope moved by `Δ`; the eye the
    /// passes shade for is `W⁻¹ T⁻¹ e`. Emitters stay visible.
    pub fn sheared_through_slab(
        &self,
        plane: &Plane,
        shift: f32,
        thickness: f32,
        slope: Vec2,
        method: ClipMethod,
    ) -> Self {
        let translation = Mat4::from_translation(plane.normal * shift);
        let epsilon = 1e-4 * plane.signed_distance(self.eye).abs();
        let keep = -plane.to_vec4() - Vec4::W * (thickness + epsilon);
        let shear = face_shear(plane, slope);
        Self {
            view: self.view * translation * shear,
            projection: self.projection,
            eye: shear
                .inverse()
                .transform_point3(self.eye - plane.normal * shift),
            clip_plane: None,
            stencil_reference: self.stencil_reference + 1,
            level: self.level + 1,
            shows_emitters: true,
        }
        .with_clip_plane(keep, method)
    }

    /// The virtual view through a single refracting interface `plane` (its
    /// normal towards the eye), in Heckbert & Hanrahan's paraxial refraction
    /// (section 3): the world beyond the plane drawn scaled along the normal
    /// by `ratio` (`n_eye / n_beyond`: a point at depth `d` is seen at
    /// `ratio · d`), the eye moved to the point the scaling maps onto it (at
    /// `1 / ratio` of its height, where refracted rays seem to come from),
    /// one level deeper, and everything on the eye's side clipped. The
    /// scaling fixes the plane, so the image lands on the face as it is: the
    /// quad-to-quad fit the paper applies to its refracted image from a
    /// moved viewpoint is the identity here.
    pub fn through_interface(&self, plane: &Plane, ratio: f32, method: ClipMethod) -> Self {
        let scale = interface_scaling(plane, ratio);
        let height = plane.signed_distance(self.eye);
        let epsilon = 1e-4 * height.abs();
        let keep = -plane.to_vec4() - Vec4::W * epsilon;
        Self {
            view: self.view * scale,
            projection: self.projection,
            eye: self.eye + plane.normal * height * (1.0 / ratio - 1.0),
            clip_plane: None,
            stencil_reference: self.stencil_reference + 1,
            level: self.level + 1,
            shows_emitters: self.shows_emitters,
        }
        .with_clip_plane(keep, method)
    }

    /// Clips away world points with `plane · (p, 1) < 0` by `method`.
    pub fn with_clip_plane(mut self, plane: Vec4, method: ClipMethod) -> Self {
        match method {
            ClipMethod::Hardware => self.clip_plane = Some(plane),
            ClipMethod::ObliqueNearPlane => {
                // The plane in view space: p_world = view⁻¹ p_view.
                let view_plane = self.view.inverse().transpose() * plane;
                self.projection = oblique_near_plane(self.projection, view_plane);
                self.clip_plane = None;
            }
        }
        self
    }

    /// The GPU block of this view ([`ViewUniforms`]).
    pub fn uniforms(&self) -> ViewUniforms {
        ViewUniforms {
            view_projection: self.view_projection().to_cols_array_2d(),
            eye: self.eye.extend(1.0).to_array(),
            // (0, 0, 0, 1) keeps every point.
            clip_plane: self.clip_plane.unwrap_or(Vec4::W).to_array(),
            level: [
                self.level,
                self.stencil_reference,
                u32::from(!self.shows_emitters),
                0,
            ],
        }
    }

    /// Whether the view may see any of the convex hull of `points`: false
    /// only when every point lies outside one side of the frustum (left,
    /// right, bottom, top, near, each a half space of world space since clip
    /// coordinates are linear in the world point) or on the removed side of
    /// the clip plane. Conservative: may answer true for a hull it misses.
    pub fn may_see(&self, points: &[Vec3]) -> bool {
        let vp = self.view_projection();
        let clip: Vec<Vec4> = points.iter().map(|p| vp * p.extend(1.0)).collect();
        let all = |outside: fn(Vec4) -> bool| clip.iter().all(|&c| outside(c));
        let culled = all(|c| c.x < -c.w)
            || all(|c| c.x > c.w)
            || all(|c| c.y < -c.w)
            || all(|c| c.y > c.w)
            || all(|c| c.z > c.w)
            || self
                .clip_plane
                .is_some_and(|plane| points.iter().all(|p| plane.dot(p.extend(1.0)) < 0.0));
        !points.is_empty() && !culled
    }

    /// Whether world point `p` survives this view's clipping (hardware plane and projection).
    pub fn keeps(&self, p: Vec3) -> bool {
        let clip = self.view_projection() * p.extend(1.0);
        let plane_ok = self.clip_plane.is_none_or(|c| c.dot(p.extend(1.0)) >= 0.0);
        plane_ok && clip.w > 0.0 && clip.z <= clip.w && clip.z >= 0.0
    }
}

/// The scaling by `ratio` along `plane`'s normal about the plane (Heckbert &
/// Hanrahan's paraxial refraction at one interface): `p ↦ p − (1 − ratio)
/// d(p) n`, `d` the signed distance. Its determinant is `ratio > 0`.
pub fn interface_scaling(plane: &Plane, ratio: f32) -> Mat4 {
    let n = plane.normal;
    let k = 1.0 - ratio;
    let linear = glam::Mat3::IDENTITY - k * glam::Mat3::from_cols(n * n.x, n * n.y, n * n.z);
    let translation = k * plane.offset * n;
    Mat4::from_cols(
        linear.x_axis.extend(0.0),
        linear.y_axis.extend(0.0),
        linear.z_axis.extend(0.0),
        translation.extend(1.0),
    )
}

/// An orthonormal tangent frame `(t, b)` of `plane` with `t × b = n` (the
/// face's `x` and `y` axes for [`View::sheared_reflection`]).
pub fn face_frame(plane: &Plane) -> (Vec3, Vec3) {
    let n = plane.normal.normalize();
    let t = n.any_orthonormal_vector();
    (t, n.cross(t))
}

/// The world transform `p ↦ p − z(p) Δ_w` of [`View::sheared_reflection`]:
/// `F · S(−Δ) · F⁻¹` written out as `I − Δ_w (n, −offset)ᵀ` (section 3:
/// "premultiplied by the global inverse transform of the specular face
/// normal and postmultiplied by the global transform of the normal").
pub fn face_shear(plane: &Plane, slope: Vec2) -> Mat4 {
    let (t, b) = face_frame(plane);
    let u = -(t * slope.x + b * slope.y).extend(0.0);
    let v = plane.to_vec4();
    Mat4::from_cols(
        Vec4::X + u * v.x,
        Vec4::Y + u * v.y,
        Vec4::Z + u * v.z,
        Vec4::W + u * v.w,
    )
}

/// Lengyel's oblique near plane for a reverse-Z projection with an infinite
/// far plane: the projection's depth row is replaced so that depth reaches 1
/// (the near plane) exactly on `view_plane` (view space, `(n, w)`, kept side
/// `n·v + w >= 0`), and depth stays in [0, 1] for every kept point in front
/// of the eye. With `w_clip = -z_v`, the new depth row is `w_row - a·plane`:
/// depth `1 - a (n·v + w) / (-z_v)`. Along a view ray `v = t d` this is
/// `1 - a (n·d)/(-d_z) - a w / (t (-d_z))`, so it decreases with `t` when
/// `w < 0` (the eye on the clipped side, as a virtual eye behind its face
/// always is), and stays `>= 0` at infinity when `a (n·d) <= -d_z` for every
/// direction of the frustum; `a` is the largest scale meeting that at the
/// frustum's four corner directions (the bound is linear in `d`, so the corners
/// suffice), times 0.999.
pub fn oblique_near_plane(projection: Mat4, view_plane: Vec4) -> Mat4 {
    let rows = projection.transpose();
    let w_row = rows.w_axis;
    // Frustum corner directions in view space from the inverse projection.
    let inverse = projection.inverse();
    let mut scale = f32::INFINITY;
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        // A point at depth 0.5 on the corner ray gives its direction.
        let p = inverse * Vec4::new(x, y, 0.5, 1.0);
        let d = (p.truncate() / p.w).normalize();
        let along = view_plane.truncate().dot(d);
        if along > 0.0 {
            scale = scale.min(-d.z / along);
        }
    }
    if !scale.is_finite() {
        // The plane's normal faces away from every frustum direction: any
        // positive scale keeps depth in range; pick one of the plane's size.
        scale = 1.0 / view_plane.truncate().length().max(f32::MIN_POSITIVE);
    }
    let new_z = w_row - 0.999 * scale * view_plane;
    Mat4::from_cols(rows.x_axis, rows.y_axis, new_z, w_row).transpose()
}

/// The GPU block of one view (`View` in `shaders/common/view.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewUniforms {
    /// Column-major world-to-clip matrix.
    pub view_projection: [[f32; 4]; 4],
    /// Eye position, w = 1.
    pub eye: [f32; 4],
    /// World clip plane; (0, 0, 0, 1) when none.
    pub clip_plane: [f32; 4],
    /// `x` recursion level, `y` stencil reference, `z` 1 where emitters are
    /// hidden ([`View::shows_emitters`]), `w` zero.
    pub level: [u32; 4],
}

/// The bind group layout of group 0 of every scene pass: one [`ViewUniforms`] at a dynamic offset.
pub fn view_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("view"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(size_of::<ViewUniforms>() as u64),
            },
            count: None,
        }],
    })
}

/// The pixels `[x, y, w, h]` of a `width × height` target (row 0 at the
/// top) that the NDC rectangle `[lo, hi]` covers, one pixel added all round
/// and clamped to the target; zero-sized when it misses the target.
pub fn ndc_to_pixels(lo: glam::DVec2, hi: glam::DVec2, width: u32, height: u32) -> [u32; 4] {
    let (w, h) = (width as f64, height as f64);
    let x0 = (((lo.x + 1.0) * 0.5 * w).floor() - 1.0).clamp(0.0, w);
    let x1 = (((hi.x + 1.0) * 0.5 * w).ceil() + 1.0).clamp(0.0, w);
    let y0 = (((1.0 - hi.y) * 0.5 * h).floor() - 1.0).clamp(0.0, h);
    let y1 = (((1.0 - lo.y) * 0.5 * h).ceil() + 1.0).clamp(0.0, h);
    [
        x0 as u32,
        y0 as u32,
        (x1 - x0).max(0.0) as u32,
        (y1 - y0).max(0.0) as u32,
    ]
}

/// The intersection of two pixel rectangles `[x, y, w, h]` (empty: zero size).
pub fn intersect_rects(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    let x0 = a[0].max(b[0]);
    let y0 = a[1].max(b[1]);
    let x1 = (a[0].saturating_add(a[2])).min(b[0].saturating_add(b[2]));
    let y1 = (a[1].saturating_add(a[3])).min(b[1].saturating_add(b[3]));
    [x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0)]
}

/// The world bounding box of each surface of `scene` in its current pose,
/// in `SurfaceId` order (`[+∞, −∞]` for a surface without triangles).
pub fn surface_boxes(scene: &lustre_geometry::Scene) -> Vec<[Vec3; 2]> {
    surface_boxes_of(&scene.world_triangles(), scene.surfaces().len())
}

/// [`surface_boxes`] of world triangles of a scene with `surfaces` surfaces.
pub fn surface_boxes_of(
    triangles: &[lustre_geometry::WorldTriangle],
    surfaces: usize,
) -> Vec<[Vec3; 2]> {
    let mut boxes = vec![[Vec3::INFINITY, Vec3::NEG_INFINITY]; surfaces];
    for t in triangles {
        if let Some(b) = boxes.get_mut(t.surface as usize) {
            for p in t.positions {
                b[0] = b[0].min(p);
                b[1] = b[1].max(p);
            }
        }
    }
    boxes
}

/// The ranges of `ranges` (one per surface, by `SurfaceId`) of the listed
/// `surfaces`, in their order, empty ones left out and adjacent ones merged:
/// the fewest draws of those surfaces' triangles or splats.
pub fn surface_draw_ranges(
    surfaces: &[u32],
    ranges: &[std::ops::Range<u32>],
) -> Vec<std::ops::Range<u32>> {
    let mut merged: Vec<std::ops::Range<u32>> = Vec::new();
    for range in surfaces
        .iter()
        .filter_map(|&s| ranges.get(s as usize))
        .filter(|r| !r.is_empty())
    {
        match merged.last_mut() {
            Some(last) if last.end == range.start => last.end = range.end,
            _ => merged.push(range.clone()),
        }
    }
    merged
}

/// The surfaces whose boxes may show in the pixels `region` (`[x, y, w,
/// h]`) of a `width × height` target seen with `view_projection` (reverse
/// Z): every box not wholly outside one side of the region's frustum or
/// wholly before the near plane (section 8's viewpoint culling, per view).
pub fn surfaces_in_region(
    boxes: &[[Vec3; 2]],
    view_projection: Mat4,
    region: [u32; 4],
    width: u32,
    height: u32,
) -> Vec<u32> {
    let [x, y, w, h] = region;
    let ndc = |px: u32, size: u32| 2.0 * px as f32 / size.max(1) as f32 - 1.0;
    let (x0, x1) = (ndc(x, width), ndc(x + w, width));
    // Pixel rows grow downwards, NDC y upwards.
    let (y1, y0) = (-ndc(y, height), -ndc(y + h, height));
    let [r0, r1, r2, r3] = [0, 1, 2, 3].map(|i| view_projection.row(i));
    // Half-spaces `plane · (p, 1) ≥ 0` of the region's frustum.
    let planes = [
        r0 - x0 * r3,
        x1 * r3 - r0,
        r1 - y0 * r3,
        y1 * r3 - r1,
        r3 - r2,
    ];
    boxes
        .iter()
        .enumerate()
        .filter(|(_, [lo, hi])| {
            lo.is_finite()
                && !planes.iter().any(|plane| {
                    (0..8).all(|i| {
                        let c = Vec3::new(
                            if i & 1 == 0 { lo.x } else { hi.x },
                            if i & 2 == 0 { lo.y } else { hi.y },
                            if i & 4 == 0 { lo.z } else { hi.z },
                        );
                        plane.dot(c.extend(1.0)) < 0.0
                    })
                })
        })
        .map(|(i, _)| i as u32)
        .collect()
}

/// Where one view's block lies in a [`ViewBuffer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewSlot {
    /// Byte offset of the block (a multiple of the device's uniform offset alignment).
    pub offset: u32,
    /// Its stencil reference.
    pub stencil_reference: u32,
    /// [`View::is_mirrored`]: front faces wind clockwise in this view (the
    /// shadow-volume count of Diefenbach & Badler 1997, section 4.1, needs it).
    pub mirrored: bool,
    /// [`View::view_projection`], for bounds on the CPU (the scissor of a
    /// virtual light's passes).
    pub view_projection: Mat4,
    /// `[x, y, width, height]` in pixels holding every pixel of the view's
    /// stencil area (its faces' projections through the views above it,
    /// [`crate::passes::specular::ViewTree::regions`]); `u32::MAX` sizes
    /// for the whole target ([`ViewSlot::scissor_in`]).
    pub scissor: [u32; 4],
    /// The jittered lights the view's direct light draws, and their weight
    /// ([`crate::light_group`]: one group inside a glossy image).
    pub lights: crate::light_group::LightGroup,
}

impl ViewSlot {
    /// [`ViewSlot::scissor`] clamped to a `width × height` target.
    pub fn scissor_in(&self, width: u32, height: u32) -> [u32; 4] {
        let [x, y, w, h] = self.scissor;
        let (x, y) = (x.min(width), y.min(height));
        [x, y, w.min(width - x), h.min(height - y)]
    }
}

/// The views of a frame in one uniform buffer with one bind group read at dynamic offsets.
#[derive(Debug)]
pub struct ViewBuffer {
    buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    stride: u64,
    capacity: usize,
}

impl ViewBuffer {
    /// A buffer with room for `capacity` views (grown by [`ViewBuffer::write`] when needed).
    pub fn new(ctx: &GpuContext, capacity: usize) -> Self {
        let alignment = u64::from(ctx.device.limits().min_uniform_buffer_offset_alignment);
        let stride = (size_of::<ViewUniforms>() as u64).div_ceil(alignment) * alignment;
        let capacity = capacity.max(1);
        let (buffer, bind_group) = Self::allocate(ctx, stride, capacity);
        Self {
            buffer,
            bind_group,
            stride,
            capacity,
        }
    }

    fn allocate(ctx: &GpuContext, stride: u64, capacity: usize) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("views"),
            size: stride * capacity as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("views"),
            layout: ctx.view_layout(),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(size_of::<ViewUniforms>() as u64),
                }),
            }],
        });
        (buffer, bind_group)
    }

    /// A buffer holding the one view of `camera`, and its slot (for passes drawn outside a [`crate::FrameGraph`]).
    pub fn for_camera(ctx: &GpuContext, camera: &Camera) -> Result<(Self, ViewSlot)> {
        Self::for_view(ctx, View::from_camera(camera))
    }

    /// A buffer holding `view` alone, and its slot.
    pub fn for_view(ctx: &GpuContext, view: View) -> Result<(Self, ViewSlot)> {
        let mut views = Self::new(ctx, 1);
        let slots = views.write(ctx, &[view])?;
        Ok((views, slots[0]))
    }

    /// Writes `views` (applied at the next submit) and returns their slots, in order.
    pub fn write(&mut self, ctx: &GpuContext, views: &[View]) -> Result<Vec<ViewSlot>> {
        if views.len() > self.capacity {
            let capacity = views.len().next_power_of_two();
            let (buffer, bind_group) = Self::allocate(ctx, self.stride, capacity);
            self.buffer = buffer;
            self.bind_group = bind_group;
            self.capacity = capacity;
        }
        let mut bytes = vec![0u8; (self.stride as usize) * views.len()];
        let mut slots = Vec::with_capacity(views.len());
        for (i, view) in views.iter().enumerate() {
            let offset = i * self.stride as usize;
            let block = view.uniforms();
            bytes[offset..offset + size_of::<ViewUniforms>()]
                .copy_from_slice(bytemuck::bytes_of(&block));
            slots.push(ViewSlot {
                offset: u32::try_from(offset).map_err(|_| MprError::InvalidSetting {
                    what: "views",
                    message: format!("{} views exceed a 4 GiB uniform buffer", views.len()),
                })?,
                stencil_reference: view.stencil_reference,
                mirrored: view.is_mirrored(),
                view_projection: view.view_projection(),
                scissor: [0, 0, u32::MAX, u32::MAX],
                lights: crate::light_group::LightGroup::ALL,
            });
        }
        if !bytes.is_empty() {
            ctx.queue.write_buffer(&self.buffer, 0, &bytes);
        }
        Ok(slots)
    }

    /// Binds the view of `slot` at `group` and sets its stencil reference.
    pub fn bind(&self, pass: &mut wgpu::RenderPass<'_>, group: u32, slot: ViewSlot) {
        pass.set_bind_group(group, &self.bind_group, &[slot.offset]);
        pass.set_stencil_reference(slot.stencil_reference);
    }

    /// [`ViewBuffer::bind`] in a render pass over `targets`, with the
    /// scissor set to the view's region ([`ViewSlot::scissor_in`]: the
    /// rasteriser skips pixels the view's stencil area cannot hold). Returns
    /// false, binding nothing, when the region is empty.
    pub fn bind_in(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        group: u32,
        slot: ViewSlot,
        targets: &crate::RenderTargets,
    ) -> bool {
        let [x, y, w, h] = slot.scissor_in(targets.width, targets.height);
        if w == 0 || h == 0 {
            return false;
        }
        pass.set_scissor_rect(x, y, w, h);
        self.bind(pass, group, slot);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::look_at(
            Vec3::new(0.3, 0.2, 2.0),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::Y,
            50.0,
        )
    }

    /// The listed surfaces' ranges, empty and unknown ones dropped, touching ones
    /// merged: every index of a listed surface once, nothing else (checked
    /// against the indices taken one by one).
    #[test]
    fn surface_draw_ranges_cover_the_listed_surfaces_once() {
        let ranges = [0..3, 3..3, 3..7, 7..9, 12..15, 15..20];
        let surfaces = [0u32, 1, 2, 4, 5, 9];
        let merged = surface_draw_ranges(&surfaces, &ranges);
        assert_eq!(merged, vec![0..7, 12..20]);
        let drawn: Vec<u32> = merged.into_iter().flatten().collect();
        let expected: Vec<u32> = surfaces
            .iter()
            .filter_map(|&s| ranges.get(s as usize))
            .flat_map(|r| r.clone())
            .collect();
        assert_eq!(drawn, expected);
        assert!(surface_draw_ranges(&[1, 7], &ranges).is_empty());
    }

    /// A box is kept when any point of it projects into the region in front
    /// of the eye (brute force over points sampled in the box), and culled
    /// when none does and it lies wholly outside one side of the region.
    #[test]
    fn surfaces_in_region_keep_what_projects_into_it() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0);
        let m = cam.projection_matrix() * cam.view_matrix();
        let (width, height) = (200, 100);
        let boxes = vec![
            [Vec3::splat(-0.1), Vec3::splat(0.1)],
            [Vec3::new(-1.5, -0.1, -0.1), Vec3::new(-1.2, 0.1, 0.1)],
            [Vec3::new(1.2, -0.1, -0.1), Vec3::new(1.5, 0.1, 0.1)],
            [Vec3::new(-0.1, -0.1, 3.5), Vec3::new(0.1, 0.1, 4.0)],
            [Vec3::new(-0.1, 0.5, -0.1), Vec3::new(0.1, 0.7, 0.1)],
            [Vec3::INFINITY, Vec3::NEG_INFINITY],
        ];
        for region in [[0, 0, width, height], [100, 0, 100, 100], [0, 60, 200, 40]] {
            let kept = surfaces_in_region(&boxes, m, region, width, height);
            for (i, [lo, hi]) in boxes.iter().enumerate().take(5) {
                let inside = (0..1000).any(|k| {
                    let f = |a: u32| ((k * a) % 997) as f32 / 996.0;
                    let p = *lo + (*hi - *lo) * Vec3::new(f(13), f(71), f(389));
                    let c = m * p.extend(1.0);
                    if c.w <= 0.0 || c.z > c.w {
                        return false;
                    }
                    let px = (c.x / c.w + 1.0) * 0.5 * width as f32;
                    let py = (1.0 - c.y / c.w) * 0.5 * height as f32;
                    px >= region[0] as f32
                        && px <= (region[0] + region[2]) as f32
                        && py >= region[1] as f32
                        && py <= (region[1] + region[3]) as f32
                });
                if inside {
                    assert!(
                        kept.contains(&(i as u32)),
                        "box {i} in {region:?}: {kept:?}"
                    );
                }
            }
            assert!(!kept.contains(&3), "behind the eye: {kept:?}");
            assert!(!kept.contains(&5), "empty: {kept:?}");
        }
        // The right half holds the box at +x, not the one at -x.
        let right = surfaces_in_region(&boxes, m, [100, 0, 100, 100], width, height);
        assert!(right.contains(&2) && !right.contains(&1), "{right:?}");
        // The bottom strip does not hold the box above the centre.
        let bottom = surfaces_in_region(&boxes, m, [0, 60, 200, 40], width, height);
        assert!(!bottom.contains(&4), "{bottom:?}");
    }

    /// A pinhole's view projects every point to the pixel and reverse-Z
    /// depth the pinhole gives it: a camera's pinhole, its mirror image
    /// (left-handed: a mirrored view) and a radiance map's off-axis one.
    #[test]
    fn a_pinhole_view_projects_as_its_pinhole() {
        use lustre_ibr::{Reflector, SampleCamera};
        let camera = Camera::look_at(
            Vec3::new(0.2, 1.0, 3.0),
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::Y,
            40.0,
        )
        .with_aspect(1.5);
        let reflector = Reflector::from_points(
            0,
            Plane::from_point_normal(Vec3::ZERO, Vec3::Y),
            &[
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
            ],
        )
        .unwrap();
        let element = reflector.elements(2, 2).unwrap()[1];
        let sample = SampleCamera::new(0, element, 0.9, 2.0);
        let near = 0.01;
        let eye = lustre_ibr::PinholeView::from_camera(&camera, 90, 60);
        for (pinhole, mirrored) in [
            (eye, false),
            (eye.reflected(&reflector.plane), true),
            (sample.pinhole(64, 48), false),
        ] {
            let view = View::from_pinhole(&pinhole, near);
            assert_eq!(view.is_mirrored(), mirrored);
            let m = view.view_projection();
            let mut seen = 0;
            for i in 0..200u32 {
                let h = |s: u32| ((i.wrapping_mul(2_654_435_761) >> s) & 0xff) as f32 / 255.0;
                let p = Vec3::new(4.0 * h(0) - 2.0, 3.0 * h(8) - 0.5, 4.0 * h(16) - 2.0);
                let Some((pixel, z)) = pinhole.project(p) else {
                    continue;
                };
                let clip = m * p.extend(1.0);
                assert!(clip.w > 0.0);
                let ndc = clip.truncate() / clip.w;
                let (w, hgt) = (pinhole.width as f32, pinhole.height as f32);
                let got = Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * hgt);
                assert!(
                    (got - pixel).length() < 1e-3 * w,
                    "{p}: pixel {got} vs {pixel}"
                );
                assert!(
                    (ndc.z - near / z).abs() < 1e-5 * (near / z).max(1e-3),
                    "depth"
                );
                seen += 1;
            }
            assert!(seen > 50, "{seen} points in front");
        }
    }

    /// The paraxial interface scaling keeps the plane, scales depths by the
    /// ratio, and its virtual eye sees each scaled point along the line the
    /// real eye sees it (Heckbert & Hanrahan).
    #[test]
    fn interface_scaling_keeps_the_plane_and_scales_depth() {
        let plane = Plane::from_point_normal(Vec3::new(0.0, -0.5, 0.0), Vec3::Y);
        let m = interface_scaling(&plane, 0.75);
        let on = Vec3::new(0.3, -0.5, -0.2);
        assert!((m.transform_point3(on) - on).length() < 1e-6);
        let below = Vec3::new(0.3, -1.5, -0.2);
        assert!((m.transform_point3(below) - Vec3::new(0.3, -1.25, -0.2)).length() < 1e-6);
        let root = View::from_camera(&camera());
        let through = root.through_interface(&plane, 0.75, ClipMethod::Hardware);
        // Real eye 0.7 above the plane → virtual eye at 0.7 / 0.75.
        assert!(
            (through.eye.y - (-0.5 + 0.7 / 0.75)).abs() < 1e-5,
            "{}",
            through.eye
        );
        // The virtual eye's line to a point beyond and the real eye's line to
        // its scaled image cross the plane at one point.
        let cross = |from: Vec3, to: Vec3| from + (to - from) * ((from.y + 0.5) / (from.y - to.y));
        let x1 = cross(through.eye, below);
        let x2 = cross(root.eye, m.transform_point3(below));
        assert!((x1 - x2).length() < 1e-5, "{x1} {x2}");
        assert!(!through.is_mirrored());
        assert_eq!(through.level, 1);
    }

    /// Depth (z/w) and whether the point is inside the clip volume (0 ≤ z ≤ w, w > 0).
    fn depth(view: &View, p: Vec3) -> (f32, bool) {
        let c = view.view_projection() * p.extend(1.0);
        (c.z / c.w, c.w > 0.0 && c.z >= 0.0 && c.z <= c.w)
    }

    #[test]
    fn the_oblique_near_plane_is_the_clip_plane_and_keeps_depth_order() {
        // A mirror at x = -1 facing +x; the reflected view keeps x >= -1.
        let mirror = Plane::from_point_normal(Vec3::new(-1.0, 0.0, 0.0), Vec3::X);
        let root = View::from_camera(&camera().with_aspect(1.0));
        let view = root.reflected(&mirror, ClipMethod::ObliqueNearPlane);
        assert!(view.clip_plane.is_none() && view.is_mirrored());
        // On the plane (just in front of its 1e-4 offset) depth is 1, the near plane.
        let on = Vec3::new(-1.0 + 1e-3, 0.1, 0.2);
        let (d, inside) = depth(&view, on);
        assert!(inside && (d - 1.0).abs() < 1e-3, "{d}");
        // Behind the mirror (x < -1): clipped.
        assert!(!depth(&view, Vec3::new(-1.5, 0.0, 0.0)).1);
        // Kept points along one ray from the virtual eye: farther is smaller (reverse Z), all in [0, 1].
        let dir = (Vec3::new(-1.0, 0.05, 0.1) - view.eye).normalize();
        let mut last = f32::INFINITY;
        for t in [3.0f32, 3.5, 5.0, 10.0, 100.0] {
            let p = view.eye + dir * t;
            if mirror.signed_distance(p) <= 1e-3 {
                continue;
            }
            let (d, inside) = depth(&view, p);
            assert!(inside, "t = {t}: depth {d}");
            assert!(d < last, "t = {t}: {d} after {last}");
            last = d;
        }
        // The hardware variant keeps the same points by its plane.
        let hw = root.reflected(&mirror, ClipMethod::Hardware);
        assert!(hw.keeps(Vec3::new(0.0, 0.0, 0.0)));
        assert!(!hw.keeps(Vec3::new(-1.5, 0.0, 0.0)));
    }

    #[test]
    fn a_sheared_views_ray_through_the_face_centre_leaves_with_its_slope_shifted_by_the_shear() {
        // A floor at y = -1 facing +y, seen from above at an angle.
        let floor = Plane::from_point_normal(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        let camera = Camera::look_at(
            Vec3::new(0.3, 0.5, 2.0),
            Vec3::new(0.1, -1.0, 0.2),
            Vec3::Y,
            50.0,
        )
        .with_aspect(1.0);
        let root = View::from_camera(&camera);
        let centre = Vec3::new(0.1, -1.0, 0.2);
        // The mirror direction at the centre, and its slope in the face's frame.
        let r = floor.reflect_vector(centre - camera.position).normalize();
        let (t, b) = face_frame(&floor);
        let slope = |d: Vec3| Vec2::new(d.dot(t), d.dot(b)) / d.dot(floor.normal);
        for method in [ClipMethod::Hardware, ClipMethod::ObliqueNearPlane] {
            for shear in [Vec2::ZERO, Vec2::new(0.1, 0.0), Vec2::new(-0.04, 0.07)] {
                let view = root.sheared_reflection(&floor, shear, method);
                // The face centre stays where the camera sees it (the image is registered).
                let vp = view.view_projection();
                let c = vp * centre.extend(1.0);
                let seen = root.view_projection() * centre.extend(1.0);
                assert!(
                    (c.truncate() / c.w - seen.truncate() / seen.w)
                        .truncate()
                        .length()
                        < 1e-5
                );
                // Another world point on the same pixel, farther along the view's ray.
                let ndc = c.truncate() / c.w;
                let q = vp.inverse() * Vec4::new(ndc.x, ndc.y, 0.5 * ndc.z, 1.0);
                let q = q.truncate() / q.w;
                let d = q - centre;
                assert!(floor.signed_distance(q) > 0.0, "{method:?} {shear}: {q}");
                let expected = slope(r) + shear;
                assert!(
                    (slope(d) - expected).length() < 1e-4,
                    "{method:?} shear {shear}: slope {} expected {expected}",
                    slope(d)
                );
                // The eye the passes shade for lies on that ray, behind the face.
                let back = view.eye - centre;
                assert!((slope(back) - expected).length() < 1e-4, "{}", slope(back));
                assert!(floor.signed_distance(view.eye) < 0.0);
                assert!(!view.shows_emitters);
            }
        }
    }

    #[test]
    fn a_sheared_slab_views_ray_through_the_face_centre_keeps_the_slab_shift_and_moves_its_slope() {
        // A slab's near face at z = 0 facing +z, 5 cm thick, η = 1.5.
        let face = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let (thickness, shift) = (0.05, 0.05 * (1.0 - 1.0 / 1.5));
        let camera = Camera::look_at(
            Vec3::new(0.2, 0.1, 1.5),
            Vec3::new(0.05, -0.02, 0.0),
            Vec3::Y,
            40.0,
        )
        .with_aspect(1.0);
        let root = View::from_camera(&camera);
        let centre = Vec3::new(0.05, -0.02, 0.0);
        let (t, b) = face_frame(&face);
        let slope = |d: Vec3| Vec2::new(d.dot(t), d.dot(b)) / d.dot(face.normal);
        let incident = slope(centre - camera.position);
        // The oblique near plane changes only the depth row, not which world
        // points a pixel sees; the camera's projection gives known depths.
        for method in [ClipMethod::Hardware] {
            let clear = root.through_slab(&face, shift, thickness, method);
            for shear in [Vec2::new(0.08, 0.0), Vec2::new(-0.03, 0.05)] {
                let view = root.sheared_through_slab(&face, shift, thickness, shear, method);
                assert!(view.shows_emitters);
                // Two world points on the pixel through the face centre, behind the slab.
                let c = root.view_projection() * centre.extend(1.0);
                let ndc = c.truncate() / c.w;
                let world = |v: &View, depth: f32| {
                    let q = v.view_projection().inverse() * Vec4::new(ndc.x, ndc.y, depth, 1.0);
                    q.truncate() / q.w
                };
                let depth = 0.3 * ndc.z;
                let (p, q) = (world(&view, depth), world(&view, 0.5 * depth));
                assert!(p.z < -thickness && q.z < p.z, "{p} {q}");
                // The line's slope is the incident one moved by the shear
                // (the paraxial slab keeps directions, the shear moves them).
                let expected = incident + shear;
                assert!(
                    (slope(q - p) - expected).length() < 1e-3,
                    "{} vs {expected}",
                    slope(q - p)
                );
                // Without shear the same pixel's line keeps the incident slope.
                let (p0, q0) = (world(&clear, depth), world(&clear, 0.5 * depth));
                assert!((slope(q0 - p0) - incident).length() < 1e-3);
            }
        }
    }

    #[test]
    fn may_see_culls_by_frustum_side_and_clip_plane_only() {
        let root = View::from_camera(&camera().with_aspect(1.0));
        // A quad in front of the camera, one behind it, one far to the right.
        let quad = |c: Vec3| [c + Vec3::Y * 0.1, c - Vec3::Y * 0.1, c + Vec3::Z * 0.1];
        assert!(root.may_see(&quad(Vec3::new(-1.0, 0.0, 0.0))));
        assert!(!root.may_see(&quad(Vec3::new(0.3, 0.2, 4.0))));
        assert!(!root.may_see(&quad(Vec3::new(20.0, 0.0, 0.0))));
        // A triangle straddling the frustum's left side is kept.
        let wide = [
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(-30.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.1, 0.0),
        ];
        assert!(root.may_see(&wide));
        assert!(!root.may_see(&[]));
        // Through a mirror at x = -1, what lies behind the mirror is clipped.
        let mirror = Plane::from_point_normal(Vec3::new(-1.0, 0.0, 0.0), Vec3::X);
        let view = root.reflected(&mirror, ClipMethod::Hardware);
        assert!(!view.may_see(&quad(Vec3::new(-2.0, 0.0, 0.0))));
        assert!(view.may_see(&quad(Vec3::new(0.5, 0.0, 0.0))));
    }
}
