//! Shadow volumes (Diefenbach & Badler 1997, section 4.1, after Crow 1977
//! and Brotman & Badler 1984): per object and point light, the closed
//! polyhedron behind the object's silhouette, stored with the object and
//! rebuilt only when the object or the light moves (section 4.3), with the
//! far vertices at infinity so that the pivot jitter of section 4.4 is exact
//! in homogeneous form, and a CPU twin of the GPU's z-fail stencil count.
//!
//! # Construction
//!
//! For a light at `l`, a triangle `p0 p1 p2` (world space, geometric normal
//! `n = (p1 - p0) × (p2 - p0)` from its winding) is *lit* when
//! `(l - p0) · n > 0` (clearly, beyond a relative tolerance that leaves
//! edge-on triangles, such as an area light's own quad seen from its centre,
//! unlit). The volume is made of
//!
//! * the **front cap**: the lit triangles themselves, normals toward the light;
//! * the **back cap**: the same triangles extruded to infinity, every corner
//!   `p` replaced by the point at infinity in direction `p − l`
//!   (homogeneous `(p − l, 0)`), wound the other way;
//! * the **sides**: for every undirected edge, the signed count of lit
//!   triangles using it (`+1` for `a → b`, `−1` for `b → a`, with `a < b` the
//!   welded vertex ids); an edge with count `c ≠ 0` gets `|c|` quads
//!   `a, b, b∞, a∞` oriented by the sign of `c`. Edges between two lit
//!   triangles of a consistently wound mesh cancel, so a closed mesh gets its
//!   silhouette edges only; the edges of open or non-manifold meshes (the
//!   Cornell box's single-quad walls) get the quads they need, so every volume
//!   is closed and its faces point outward.
//!
//! Vertices are shared by position (welded within a tolerance relative to the
//! object's size), so meshes with per-face vertices (Mitsuba's cube) are
//! handled like indexed ones; the caps keep each triangle's own positions so
//! they coincide with what the depth pass drew.
//!
//! In a closed object only the triangles facing the light cast (its back
//! faces bound the same shadow). An open object (some welded edge not used
//! once each way, such as a single-quad wall) casts from both sides, as a
//! ray cast is blocked by it from either side: a triangle facing away is
//! taken with the opposite winding. Were it one-sided, a wall turned away
//! from a light outside the room would let that light in.
//!
//! # Storage and the pivot approximation
//!
//! Every vertex is a [`VolumeVertex`]: a world position and whether it is
//! extruded. A vertex shader draws a finite vertex at `(p, 1)` and an
//! extruded one at `(p − l′, 0)` for the light position `l′` of the current
//! pass. Section 4.4 jitters the light without rebuilding the volumes: the
//! silhouette is kept from the central light `l`, and only the two far
//! vertices of each side face move, linearly in the jitter `δ = l′ − l`
//! (figure 7: the silhouette edge is the pivot, and the paper scales the
//! displacement by the ratios `a2/a1`, `b2/b1`, approximated by a constant).
//! With the far vertices at infinity that linear move is exact: the far
//! vertex of `p` becomes the direction `p − l − δ`, every side face stays in
//! the plane through `l′` and its edge, the back cap stays the directions of
//! the front cap's corners, so the volume is exactly the closed shadow
//! volume, seen from `l′`, of the *central* light's lit set. The only
//! approximation left is that lit set: near the silhouette a triangle lit
//! from `l` but not from `l′` (or the reverse) is treated as it is from `l`.
//!
//! # Counting (z-fail)
//!
//! The GPU counts with the depth-fail rule (Carmack's reverse): faces
//! *behind* the visible point `p` along the eye ray, back faces `+1`, front
//! faces `−1`; `p` is in shadow where the count is not zero (it is the number
//! of volumes containing `p`). [`in_shadow`] and [`ShadowVolume::count_behind`]
//! do the same count by brute-force intersection of the ray from `p` away from
//! the eye with every volume triangle in homogeneous coordinates, so the faces
//! at infinity count exactly as the GPU's depth-0 back caps do.

use std::collections::HashMap;

