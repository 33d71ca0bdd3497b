//! Virtual lights: a light reflected or refracted by chains of specular
//! faces (Diefenbach & Badler 1997, sections 4.2, 4.3 and 7.1's
//! `make_spec_shadows`), on the CPU: which chains reach which face, the
//! transform and the factor of each chain, which geometry may cast a
//! shadow into each stretch of its path, the pass count of equation 7, and
//! the CPU twin that follows the unfolded path with ray casts.
//!
//! A chain `F₁ … F_k` of [`SpecularFace`]s takes a point light at `L₀ = L`
//! to the virtual lights `L_j = T_j(L_{j−1})`, where `T_j` is `F_j`'s
//! transform: the mirror reflection of its plane, the slab's paraxial
//! shift `t (1 − 1/η)` along its normal, or a single interface's paraxial
//! scaling about its plane (the same maps the specular images use,
//! [`View::reflected`](crate::View::reflected),
//! [`View::through_slab`](crate::View::through_slab) and
//! [`View::through_interface`](crate::View::through_interface)). Light from `L` that
//! passed `F₁ … F_k` reaches a point `P` on the outgoing side of `F_k` as
//! if from `L_k`, with the intensity times the faces' factors, when
//!
//! * for every `j`, the line from `L_j` to the point the path reached next
//!   crosses `F_j`'s polygon (the *light volume* of section 4.2, the
//!   stencilled intersection of one volume per face), and
//! * no geometry blocks any stretch of the path: stretch `j` runs from
//!   `F_j` (the light for `j = 0`) to `F_{j+1}` (the receiver for `j = k`);
//!   only geometry on the outgoing side of `F_j` and the incoming side of
//!   `F_{j+1}` can block it, and the shadow it casts is its volume from
//!   `L_j` moved by `T_k ∘ … ∘ T_{j+1}` (section 4.3: a shadow bent by
//!   specular faces is a transformed copy, figure 6's `S₀₁₂` from `S₀₁`).
//!
//! Exact for mirrors; for slabs and interfaces the paraxial approximation of the images.
//! A chain continues from `F_j` to a face that its light can reach:
//! `L_j` on the incoming side of the next face, and the next face's corners,
//! projected from `L_j` onto `F_j`'s plane, overlapping `F_j`'s extent there
//! (the viewpoint culling of section 8, done per light).

use glam::{Affine3A, Vec3};
use lustre_geometry::{Bvh, Light, Ray};

use crate::passes::specular::{SpecularFace, SpecularKind};
use crate::projective_texture::Window;
use crate::view::face_frame;

/// How much of the shadowing of virtual lights is drawn (Diefenbach &
/// Badler 1997, section 8.1, table 2: "Spec Shad", "2+ Bounces").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpecularShadows {
    /// Every stretch of every path casts its shadows (table 2 (a)).
    #[default]
    All,
    /// Shadows that pass more than one specular face before the receiver
    /// are left out (table 2 (b)).
    OneBounce,
    /// Virtual lights are bounded by their light volumes only (table 2 (c)).
    Off,
}

/// The settings of virtual lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VirtualLightSettings {
    /// Shadow recursion depth (section 8.1): the longest chain of faces a
    /// light is followed through; 0 draws no virtual light.
    pub depth: u32,
    /// Which of their shadows are drawn.
    pub shadows: SpecularShadows,
    /// How light through stained-glass panes is drawn (section 4.5).
    pub panes: crate::projective_texture::PaneLight,
}

impl Default for VirtualLightSettings {
    fn default() -> Self {
        Self {
            depth: 1,
            shadows: SpecularShadows::All,
            panes: crate::projective_texture::PaneLight::default(),
        }
    }
}

/// The most faces a chain may pass (the stencil counts one light volume per
/// face above `SHAD_ZERO`, which leaves 63 values).
pub const MAX_SHADOW_DEPTH: u32 = 8;

/// The map a face applies to what is seen, and lit, through it: the mirror
/// reflection of its plane, or the slab's shift toward its outgoing side.
pub fn face_transform(face: &SpecularFace) -> Affine3A {
    match plain_kind(face) {
        SpecularKind::Mirror | SpecularKind::Glossy(_) => {
            Affine3A::from_mat4(face.plane.reflection_matrix())
        }
        SpecularKind::Slab { shift, .. } => Affine3A::from_translation(face.plane.normal * shift),
        SpecularKind::Interface { ratio } => {
            Affine3A::from_mat4(crate::view::interface_scaling(&face.plane, ratio))
        }
        // A thin pane passes light straight on (section 4.5).
        SpecularKind::Pane { .. } => Affine3A::IDENTITY,
    }
}

/// What a face does to light as a sharp face: a glossy face's mean
/// reflection is its mirror's, a frosted slab's its clear slab's.
fn plain_kind(face: &SpecularFace) -> SpecularKind {
    match face.kind {
        SpecularKind::Glossy(g) => match g.through_slab {
            None => SpecularKind::Mirror,
            Some((shift, thickness)) => SpecularKind::Slab { shift, thickness },
        },
        kind => kind,
    }
}

/// A half-space `normal · p ≥ offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfSpace {
    /// Unit normal pointing inside.
    pub normal: Vec3,
    /// Offset along the normal.
    pub offset: f32,
}

impl HalfSpace {
    /// How far inside `p` lies (negative outside).
    pub fn depth(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }

    /// Whether a triangle lies inside up to `epsilon` and not wholly on the
    /// boundary: the geometry that may block a stretch of a path. Triangles
    /// that cross the boundary are left out.
    pub fn holds_triangle(&self, t: &[Vec3; 3], epsilon: f32) -> bool {
        let d = t.map(|p| self.depth(p));
        d.iter().all(|&d| d >= -epsilon) && d.iter().any(|&d| d > epsilon)
    }
}

/// Where light leaves `face`: in front of a mirror, on the normal's side of a slab face.
pub fn outgoing(face: &SpecularFace) -> HalfSpace {
    HalfSpace {
        normal: face.plane.normal,
        offset: face.plane.offset,
    }
}