use glam::{Affine3A, DVec3, DVec4, Vec3};

use crate::light::Light;
use crate::scene::{ObjectId, Scene};
use crate::{GeometryError, MeshId, Result};

/// One corner of a shadow-volume triangle (Diefenbach & Badler 1997, section
/// 4.4): a world position, drawn at `(position, 1)`, or, when `extruded`, at
/// the point at infinity `(position − light, 0)` for the light of the pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeVertex {
    /// World position of the corner (of the silhouette or cap vertex it is extruded from).
    pub position: Vec3,
    /// Whether the corner is the point at infinity in direction `position − light`.
    pub extruded: bool,
}

impl VolumeVertex {
    /// Size of the GPU form, [`VolumeVertex::gpu`], in bytes.
    pub const GPU_SIZE: usize = 16;

    /// The GPU form `[x, y, z, w]` with `w = 1` for a finite corner and
    /// `w = 0` for an extruded one; the vertex shader replaces `xyz` by
    /// `xyz − light` where `w = 0` (section 4.4).
    pub fn gpu(&self) -> [f32; 4] {
        let p = self.position;
        [p.x, p.y, p.z, if self.extruded { 0.0 } else { 1.0 }]
    }

    /// The homogeneous point it stands for when the volume is extruded from `light`.
    fn homogeneous(&self, light: DVec3) -> DVec4 {
        let p = self.position.as_dvec3();
        if self.extruded {
            (p - light).extend(0.0)
        } else {
            p.extend(1.0)
        }
    }
}

/// The shadow volume of one object for one point light (Diefenbach & Badler
/// 1997, section 4.1): a closed, outward-facing triangle list with front
/// caps, back caps at infinity and side quads (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowVolume {
    /// The object that casts it.
    pub object: ObjectId,
    /// Index of the light in the light list it was built for.
    pub light_index: usize,
    /// The light position it was built for (the central light of section 4.4).
    pub light: Vec3,
    /// The object's transform it was built for.
    pub transform: Affine3A,
    /// Triangle list, three vertices per triangle: front caps, back caps, then sides.
    pub vertices: Vec<VolumeVertex>,
    /// Number of front-cap triangles (the lit triangles; as many back-cap triangles follow).
    pub cap_triangles: usize,
    /// Number of undirected edges with a non-zero signed count (silhouette and open edges).
    pub silhouette_edges: usize,
    /// Number of side quads (the sum of the edges' absolute counts; two triangles each).
    pub side_quads: usize,
}

impl ShadowVolume {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.vertices.len() / 3
    }

    /// Whether the volume is empty (nothing of the object faces the light).
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Bytes of its vertex data in the GPU form ([`VolumeVertex::GPU_SIZE`] per vertex).
    pub fn byte_size(&self) -> usize {
        self.vertices.len() * VolumeVertex::GPU_SIZE
    }

    /// The volume moved by the affine map `m` (a mirror's reflection or a
    /// slab's shift): every corner mapped, the light it was built for mapped
    /// with it, so the far vertices extrude from `m(light)` in the mapped
    /// directions, and the winding reversed where `m` mirrors, so the faces
    /// still point outward (section 4.3: a shadow bent by a specular face is
    /// a transformed copy of the original volume).
    pub fn transformed(&self, m: Affine3A) -> ShadowVolume {
        let mirrors = m.matrix3.determinant() < 0.0;
        let mut vertices: Vec<VolumeVertex> = self
            .vertices
            .iter()
            .map(|v| VolumeVertex {
                position: m.transform_point3(v.position),
                extruded: v.extruded,
            })
            .collect();
        if mirrors {
            for tri in vertices.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }
        ShadowVolume {
            object: self.object,
            light_index: self.light_index,
            light: m.transform_point3(self.light),
            transform: m * self.transform,
            vertices,
            cap_triangles: self.cap_triangles,
            silhouette_edges: self.silhouette_edges,
            side_quads: self.side_quads,
        }
    }

    /// The vertices in the GPU form, ready to upload as a vertex buffer.
    pub fn gpu_vertices(&self) -> Vec<[f32; 4]> {
        self.vertices.iter().map(VolumeVertex::gpu).collect()
    }

    /// The z-fail count at `p` seen from `eye` with the far vertices
    /// extruded from `light` (the built light, or a jittered one for the
    /// pivot approximation of section 4.4): over the volume's faces that the
    /// ray from `p` away from the eye meets (at infinity included), back faces
    /// `+1` and front faces `−1` (section 4.1 with the depth-fail rule). The
    /// ray starts [`SURFACE_BIAS`] toward the eye, so the front cap lying on
    /// the surface that holds `p` counts, as it does on the GPU, where its
    /// depth equals the depth buffer's and fails the `Greater` test.
    pub fn count_behind(&self, light: Vec3, eye: Vec3, p: Vec3) -> i32 {
        let d = (p - eye).as_dvec3();
        let len = d.length();
        if !(len > 0.0) || !light.is_finite() {
            return 0;
        }
        let d = d / len;
        let start = p.as_dvec3() - f64::from(SURFACE_BIAS) * d;
        let (pp, dd, e) = (start.extend(1.0), d.extend(0.0), eye.as_dvec3().extend(1.0));
        let l = light.as_dvec3();
        let mut count = 0;
        for tri in self.vertices.chunks_exact(3) {
            let v = [
                tri[0].homogeneous(l),
                tri[1].homogeneous(l),
                tri[2].homogeneous(l),
            ];
            if !ray_meets_beyond(pp, dd, v) {
                continue;
            }
            let facing = plane(v).dot(e);
            if facing > 0.0 {
                count -= 1;
            } else if facing < 0.0 {
                count += 1;
            }
        }
        count
    }
}

/// Distance, in metres, toward the eye from which [`ShadowVolume::count_behind`]
/// starts its ray, so that a front cap on the surface holding `p` counts as
/// behind it (the GPU's depth-equal fail) (section 4.1).
pub const SURFACE_BIAS: f32 = 1e-4;

/// Whether `p`, seen from `eye`, is inside any of the volumes: the z-fail
/// count of section 4.1 summed over them, each extruded from the light it was
/// built for, is not zero.
pub fn in_shadow<'a>(
    volumes: impl IntoIterator<Item = &'a ShadowVolume>,
    eye: Vec3,
    p: Vec3,
) -> bool {
    shadow_count(volumes, Vec3::ZERO, eye, p) != 0
}

/// The z-fail count of section 4.1 summed over the volumes, each extruded
/// from its built light moved by `jitter` (the pivot approximation of section
/// 4.4; `Vec3::ZERO` for none).
pub fn shadow_count<'a>(
    volumes: impl IntoIterator<Item = &'a ShadowVolume>,
    jitter: Vec3,
    eye: Vec3,
    p: Vec3,
) -> i32 {
    volumes
        .into_iter()
        .map(|v| v.count_behind(v.light + jitter, eye, p))
        .sum()
}

/// Whether the ray `start + τ d` (homogeneous `σ start + τ d`) meets the
/// homogeneous triangle `v` with `τ > 0`, at infinity (`σ = 0`) included:
/// the null vector of `[start, d, −v0, −v1, −v2]` has all components of one sign.
fn ray_meets_beyond(start: DVec4, d: DVec4, v: [DVec4; 3]) -> bool {
    let cols = [start, d, -v[0], -v[1], -v[2]];
    let mut x = [0.0f64; 5];
    for k in 0..5 {
        let mut m = [DVec4::ZERO; 4];
        let mut j = 0;
        for (i, c) in cols.iter().enumerate() {
            if i != k {
                m[j] = *c;
                j += 1;
            }
        }
        let det = glam::DMat4::from_cols(m[0], m[1], m[2], m[3]).determinant();
        x[k] = if k % 2 == 0 { det } else { -det };
    }
    // Orient the null vector so that the barycentric weights are positive.
    let s = x[2] + x[3] + x[4];
    if s == 0.0 || !s.is_finite() {
        return false;
    }
    let x = x.map(|c| c * s.signum());
    x[0] >= 0.0 && x[1] > 0.0 && x[2] >= 0.0 && x[3] >= 0.0 && x[4] >= 0.0
}