/// Where light must come from to pass `face`: in front of a mirror, beyond
/// the far face of a slab.
pub fn incoming(face: &SpecularFace) -> HalfSpace {
    match plain_kind(face) {
        SpecularKind::Mirror | SpecularKind::Glossy(_) => outgoing(face),
        SpecularKind::Slab { thickness, .. } => HalfSpace {
            normal: -face.plane.normal,
            offset: -face.plane.offset + thickness,
        },
        SpecularKind::Interface { .. } | SpecularKind::Pane { .. } => HalfSpace {
            normal: -face.plane.normal,
            offset: -face.plane.offset,
        },
    }
}

/// The side planes of the cone of rays from `apex` through `face`'s
/// polygon (the convex hull of its corners), as half-spaces holding the
/// cone; empty when `apex` lies in the face's plane. Geometry wholly outside
/// one of them cannot block light that passes the face (section 8's
/// culling, applied to the casters of virtual lights' shadows).
pub fn cone_planes(apex: Vec3, face: &SpecularFace) -> Vec<HalfSpace> {
    if face.plane.signed_distance(apex).abs() <= 1e-6 || face.corners.is_empty() {
        return Vec::new();
    }
    let (u, v) = face_frame(&face.plane);
    let mut points: Vec<(f32, f32, Vec3)> = face
        .corners
        .iter()
        .map(|&c| (c.dot(u), c.dot(v), c))
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    points.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-7 && (a.1 - b.1).abs() < 1e-7);
    // Andrew's monotone chain: the hull counter-clockwise in (u, v).
    let cross = |o: &(f32, f32, Vec3), a: &(f32, f32, Vec3), b: &(f32, f32, Vec3)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f32, f32, Vec3)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f32, f32, Vec3)>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for p in iter {
            while hull.len() >= start + 2
                && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(*p);
        }
        hull.pop();
    }
    if hull.len() < 3 {
        return Vec::new();
    }
    let centre = hull.iter().map(|p| p.2).sum::<Vec3>() / hull.len() as f32;
    (0..hull.len())
        .filter_map(|i| {
            let (a, b) = (hull[i].2, hull[(i + 1) % hull.len()].2);
            let normal = (a - apex).cross(b - apex).normalize_or_zero();
            if normal == Vec3::ZERO {
                return None;
            }
            let normal = if normal.dot(centre - apex) >= 0.0 {
                normal
            } else {
                -normal
            };
            Some(HalfSpace {
                normal,
                offset: normal.dot(apex),
            })
        })
        .collect()
}

/// One chain of faces a light passes, with what it does to the light.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecularPath {
    /// Indices of the faces, in the order the light meets them.
    pub faces: Vec<usize>,
    /// `A_j = T_j ∘ … ∘ T₁` for `j = 0..=k` (`A₀` the identity): the virtual
    /// light after `j` faces is `A_j(L)`.
    pub prefix: Vec<Affine3A>,
    /// Product of the faces' factors (reflectance, transmittance).
    pub factor: Vec3,
}

impl SpecularPath {
    /// Number of faces `k`.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether the chain has no face.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// `A_k`: the whole chain's transform.
    pub fn transform(&self) -> Affine3A {
        *self.prefix.last().unwrap_or(&Affine3A::IDENTITY)
    }

    /// `T_k ∘ … ∘ T_{j+1}`: what moves stretch `j`'s shadows and face
    /// `j`'s light volume (`j ≤ k`) to where the path ends.
    pub fn suffix(&self, j: usize) -> Affine3A {
        self.transform() * self.prefix[j].inverse()
    }

    /// The half-spaces whose geometry may block stretch `j` (`0..=k`): the
    /// outgoing side of `F_j` (`j ≥ 1`) and the incoming side of `F_{j+1}` (`j < k`).
    pub fn stretch_bounds(&self, faces: &[SpecularFace], j: usize) -> Vec<HalfSpace> {
        let mut bounds = Vec::new();
        if j >= 1 {
            bounds.push(outgoing(&faces[self.faces[j - 1]]));
        }
        if j < self.len() {
            bounds.push(incoming(&faces[self.faces[j]]));
        }
        bounds
    }

    /// The cone of stretch `j`'s light for a light at `light`: from `A_j(L)`
    /// through the face it goes to next (`F_{j+1}`), or, for the last
    /// stretch, through `F_k` from `A_k(L)` ([`cone_planes`]).
    pub fn stretch_cone(&self, faces: &[SpecularFace], light: Vec3, j: usize) -> Vec<HalfSpace> {
        let apex = self.prefix[j].transform_point3(light);
        let face = if j < self.len() {
            self.faces[j]
        } else {
            self.faces[j - 1]
        };
        cone_planes(apex, &faces[face])
    }

    /// The stretches whose shadows are drawn under `shadows`: all `0..=k`,
    /// the last two ([`SpecularShadows::OneBounce`]) or none.
    pub fn shadowed_stretches(&self, shadows: SpecularShadows) -> std::ops::Range<usize> {
        let k = self.len();
        match shadows {
            SpecularShadows::All => 0..k + 1,
            SpecularShadows::OneBounce => k.saturating_sub(1)..k + 1,
            SpecularShadows::Off => 0..0,
        }
    }
}

/// Whether light from `source` through `from` may reach `to`: some corner
/// of `to` lies beyond `from`, and the corners' central projection from
/// `source` onto `from`'s plane overlaps `from`'s extent there (conservative:
/// a corner not beyond the plane keeps the face).
fn reaches(source: Vec3, from: &SpecularFace, to: &SpecularFace) -> bool {
    let out = outgoing(from);
    let ds = out.depth(source);
    let depths: Vec<f32> = to.corners.iter().map(|&c| out.depth(c)).collect();
    if depths.iter().all(|&d| d <= 0.0) {
        return false;
    }
    if depths.iter().any(|&d| d <= 0.0) || ds >= 0.0 {
        return true;
    }
    let (u, v) = face_frame(&from.plane);
    let extent = |points: &mut dyn Iterator<Item = Vec3>| {
        points.fold(
            (
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::NEG_INFINITY,
            ),
            |b, p| {
                let (x, y) = (p.dot(u), p.dot(v));
                (b.0.min(x), b.1.max(x), b.2.min(y), b.3.max(y))
            },
        )
    };
    let face = extent(&mut from.corners.iter().copied());
    let projected = extent(&mut to.corners.iter().zip(&depths).map(|(&c, &d)| {
        let t = ds / (ds - d);
        source + (c - source) * t
    }));
    projected.0 <= face.1 && face.0 <= projected.1 && projected.2 <= face.3 && face.2 <= projected.3
}