/// The oriented plane `(n, d)` through three homogeneous points: for finite
/// points `n = (v1 − v0) × (v2 − v0)`, `d = −n · v0`; the same formula
/// orients triangles with corners at infinity consistently (oriented
/// projective geometry).
fn plane(v: [DVec4; 3]) -> DVec4 {
    let (x0, x1, x2) = (v[0].truncate(), v[1].truncate(), v[2].truncate());
    let (w0, w1, w2) = (v[0].w, v[1].w, v[2].w);
    let n = w2 * x0.cross(x1) + w0 * x1.cross(x2) + w1 * x2.cross(x0);
    n.extend(-x0.dot(x1.cross(x2)))
}

/// The position of a light seen as a point: the position of a point, oriented
/// point or spot light, the centroid of an area light (its single point light
/// of section 4.4).
pub fn light_position(light: &Light) -> Vec3 {
    match light {
        Light::Point(l) => l.position,
        Light::OrientedPoint(l) => l.position,
        Light::Spot(l) => l.position,
        Light::Area(l) => l.shape.centroid(),
    }
}

/// Relative tolerance of the welding of positions (of the object's size).
const WELD_RELATIVE: f32 = 1e-6;
/// A triangle is lit when the sine of the light's elevation above its plane exceeds this.
const LIT_SINE: f64 = 1e-5;

/// The connectivity of one object: its triangles by mesh, and the welded
/// vertex id of every mesh vertex (computed once in the rest pose).
#[derive(Debug, Clone, PartialEq)]
struct ObjectTopology {
    /// The object's meshes.
    meshes: Vec<MeshId>,
    /// Vertex count of each mesh, to notice a changed scene.
    vertex_counts: Vec<usize>,
    /// `weld[i][v]`: welded id of vertex `v` of mesh `meshes[i]`.
    weld: Vec<Vec<u32>>,
    /// For each welded id, the (mesh slot, vertex) whose position stands for it.
    representative: Vec<(usize, u32)>,
    /// Whether every welded edge is used once each way (a closed surface).
    closed: bool,
}

impl ObjectTopology {
    fn new(scene: &Scene, object: ObjectId) -> Self {
        let meshes = scene.objects()[object as usize].meshes.clone();
        let all = || {
            meshes
                .iter()
                .flat_map(|&m| scene.meshes()[m as usize].positions.iter().copied())
        };
        let (lo, hi) = all().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
        let extent = (hi - lo).max_element();
        let tol = if extent.is_finite() && extent > 0.0 {
            WELD_RELATIVE * extent
        } else {
            f32::MIN_POSITIVE
        };
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        let mut representative: Vec<(usize, u32)> = Vec::new();
        let mut rep_pos: Vec<Vec3> = Vec::new();
        let mut weld = Vec::with_capacity(meshes.len());
        let mut vertex_counts = Vec::with_capacity(meshes.len());
        for (slot, &m) in meshes.iter().enumerate() {
            let positions = &scene.meshes()[m as usize].positions;
            vertex_counts.push(positions.len());
            let mut ids = Vec::with_capacity(positions.len());
            for (v, &p) in positions.iter().enumerate() {
                let cell = (p / tol).floor().as_i64vec3().to_array();
                let mut found = None;
                'search: for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let key = [cell[0] + dx, cell[1] + dy, cell[2] + dz];
                            for &id in grid.get(&key).map(Vec::as_slice).unwrap_or(&[]) {
                                if rep_pos[id as usize].distance(p) <= tol {
                                    found = Some(id);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
                let id = found.unwrap_or_else(|| {
                    let id = representative.len() as u32;
                    representative.push((slot, v as u32));
                    rep_pos.push(p);
                    grid.entry(cell).or_default().push(id);
                    id
                });
                ids.push(id);
            }
            weld.push(ids);
        }
        // Per undirected welded edge: uses a → b (a < b) and b → a.
        let mut uses: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for (slot, &m) in meshes.iter().enumerate() {
            for tri in &scene.meshes()[m as usize].indices {
                let w = tri.map(|i| weld[slot][i as usize]);
                for (a, b) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
                    if a < b {
                        uses.entry((a, b)).or_default().0 += 1;
                    } else if b < a {
                        uses.entry((b, a)).or_default().1 += 1;
                    }
                }
            }
        }
        let closed = !uses.is_empty() && uses.values().all(|&u| u == (1, 1));
        Self {
            meshes,
            vertex_counts,
            weld,
            representative,
            closed,
        }
    }

    /// Whether the scene still has the meshes this topology was made from.
    fn matches(&self, scene: &Scene, object: ObjectId) -> bool {
        let Some(o) = scene.objects().get(object as usize) else {
            return false;
        };
        o.meshes == self.meshes
            && self
                .meshes
                .iter()
                .zip(&self.vertex_counts)
                .all(|(&m, &n)| scene.meshes()[m as usize].positions.len() == n)
    }
}

/// Which of an object's triangles cast a volume, and with which winding.
#[derive(Clone, Copy)]
struct Selection<'a> {
    /// Keeps a triangle (world positions, own winding) when true.
    keep: &'a dyn Fn(&[Vec3; 3]) -> bool,
    /// Takes every kept triangle with the opposite winding.
    reversed: bool,
}