/// Every chain of at most `depth` faces that light from a point light at
/// `light` can pass (section 7.1, `make_spec_shadows` recursing per face),
/// depth first, each with its transforms and factor.
pub fn specular_paths(faces: &[SpecularFace], light: Vec3, depth: u32) -> Vec<SpecularPath> {
    let mut out = Vec::new();
    let root = SpecularPath {
        faces: Vec::new(),
        prefix: vec![Affine3A::IDENTITY],
        factor: Vec3::ONE,
    };
    grow(faces, light, depth, &root, &mut out);
    out
}

fn grow(
    faces: &[SpecularFace],
    light: Vec3,
    depth: u32,
    path: &SpecularPath,
    out: &mut Vec<SpecularPath>,
) {
    if path.len() >= depth as usize {
        return;
    }
    let source = path.transform().transform_point3(light);
    for (f, face) in faces.iter().enumerate() {
        // Glossy and frosted faces spread the light they pass: no virtual
        // light (their photons stay in the splats).
        if matches!(face.kind, SpecularKind::Glossy(_)) || incoming(face).depth(source) <= 0.0 {
            continue;
        }
        if let Some(&last) = path.faces.last()
            && (last == f || !reaches(source, &faces[last], face))
        {
            continue;
        }
        // One projective texture per virtual light: a chain passes at most
        // one window (light through two is left to the splats).
        if matches!(face.kind, SpecularKind::Pane { .. })
            && path
                .faces
                .iter()
                .any(|&g| matches!(faces[g].kind, SpecularKind::Pane { .. }))
        {
            continue;
        }
        let mut next = path.clone();
        next.faces.push(f);
        next.prefix.push(face_transform(face) * path.transform());
        next.factor *= face.factor;
        out.push(next.clone());
        grow(faces, light, depth, &next, out);
    }
}

/// The faces virtual lights pass in a scene: its specular faces
/// ([`specular_faces`](crate::passes::specular::specular_faces)) and, as
/// [`PaneLight`](crate::projective_texture::PaneLight) says, its windows of
/// stained glass with their faces ([`window_faces`], section 4.5). The
/// frame's virtual lights and the photon filter
/// ([`drawn_by_virtual_lights`]) must take the same.
#[derive(Debug, Clone, PartialEq)]
pub struct PassedFaces {
    /// Specular faces, then two per window.
    pub faces: Vec<SpecularFace>,
    /// The windows the faces' [`SpecularKind::Pane`]s index.
    pub windows: Vec<Window>,
}

impl PassedFaces {
    /// The faces of `scene` with its windows drawn as `panes` says.
    pub fn new(
        scene: &lustre_geometry::Scene,
        panes: crate::projective_texture::PaneLight,
    ) -> crate::Result<Self> {
        let mut faces = crate::passes::specular::specular_faces(scene);
        // A curved interface imaged at its mean plane (the pool's wavy
        // water) passes no virtual light, nor do the triangles of its mesh
        // that happen to form planar surfaces: a light through the mean
        // plane, or through a single wave facet, would lose or distort the
        // waves' caustic, which their photons' splats keep.
        let surfaces = scene.surfaces();
        let curved: std::collections::HashSet<u32> = surfaces
            .iter()
            .filter(|s| s.kind == lustre_geometry::SurfaceKind::Curved)
            .map(|s| s.mesh)
            .collect();
        faces.retain(|f| {
            surfaces
                .get(f.surface as usize)
                .is_some_and(|s| !curved.contains(&s.mesh))
        });
        let windows = crate::projective_texture::windows(scene, panes)?;
        faces.extend(window_faces(&windows));
        Ok(Self { faces, windows })
    }
}

/// The faces a window gives the virtual lights (section 4.5): one
/// [`SpecularKind::Pane`] per side, its normal on the side light leaves
/// to, passing the texture's light (factor 1: the projective texture and
/// the slab's Fresnel transmittance are applied per fragment).
pub fn window_faces(windows: &[Window]) -> Vec<SpecularFace> {
    windows
        .iter()
        .enumerate()
        .flat_map(|(i, w)| {
            let corners = w.corners();
            let face = |plane: lustre_geometry::Plane| SpecularFace {
                surface: w.surfaces[0],
                plane,
                kind: SpecularKind::Pane { window: i as u32 },
                factor: Vec3::ONE,
                corners: corners.clone(),
            };
            [face(w.plane), face(w.plane.flipped())]
        })
        .collect()
}