/// Every triangle, as wound.
fn everything(_: &[Vec3; 3]) -> bool {
    true
}

const ALL: Selection<'static> = Selection {
    keep: &everything,
    reversed: false,
};

/// Builds the volume of one object for one light from the object's current pose.
fn build_volume(
    scene: &Scene,
    topology: &ObjectTopology,
    object: ObjectId,
    light_index: usize,
    light: Vec3,
) -> ShadowVolume {
    build_selected(scene, topology, object, light_index, light, ALL)
}

/// [`build_volume`] over the triangles `selection` keeps, in its winding.
fn build_selected(
    scene: &Scene,
    topology: &ObjectTopology,
    object: ObjectId,
    light_index: usize,
    light: Vec3,
    selection: Selection<'_>,
) -> ShadowVolume {
    let world: Vec<Vec<Vec3>> = topology
        .meshes
        .iter()
        .map(|&m| scene.world_positions(m))
        .collect();
    let l = light.as_dvec3();
    let mut front = Vec::new();
    let mut back = Vec::new();
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for (slot, &m) in topology.meshes.iter().enumerate() {
        for &tri in &scene.meshes()[m as usize].indices {
            let p = tri.map(|i| world[slot][i as usize]);
            if !(selection.keep)(&p) {
                continue;
            }
            let (tri, p) = if selection.reversed {
                ([tri[0], tri[2], tri[1]], [p[0], p[2], p[1]])
            } else {
                (tri, p)
            };
            let [p0, p1, p2] = p.map(Vec3::as_dvec3);
            let n = (p1 - p0).cross(p2 - p0);
            let to_light = l - p0;
            let scale = n.length() * to_light.length();
            let facing = n.dot(to_light);
            let (tri, p) = if facing > LIT_SINE * scale {
                (tri, p)
            } else if !topology.closed && -facing > LIT_SINE * scale {
                // An open surface seen from behind casts as if turned round.
                ([tri[0], tri[2], tri[1]], [p[0], p[2], p[1]])
            } else {
                continue;
            };
            front.extend(p.map(|position| VolumeVertex {
                position,
                extruded: false,
            }));
            back.extend([p[0], p[2], p[1]].map(|position| VolumeVertex {
                position,
                extruded: true,
            }));
            let w = tri.map(|i| topology.weld[slot][i as usize]);
            for (a, b) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
                if a < b {
                    *edges.entry((a, b)).or_insert(0) += 1;
                } else if b < a {
                    *edges.entry((b, a)).or_insert(0) -= 1;
                }
            }
        }
    }
    let mut silhouette: Vec<((u32, u32), i32)> =
        edges.into_iter().filter(|&(_, c)| c != 0).collect();
    silhouette.sort_unstable();
    let position = |id: u32| {
        let (slot, v) = topology.representative[id as usize];
        world[slot][v as usize]
    };
    let cap_triangles = front.len() / 3;
    let mut vertices = front;
    vertices.append(&mut back);
    let mut side_quads = 0;
    for &((a, b), c) in &silhouette {
        // The edge as a lit triangle walks it: a → b for a positive count.
        let (a, b) = if c > 0 {
            (position(a), position(b))
        } else {
            (position(b), position(a))
        };
        let finite = |position| VolumeVertex {
            position,
            extruded: false,
        };
        let far = |position| VolumeVertex {
            position,
            extruded: true,
        };
        for _ in 0..c.unsigned_abs() {
            vertices.extend([finite(b), finite(a), far(a), finite(b), far(a), far(b)]);
            side_quads += 1;
        }
    }
    ShadowVolume {
        object,
        light_index,
        light,
        transform: scene.objects()[object as usize].transform,
        vertices,
        cap_triangles,
        silhouette_edges: silhouette.len(),
        side_quads,
    }
}

/// The shadow volumes of a scene's casting objects for a list of point
/// lights, kept with the objects and rebuilt only for objects or lights that
/// moved (Diefenbach & Badler 1997, sections 4.1 and 4.3).
#[derive(Debug, Clone)]
pub struct ShadowVolumeSet {
    casters: Vec<ObjectId>,
    topologies: Vec<ObjectTopology>,
    lights: Vec<Vec3>,
    /// `volumes[light * casters.len() + caster]`.
    volumes: Vec<ShadowVolume>,
}

fn check_lights(lights: &[Vec3]) -> Result<()> {
    match lights.iter().position(|l| !l.is_finite()) {
        Some(i) => Err(GeometryError::InvalidLight {
            light: format!("#{i}"),
            message: "shadow-volume light position is not finite".into(),
        }),
        None => Ok(()),
    }
}

impl ShadowVolumeSet {
    /// The volumes of every object of the scene for every light position
    /// (section 4.1). Fails when a light position is not finite.
    pub fn new(scene: &Scene, lights: &[Vec3]) -> Result<Self> {
        let casters: Vec<ObjectId> = (0..scene.objects().len() as ObjectId).collect();
        Self::with_casters(scene, &casters, lights)
    }

    /// The volumes of the given objects for every light position (section
    /// 4.1). Fails when an object does not exist or a light position is not finite.
    pub fn with_casters(scene: &Scene, casters: &[ObjectId], lights: &[Vec3]) -> Result<Self> {
        check_lights(lights)?;
        if let Some(&bad) = casters
            .iter()
            .find(|&&o| o as usize >= scene.objects().len())
        {
            return Err(GeometryError::UnknownObject(format!("#{bad}")));
        }
        let topologies = casters
            .iter()
            .map(|&o| ObjectTopology::new(scene, o))
            .collect();
        let mut set = Self {
            casters: casters.to_vec(),
            topologies,
            lights: Vec::new(),
            volumes: Vec::new(),
        };
        set.rebuild_all(scene, lights);
        Ok(set)
    }

    fn rebuild_all(&mut self, scene: &Scene, lights: &[Vec3]) -> usize {
        self.lights = lights.to_vec();
        self.volumes = lights
            .iter()
            .enumerate()
            .flat_map(|(li, &l)| {
                self.casters
                    .iter()
                    .zip(&self.topologies)
                    .map(move |(&o, t)| build_volume(scene, t, o, li, l))
            })
            .collect();
        self.volumes.len()
    }