/// The pixels of a `width × height` target, seen with `view_projection`
/// (reverse Z), where a virtual light at `apex` shining through `face` may
/// fall inside the box `bounds`: the bounding rectangle `[x, y, w, h]` of
/// the polytope that the cone from `apex` through the face ([`cone_planes`]),
/// the face's outgoing side, the box and the view's near side bound, or
/// `None` when it is empty. Vertices by brute force over triples of planes
/// (at most 15 planes); a pixel is added all round. Conservative: the
/// scissor of the virtual light's stencil and lit passes, which only skips
/// pixels its light cannot reach.
pub fn light_scissor(
    view_projection: glam::Mat4,
    apex: Vec3,
    face: &SpecularFace,
    bounds: [Vec3; 2],
    width: u32,
    height: u32,
) -> Option<[u32; 4]> {
    use glam::{DMat3, DVec3, DVec4};
    let full = Some([0, 0, width, height]);
    let cone = cone_planes(apex, face);
    if cone.is_empty() || !bounds[0].is_finite() || !bounds[1].is_finite() {
        return full;
    }
    // Half-spaces n · p ≥ d.
    let mut planes: Vec<(DVec3, f64)> = cone
        .iter()
        .chain(std::iter::once(&outgoing(face)))
        .map(|h| (h.normal.as_dvec3(), h.offset as f64))
        .collect();
    let (lo, hi) = (bounds[0].as_dvec3(), bounds[1].as_dvec3());
    for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
        planes.push((axis, axis.dot(lo)));
        planes.push((-axis, -axis.dot(hi)));
    }
    let m = view_projection.as_dmat4();
    let (row2, row3) = (m.row(2), m.row(3));
    // Reverse Z: 0 ≤ z ≤ w in front of the near plane.
    for row in [row2, row3 - row2] {
        planes.push((row.truncate(), -row.w));
    }
    let scale = (hi - lo).length().max(1e-9);
    let tolerance = 1e-7 * scale;
    let (mut min, mut max) = (
        glam::DVec2::splat(f64::INFINITY),
        glam::DVec2::splat(f64::NEG_INFINITY),
    );
    let mut any = false;
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let a = DMat3::from_cols(planes[i].0, planes[j].0, planes[k].0).transpose();
                let det = a.determinant();
                if det.abs() < 1e-12 {
                    continue;
                }
                let p = a.inverse() * DVec3::new(planes[i].1, planes[j].1, planes[k].1);
                if planes.iter().any(|&(n, d)| n.dot(p) < d - tolerance) {
                    continue;
                }
                let c = m * DVec4::new(p.x, p.y, p.z, 1.0);
                if c.w <= 0.0 {
                    return full;
                }
                let ndc = glam::DVec2::new(c.x / c.w, c.y / c.w);
                min = min.min(ndc);
                max = max.max(ndc);
                any = true;
            }
        }
    }
    if !any {
        return None;
    }
    let rect = crate::view::ndc_to_pixels(min, max, width, height);
    (rect[2] > 0 && rect[3] > 0).then_some(rect)
}

/// Shadow-volume generations per light and image (section 8.1): one for
/// the light itself, and per path one for each stretch drawn under
/// `shadows` (`k + 1` for a chain of `k` faces with every shadow).
pub fn shadow_generations(paths: &[SpecularPath], shadows: SpecularShadows) -> usize {
    1 + paths
        .iter()
        .map(|p| p.shadowed_stretches(shadows).len())
        .sum::<usize>()
}

/// Equation 7's count of shadow generations per image and light,
/// `n (d² + 3d)/2 + 1`, for `n` specular faces and shadow depth `d`: exact
/// when the light of every face goes on through one face per level.
pub fn equation_7(n: usize, d: u32) -> usize {
    let d = d as usize;
    n * (d * d + 3 * d) / 2 + 1
}

/// The point light `light` seen through `path`: moved by its transform, its
/// axis by the linear part, its intensity times the factor; `None` for an
/// area light.
pub fn virtual_light(light: &Light, path: &SpecularPath) -> Option<Light> {
    let m = path.transform();
    let axis = |a: Vec3| (m.matrix3 * a).normalize_or_zero();
    let scale = |i: lustre_geometry::Rgb| {
        i * lustre_geometry::Rgb::new(path.factor.x, path.factor.y, path.factor.z)
    };
    Some(match light {
        Light::Point(p) => Light::Point(lustre_geometry::light::PointLight {
            position: m.transform_point3(p.position),
            intensity: scale(p.intensity),
        }),
        Light::OrientedPoint(p) => {
            Light::OrientedPoint(lustre_geometry::light::OrientedPointLight {
                position: m.transform_point3(p.position),
                normal: axis(p.normal),
                intensity: scale(p.intensity),
            })
        }
        Light::Spot(s) => Light::Spot(lustre_geometry::light::SpotLight {
            position: m.transform_point3(s.position),
            direction: axis(s.direction),
            intensity: scale(s.intensity),
            ..*s
        }),
        Light::Area(_) => return None,
    })
}

/// Whether `x`, on `face`'s plane, lies in one of its triangles.
fn in_face(face: &SpecularFace, x: Vec3) -> bool {
    let n = face.plane.normal;
    face.corners.chunks_exact(3).any(|t| {
        let inside = |a: Vec3, b: Vec3| (b - a).cross(x - a).dot(n) >= 0.0;
        let ccw = (t[1] - t[0]).cross(t[2] - t[0]).dot(n) >= 0.0;
        let (a, b, c) = if ccw {
            (t[0], t[1], t[2])
        } else {
            (t[0], t[2], t[1])
        };
        inside(a, b) && inside(b, c) && inside(c, a)
    })
}

/// CPU twin of a virtual light's stencil (sections 4.2, 4.3): whether light
/// from a point light at `light` reaches `p` through `path`, followed back
/// from `p` by ray casts. Per face from the last, the line from the virtual
/// light `L_j` to the point reached must leave `F_j` on its outgoing side
/// and cross its polygon at `X`; the stretch from `X` to that point must be
/// free in `bvh` (ends shortened by `epsilon`). A mirror's path goes on
/// from `X` (a mirror's and an interface's); a slab's from where the line from `L_{j−1}` with the same
/// direction meets the far face (a slab keeps a ray's direction; the
/// stretch inside it is not tested). Finally the stretch from the light.
pub fn path_visible(
    bvh: &Bvh,
    faces: &[SpecularFace],
    path: &SpecularPath,
    light: Vec3,
    p: Vec3,
    epsilon: f32,
) -> bool {
    path_arrival(bvh, faces, path, light, p, epsilon).is_some()
}