    /// Rebuilds the volumes whose object's transform or light position
    /// changed since they were built (section 4.3: volumes are regenerated
    /// only when the object or the light has moved); a different number of
    /// lights, or objects whose meshes changed, rebuild what they touch.
    /// Returns the number of volumes rebuilt. Fails when a light position is
    /// not finite or a caster no longer exists (the set is left unchanged).
    pub fn refresh(&mut self, scene: &Scene, lights: &[Vec3]) -> Result<usize> {
        check_lights(lights)?;
        if let Some(&bad) = self
            .casters
            .iter()
            .find(|&&o| o as usize >= scene.objects().len())
        {
            return Err(GeometryError::UnknownObject(format!("#{bad}")));
        }
        let mut retopologised = vec![false; self.casters.len()];
        for (c, &o) in self.casters.iter().enumerate() {
            if !self.topologies[c].matches(scene, o) {
                self.topologies[c] = ObjectTopology::new(scene, o);
                retopologised[c] = true;
            }
        }
        if lights.len() != self.lights.len() {
            return Ok(self.rebuild_all(scene, lights));
        }
        let n = self.casters.len();
        let mut rebuilt = 0;
        for (li, &l) in lights.iter().enumerate() {
            for c in 0..n {
                let o = self.casters[c];
                let volume = &self.volumes[li * n + c];
                let moved = volume.light != l
                    || volume.transform != scene.objects()[o as usize].transform
                    || retopologised[c];
                if moved {
                    self.volumes[li * n + c] = build_volume(scene, &self.topologies[c], o, li, l);
                    rebuilt += 1;
                }
            }
        }
        self.lights = lights.to_vec();
        Ok(rebuilt)
    }

    /// The volume of caster `caster` (an index into [`ShadowVolumeSet::casters`])
    /// for a point light at `light` cast only by the triangles `keep`
    /// selects (world positions, as wound), each taken with the opposite
    /// winding when `reversed`: the volumes of a virtual light, cast by the
    /// geometry on one side of a specular face, and the light volume behind a
    /// face (Diefenbach & Badler 1997, sections 4.2 and 4.3). Uses the set's
    /// welding of the object; fails on an unknown caster or a light that is
    /// not finite.
    pub fn volume_where(
        &self,
        scene: &Scene,
        caster: usize,
        light: Vec3,
        keep: &dyn Fn(&[Vec3; 3]) -> bool,
        reversed: bool,
    ) -> Result<ShadowVolume> {
        check_lights(&[light])?;
        let Some(&object) = self.casters.get(caster) else {
            return Err(GeometryError::UnknownObject(format!("caster #{caster}")));
        };
        if object as usize >= scene.objects().len() {
            return Err(GeometryError::UnknownObject(format!("#{object}")));
        }
        let selection = Selection { keep, reversed };
        let topology = &self.topologies[caster];
        Ok(if topology.matches(scene, object) {
            build_selected(scene, topology, object, 0, light, selection)
        } else {
            let fresh = ObjectTopology::new(scene, object);
            build_selected(scene, &fresh, object, 0, light, selection)
        })
    }

    /// The casting objects.
    pub fn casters(&self) -> &[ObjectId] {
        &self.casters
    }

    /// The light positions the volumes were built for.
    pub fn lights(&self) -> &[Vec3] {
        &self.lights
    }

    /// Every volume, light by light, casters in [`ShadowVolumeSet::casters`] order.
    pub fn volumes(&self) -> &[ShadowVolume] {
        &self.volumes
    }

    /// The volumes of one light (empty for an index out of range).
    pub fn volumes_for_light(&self, light: usize) -> &[ShadowVolume] {
        let n = self.casters.len();
        self.volumes
            .get(light * n..(light + 1) * n)
            .unwrap_or_default()
    }

    /// The volume of one object for one light, if the object casts.
    pub fn volume(&self, object: ObjectId, light: usize) -> Option<&ShadowVolume> {
        let c = self.casters.iter().position(|&o| o == object)?;
        self.volumes.get(light * self.casters.len() + c)
    }

    /// Bytes of all the volumes' vertex data in the GPU form (section 4.3's storage cost).
    pub fn byte_size(&self) -> usize {
        self.volumes.iter().map(ShadowVolume::byte_size).sum()
    }

    /// Total number of silhouette (and open) edges over all volumes.
    pub fn silhouette_edges(&self) -> usize {
        self.volumes.iter().map(|v| v.silhouette_edges).sum()
    }

    /// Total number of triangles over all volumes.
    pub fn triangle_count(&self) -> usize {
        self.volumes.iter().map(ShadowVolume::triangle_count).sum()
    }
}

#[cfg(test)]
mod tests;