/// [`path_visible`] with where the path crosses each face: `None` where the
/// light does not reach `p`, else per face of the chain (in chain order)
/// the crossing point `X` on it and the direction the light travels there
/// (from `L_{j−1}` unfolded, not normalised).
pub fn path_arrival(
    bvh: &Bvh,
    faces: &[SpecularFace],
    path: &SpecularPath,
    light: Vec3,
    p: Vec3,
    epsilon: f32,
) -> Option<Vec<(Vec3, Vec3)>> {
    let mut crossings = vec![(Vec3::ZERO, Vec3::ZERO); path.len()];
    let free = |a: Vec3, b: Vec3| {
        let d = b - a;
        let len = d.length();
        len <= 2.0 * epsilon || !bvh.any_hit(&Ray::segment(a, d / len, epsilon, len - epsilon))
    };
    let mut point = p;
    for j in (1..=path.len()).rev() {
        let face = &faces[path.faces[j - 1]];
        let source = path.prefix[j].transform_point3(light);
        let out = outgoing(face);
        let (ds, dp) = (out.depth(source), out.depth(point));
        if !(ds < 0.0 && dp > 0.0) {
            return None;
        }
        let x = source + (point - source) * (ds / (ds - dp));
        if !in_face(face, x) || !free(x, point) {
            return None;
        }
        // The direction the light had before the face: the segment from the
        // virtual light before it (a mirror's and interface's change it).
        let before = path.prefix[j - 1].transform_point3(light);
        crossings[j - 1] = (x, x - before);
        point = match plain_kind(face) {
            SpecularKind::Mirror
            | SpecularKind::Interface { .. }
            | SpecularKind::Glossy(_)
            | SpecularKind::Pane { .. } => x,
            SpecularKind::Slab { thickness, .. } => {
                let dir = point - source;
                let far = HalfSpace {
                    normal: face.plane.normal,
                    offset: face.plane.offset - thickness,
                };
                let (d0, slope) = (far.depth(before), far.normal.dot(dir));
                if slope <= 0.0 || d0 >= 0.0 {
                    return None;
                }
                before + dir * (-d0 / slope)
            }
        };
    }
    free(light, point).then_some(crossings)
}

/// CPU twin of the virtual lights (sections 4.2, 4.3, every shadow drawn):
/// per pixel centre's closest hit, for every point light of `lights` and
/// every chain of at most `depth` faces that its position passes, the
/// light's [`virtual_light`] times `f_r cos θi` where [`path_visible`] (with
/// the tolerance of the direct CPU twin, `1e-4` of the scene's extent). Bit
/// `v` of a pixel's `visible` is the `v`-th virtual light, lights in order
/// and each light's chains in [`specular_paths`] order.
#[allow(clippy::too_many_arguments)]
pub fn virtual_direct_pixels_cpu(
    scene: &lustre_geometry::Scene,
    lights: &[Light],
    faces: &[SpecularFace],
    windows: &[Window],
    depth: u32,
    bvh: &Bvh,
    camera: &lustre_geometry::Camera,
    width: u32,
    height: u32,
    glossy: crate::material::GlossyModel,
) -> crate::Result<Vec<crate::passes::direct::DirectPixel>> {
    let mut virtual_lights = Vec::new();
    let mut origins = Vec::new();
    for light in lights {
        let position = lustre_geometry::shadow_volume::light_position(light);
        for path in specular_paths(faces, position, depth) {
            if let Some(v) = virtual_light(light, &path) {
                virtual_lights.push(v);
                origins.push((position, path));
            }
        }
    }
    let epsilon = 1e-4 * scene.bounds().extent().max_element().max(1e-6);
    let reaches = |v: usize, p: Vec3, _: Vec3, _: f32| {
        let (position, path) = &origins[v];
        let crossings = path_arrival(bvh, faces, path, *position, p, epsilon)?;
        let mut factor = Vec3::ONE;
        for (&f, (x, direction)) in path.faces.iter().zip(crossings) {
            if let SpecularKind::Pane { window } = faces[f].kind {
                let window = windows.get(window as usize)?;
                let cos = direction.normalize_or_zero().dot(window.plane.normal);
                factor *= window.transmission_at(x, cos);
            }
        }
        Some(lustre_geometry::Rgb::new(factor.x, factor.y, factor.z))
    };
    crate::passes::direct::direct_pixels_cpu_where(
        scene,
        &virtual_lights,
        bvh,
        camera,
        width,
        height,
        glossy,
        &reaches,
    )
}

/// Per hit record of a photon map (the records of one photon consecutive,
/// in hit order from bounce 1, as `lustre_photon::trace_photons` writes
/// them): whether the photon reached it through a chain of at most `depth`
/// specular faces and nothing else, the light the virtual lights draw,
/// which the photon splats must then leave out so that it is added once
/// (section 6: the indirect term beside the direct terms). A link of the
/// chain is a hit on a mirror face, or a hit on a slab's far face followed
/// by a hit on the face itself (the transmission through the slab that the
/// slab's virtual light stands for); a photon Fresnel-reflected off the
/// glass, or scattered by any other surface, leaves the chain. (A photon
/// reflected inside a slab back and forth twice passes for two
/// transmissions: light of the order `F⁴`, left to the virtual lights.)
/// A hit on a pane of a window that `faces` holds (its [`SpecularKind::Pane`]
/// faces index `windows`) followed by a hit on its other side is a link
/// too, once per chain (section 4.5: a virtual light passes one window).
pub fn drawn_by_virtual_lights(
    records: &[lustre_photon::HitRecord],
    faces: &[SpecularFace],
    windows: &[Window],
    depth: u32,
) -> Vec<bool> {
    let mirrors: std::collections::HashSet<u32> = faces
        .iter()
        .filter(|f| f.kind == SpecularKind::Mirror)
        .map(|f| f.surface)
        .collect();
    // Far face → face: a slab's two faces, each the other's far face.
    let mut slabs = std::collections::HashMap::new();
    for f in faces {
        let SpecularKind::Slab { thickness, .. } = f.kind else {
            continue;
        };
        let far = faces.iter().find(|g| {
            matches!(g.kind, SpecularKind::Slab { .. })
                && g.plane.normal.dot(f.plane.normal) < -0.9999
                && (f.plane.offset + g.plane.offset - thickness).abs() <= 1e-4 * thickness.max(1e-6)
        });
        if let Some(g) = far {
            slabs.insert(g.surface, f.surface);
        }
    }
    // Interface surface → its normal: a hit there is a link when the photon
    // went on to the other side (refracted, not reflected).
    let interfaces: std::collections::HashMap<u32, Vec3> = faces
        .iter()
        .filter(|f| matches!(f.kind, SpecularKind::Interface { .. }))
        .map(|f| (f.surface, f.plane.normal))
        .collect();
    // Pane surface → its window's normal.
    let panes: std::collections::HashMap<u32, Vec3> = faces
        .iter()
        .filter_map(|f| match f.kind {
            SpecularKind::Pane { window } => windows.get(window as usize),
            _ => None,
        })
        .flat_map(|w| w.surfaces.iter().map(|&s| (s, w.plane.normal)))
        .collect();
    let mut out = Vec::with_capacity(records.len());
    // The chain so far: links, a slab entered but not left, still a chain,
    // a window passed.
    let (mut links, mut entered, mut chain) = (0u32, None::<u32>, false);
    let mut passed_window = false;
    let mut previous_bounce = 0u8;
    // The interface hit whose side the next record decides: its normal and `n · wᵢ`.
    let mut crossing: Option<(Vec3, f32)> = None;
    for r in records {
        if r.bounce == 1 || r.bounce != previous_bounce.wrapping_add(1) {
            (links, entered, chain, crossing) = (0, None, r.bounce == 1, None);
            passed_window = false;
        }
        previous_bounce = r.bounce;
        if let Some((n, before)) = crossing.take() {
            // Refracted: it went on across the plane, so the next hit also
            // looks back across it, `n · wᵢ` keeps its sign (reflected, it flips).
            if before * n.dot(r.direction) > 0.0 {
                links += 1;
            } else {
                chain = false;
            }
            chain &= links <= depth;
        }
        out.push(chain && entered.is_none() && (1..=depth).contains(&links));
        if !chain {
            continue;
        }
        match entered.take() {
            Some(exit) => {
                chain = r.surface == exit;
                links += 1;
            }
            None if mirrors.contains(&r.surface) => links += 1,
            None => match (slabs.get(&r.surface), interfaces.get(&r.surface)) {
                (Some(&exit), _) => entered = Some(exit),
                (None, Some(&n)) => crossing = Some((n, n.dot(r.direction))),
                (None, None) => match panes.get(&r.surface) {
                    Some(&n) if !passed_window => {
                        passed_window = true;
                        crossing = Some((n, n.dot(r.direction)));
                    }
                    _ => chain = false,
                },
            },
        }
        chain &= links <= depth;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::Plane;

    fn mirror(point: Vec3, normal: Vec3, half: f32) -> SpecularFace {
        let (u, v) = face_frame(&Plane::from_point_normal(point, normal));
        let c = |a: f32, b: f32| point + half * (a * u + b * v);
        let corners = vec![
            c(-1., -1.),
            c(1., -1.),
            c(1., 1.),
            c(-1., -1.),
            c(1., 1.),
            c(-1., 1.),
        ];
        SpecularFace {
            surface: 0,
            plane: Plane::from_point_normal(point, normal),
            kind: SpecularKind::Mirror,
            factor: Vec3::splat(0.9),
            corners,
        }
    }

    /// Two facing mirrors 2 m apart, 1 m wide, with the light between them.
    fn facing_pair() -> Vec<SpecularFace> {
        vec![
            mirror(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 0.5),
            mirror(Vec3::new(1.0, 0.0, 0.0), -Vec3::X, 0.5),
        ]
    }

    #[test]
    fn mirror_transform_reflects_and_slab_shifts() {
        let m = mirror(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 0.5);
        let t = face_transform(&m);
        assert!(
            (t.transform_point3(Vec3::new(0.5, 0.2, 0.3)) - Vec3::new(-2.5, 0.2, 0.3)).length()
                < 1e-6
        );
        assert!(t.matrix3.determinant() < 0.0);
        let slab = SpecularFace {
            kind: SpecularKind::Slab {
                shift: 0.01,
                thickness: 0.03,
            },
            ..m
        };
        let t = face_transform(&slab);
        assert!((t.transform_point3(Vec3::ZERO) - Vec3::new(0.01, 0.0, 0.0)).length() < 1e-7);
        // Light comes into a slab face from beyond its far face only.
        assert!(incoming(&slab).depth(Vec3::new(-1.05, 0.0, 0.0)) > 0.0);
        assert!(incoming(&slab).depth(Vec3::new(-1.02, 0.0, 0.0)) < 0.0);
        assert!(incoming(&slab).depth(Vec3::new(0.0, 0.0, 0.0)) < 0.0);
    }

    /// Facing mirrors: the light's chains alternate A, B, A… or B, A, B…,
    /// one continuation per level, so the shadow generations per light are
    /// exactly equation 7's `n (d² + 3d)/2 + 1` with `n = 2`, for d = 1…4;
    /// virtual lights sit at the images of the light in the mirror pair.
    #[test]
    fn facing_mirrors_need_equation_7_shadow_generations() {
        let faces = facing_pair();
        let light = Vec3::new(0.2, 0.0, 0.0);
        for d in 1..=4 {
            let paths = specular_paths(&faces, light, d);
            assert_eq!(paths.len(), 2 * d as usize, "d = {d}");
            assert_eq!(
                shadow_generations(&paths, SpecularShadows::All),
                equation_7(2, d),
                "d = {d}"
            );
        }
        let paths = specular_paths(&faces, light, 2);
        let positions: Vec<Vec3> = paths
            .iter()
            .map(|p| p.transform().transform_point3(light))
            .collect();
        // A (x = -1): -2.2; then B (x = 1): 4.2; B: 1.8; then A: -3.8.
        let expected = [-2.2, 4.2, 1.8, -3.8];
        for (p, e) in positions.iter().zip(expected) {
            assert!((p.x - e).abs() < 1e-5 && p.y.abs() < 1e-6, "{p} vs {e}");
        }
        assert!((paths[1].factor - Vec3::splat(0.81)).length() < 1e-6);
        // One mirror: one chain at any depth; equation 7 counts n = 1, d = 1.
        let one = &faces[..1];
        assert_eq!(
            shadow_generations(&specular_paths(one, light, 1), SpecularShadows::All),
            equation_7(1, 1)
        );
        assert_eq!(specular_paths(one, light, 3).len(), 1);
        // Table 2's reductions: without shadows through 2+ faces, without any.
        let paths = specular_paths(&faces, light, 2);
        assert_eq!(
            shadow_generations(&paths, SpecularShadows::OneBounce),
            1 + 2 * 2 + 2 * 2
        );
        assert_eq!(shadow_generations(&paths, SpecularShadows::Off), 1);
    }

    fn record(surface: u32, bounce: u8) -> lustre_photon::HitRecord {
        lustre_photon::HitRecord {
            surface,
            triangle: 0,
            position: glam::Vec2::ZERO,
            direction: Vec3::Y,
            light: 0,
            bounce,
            rho: Vec3::ONE,
        }
    }

    /// Photon paths through mirrors (surfaces 0, 1) and a slab (faces 2, 3)
    /// to a diffuse wall (9): records after 1..=depth whole links are drawn
    /// by virtual lights; a slab hit without its far face (a Fresnel
    /// reflection), a diffuse bounce, or more links than the depth are not.
    #[test]
    fn photon_records_on_virtual_light_chains() {
        let mut faces = facing_pair();
        faces[1].surface = 1;
        let slab = |surface: u32, x: f32, n: Vec3| SpecularFace {
            surface,
            kind: SpecularKind::Slab {
                shift: 0.01,
                thickness: 0.03,
            },
            ..mirror(Vec3::new(x, 0.0, 3.0), n, 0.5)
        };
        faces.push(slab(2, 0.0, Vec3::X));
        faces.push(slab(3, -0.03, -Vec3::X));
        let paths: [(&[u32], [bool; 1]); 7] = [
            (&[0, 9], [true]),
            (&[0, 1, 9], [false]),
            (&[3, 2, 9], [true]),
            (&[2, 9], [false]),
            (&[9, 0, 9], [false]),
            (&[9], [false]),
            (&[2, 3, 9], [true]),
        ];
        for depth in [1, 2] {
            let mut records = Vec::new();
            let mut last = Vec::new();
            for (surfaces, _) in &paths {
                for (b, &s) in surfaces.iter().enumerate() {
                    records.push(record(s, b as u8 + 1));
                }
                last.push(records.len() - 1);
            }
            let drawn = drawn_by_virtual_lights(&records, &faces, &[], depth);
            let got: Vec<bool> = last.iter().map(|&i| drawn[i]).collect();
            let mut want: Vec<bool> = paths.iter().map(|p| p.1[0]).collect();
            if depth == 2 {
                want[1] = true;
            }
            assert_eq!(got, want, "depth {depth}");
            // Records on the chain itself (mirror and slab hits) other than after a whole link.
            assert!(!drawn[0], "the first hit is the real light's");
        }
    }

    /// A photon through a single interface (surface 5, the plane y = 0
    /// facing up, both of its faces) to the floor is on a chain; one
    /// reflected off it is not.
    #[test]
    fn photon_records_through_an_interface() {
        let up = mirror(Vec3::ZERO, Vec3::Y, 1.0);
        let face = |normal: Vec3, ratio: f32| SpecularFace {
            surface: 5,
            plane: Plane::from_point_normal(Vec3::ZERO, normal),
            kind: SpecularKind::Interface { ratio },
            ..up.clone()
        };
        let faces = [face(Vec3::Y, 0.75), face(-Vec3::Y, 1.33)];
        let hit = |surface: u32, bounce: u8, direction: Vec3| lustre_photon::HitRecord {
            direction,
            ..record(surface, bounce)
        };
        // From above: wᵢ points up at the interface; refracted, the floor
        // hit looks up too; reflected, the ceiling hit looks down.
        let refracted = [hit(5, 1, Vec3::Y), hit(9, 2, Vec3::Y)];
        let reflected = [hit(5, 1, Vec3::Y), hit(8, 2, -Vec3::Y)];
        assert_eq!(
            drawn_by_virtual_lights(&refracted, &faces, &[], 1),
            [false, true]
        );
        assert_eq!(
            drawn_by_virtual_lights(&reflected, &faces, &[], 1),
            [false, false]
        );
        assert_eq!(
            drawn_by_virtual_lights(&refracted, &faces, &[], 0),
            [false, false]
        );
    }

    /// The stained-glass window as virtual-light faces (section 4.5): a
    /// light outside passes it once, a mirror then may extend the chain but
    /// a second window may not; photons through its panes to the floor are
    /// drawn by the virtual light, photons reflected off them are not.
    #[test]
    fn windows_pass_light_once_and_take_their_photons() {
        let scene = lustre_geometry::builtin::stained_glass::stained_glass();
        let windows = crate::projective_texture::windows(
            &scene,
            crate::projective_texture::PaneLight::default(),
        )
        .unwrap();
        let mut faces = window_faces(&windows);
        assert_eq!(faces.len(), 2);
        let light = lustre_geometry::builtin::stained_glass::LIGHT_POSITION;
        let paths = specular_paths(&faces, light, 2);
        // Only the side facing the room passes the light from outside.
        assert_eq!(paths.len(), 1);
        assert_eq!(paths[0].transform(), Affine3A::IDENTITY);
        // A second window behind the first is not chained after it.
        let mut second = windows[0].clone();
        second.plane.offset -= 1.0;
        second.origin -= second.plane.normal;
        let mut both = windows.clone();
        both.push(second);
        faces = window_faces(&both);
        let deep = specular_paths(&faces, light, 3);
        assert!(deep.iter().all(|p| p.len() == 1), "{:?}", deep);
        // Photons: through pane 5 to the floor (surface 0), and reflected back.
        let pane = windows[0].surfaces[5];
        let n = windows[0].plane.normal;
        let inward = Vec3::new(0.0, -0.5, 1.0).normalize();
        let hit = |surface: u32, bounce: u8, direction: Vec3| lustre_photon::HitRecord {
            direction,
            ..record(surface, bounce)
        };
        let faces = window_faces(&windows);
        let through = [hit(pane, 1, -inward), hit(0, 2, -inward)];
        let back = [hit(pane, 1, -inward), hit(1, 2, inward)];
        assert!(n.dot(inward).abs() > 0.1);
        assert_eq!(
            drawn_by_virtual_lights(&through, &faces, &windows, 1),
            [false, true]
        );
        assert_eq!(
            drawn_by_virtual_lights(&back, &faces, &windows, 1),
            [false, false]
        );
        // Without the windows' faces the splats keep them.
        assert_eq!(
            drawn_by_virtual_lights(&through, &[], &windows, 1),
            [false, false]
        );
    }

    /// The scissor of a virtual light holds the pixel of every point its
    /// light may reach in the box (points sampled in the box, kept where
    /// inside the cone beyond the face and in front of the camera), and is
    /// empty when the camera looks away.
    #[test]
    fn light_scissors_hold_every_lit_point() {
        let face = mirror(Vec3::ZERO, Vec3::Z, 0.5);
        let camera = lustre_geometry::Camera::look_at(
            Vec3::new(1.5, 1.0, 3.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::Y,
            60.0,
        )
        .with_aspect(4.0 / 3.0);
        let m = camera.projection_matrix() * camera.view_matrix();
        let (width, height) = (640, 480);
        let bounds = [Vec3::new(-3.0, -2.0, -1.0), Vec3::new(3.0, 2.0, 4.0)];
        let mut rng = 7u64;
        let mut next = move || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        for apex in [Vec3::new(0.3, 0.2, -1.0), Vec3::new(-0.8, 0.5, -0.4)] {
            let [x, y, w, h] = light_scissor(m, apex, &face, bounds, width, height).unwrap();
            assert!(w < width || h < height, "{x} {y} {w} {h}: no bound");
            let cone = cone_planes(apex, &face);
            let mut inside = 0;
            for _ in 0..20_000 {
                let p = bounds[0] + (bounds[1] - bounds[0]) * Vec3::new(next(), next(), next());
                if cone.iter().any(|h| h.depth(p) < 0.0) || outgoing(&face).depth(p) < 0.0 {
                    continue;
                }
                let c = m * p.extend(1.0);
                if c.w <= 0.0 || c.z > c.w {
                    continue;
                }
                let px = (c.x / c.w + 1.0) * 0.5 * width as f32;
                let py = (1.0 - c.y / c.w) * 0.5 * height as f32;
                if !(0.0..width as f32).contains(&px) || !(0.0..height as f32).contains(&py) {
                    continue;
                }
                inside += 1;
                assert!(
                    px >= x as f32
                        && px <= (x + w) as f32
                        && py >= y as f32
                        && py <= (y + h) as f32,
                    "({px}, {py}) outside [{x}, {y}, {w}, {h}]"
                );
            }
            assert!(inside > 100, "{inside} points tested");
        }
        // Looking away from the lit part of a box that ends at z = 1: nothing to draw.
        let away = lustre_geometry::Camera::look_at(
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(0.0, 0.0, 6.0),
            Vec3::Y,
            60.0,
        );
        let m = away.projection_matrix() * away.view_matrix();
        let near_box = [bounds[0], Vec3::new(3.0, 2.0, 1.0)];
        assert_eq!(
            light_scissor(m, Vec3::new(0.3, 0.2, -1.0), &face, near_box, width, height),
            None
        );
    }

    /// The cone through a 1 m square mirror from a point 1 m in front of
    /// it: points through the square are inside every side plane, points
    /// past its edge outside one.
    #[test]
    fn cones_hold_what_passes_the_face() {
        let face = mirror(Vec3::ZERO, Vec3::Z, 0.5);
        let apex = Vec3::new(0.0, 0.0, 1.0);
        let planes = cone_planes(apex, &face);
        assert_eq!(planes.len(), 4);
        let inside = |p: Vec3| planes.iter().all(|h| h.depth(p) >= -1e-6);
        assert!(inside(Vec3::new(0.0, 0.0, -1.0)));
        assert!(inside(Vec3::new(0.9, -0.9, -1.0)));
        assert!(!inside(Vec3::new(1.1, 0.0, -1.0)));
        assert!(inside(Vec3::new(0.2, 0.2, 0.5)));
        assert!(!inside(Vec3::new(0.4, 0.0, 0.5)));
        assert!(cone_planes(Vec3::new(2.0, 0.0, 0.0), &face).is_empty());
    }

    /// A face the light cannot reach through the previous face is culled:
    /// a second pair of mirrors far to the side.
    #[test]
    fn chains_skip_faces_outside_the_light_volume() {
        let mut faces = facing_pair();
        faces.push(mirror(Vec3::new(1.0, 10.0, 0.0), -Vec3::X, 0.5));
        let light = Vec3::new(0.2, 0.0, 0.0);
        let paths = specular_paths(&faces, light, 2);
        let chains: Vec<Vec<usize>> = paths.iter().map(|p| p.faces.clone()).collect();
        assert_eq!(
            chains,
            vec![vec![0], vec![0, 1], vec![1], vec![1, 0], vec![2]]
        );
    }

    /// Stretch bounds: the outgoing side of the face before, the incoming
    /// side of the face after; the mirror itself (in its plane) never blocks.
    #[test]
    fn stretches_are_bounded_by_their_faces() {
        let faces = facing_pair();
        let path = &specular_paths(&faces, Vec3::new(0.2, 0.0, 0.0), 2)[1];
        assert_eq!(path.stretch_bounds(&faces, 0).len(), 1);
        assert_eq!(path.stretch_bounds(&faces, 1).len(), 2);
        assert_eq!(path.stretch_bounds(&faces, 2).len(), 1);
        let own = [
            faces[0].corners[0],
            faces[0].corners[1],
            faces[0].corners[2],
        ];
        assert!(!outgoing(&faces[0]).holds_triangle(&own, 1e-5));
        let between = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
        ];
        assert!(
            path.stretch_bounds(&faces, 1)
                .iter()
                .all(|h| h.holds_triangle(&between, 1e-5))
        );
        assert_eq!(path.shadowed_stretches(SpecularShadows::OneBounce), 1..3);
        // suffix(j) ∘ prefix(j) = the whole transform.
        for j in 0..=2 {
            let q = Vec3::new(0.3, 0.1, -0.2);
            let a = (path.suffix(j) * path.prefix[j]).transform_point3(q);
            assert!((a - path.transform().transform_point3(q)).length() < 1e-5);
        }
    }
}
