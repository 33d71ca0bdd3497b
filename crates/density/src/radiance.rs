//! View-dependent radiance of glossy vertices under Impact Count and Photon Maps (section 2.10 carried over from DETP's disc to the other two estimators of section 1.2).
//!
//! Equation 2.1, `L(x, ωo) = ∫ f_r(x, ωi, ωo) L_i cos θi dωi`, is estimated
//! from the impacts near `x` exactly as each estimator estimates the
//! irradiance, every impact's power weighted by the BRDF from its incoming
//! direction `ωi` (towards where the photon came from, the light side) to the
//! eye direction `ωo`:
//!
//! - Impact Count: `L_v = Σ_{t∋v} Σ_{j∈t} f_r(ωi_j, ωo) φ_j / Σ_{t∋v} A_t`
//!   over the impacts on the triangles meeting at the vertex, the analogue of
//!   its irradiance `Σ_t Σ φ / Σ_t A_t`;
//! - Photon Maps: `L(x, ωo) = Σ_{k nearest} f_r(ωi_j, ωo) φ_j / A`,
//!   Jensen's radiance estimate, `A` the area of the disc of radius `r_k`.
//!
//! Photon Maps' sums run over the `k` nearest impacts *compatible* with the
//! vertex's surface (Jensen 2001's normal filter, beyond García et al.'s
//! text; see [`ImpactMap`]), and `A` is the part of `π r_k²` that lies on
//! compatible surfaces (the boundary correction of [`crate::boundary`],
//! beyond both), exactly as for the irradiance.
//!
//! A diffuse `f_r = ρ/π` gives back `ρ/π E` of equation 2.2 exactly, so the
//! diffuse part of a blended material is the one the irradiance gives. A
//! material with a diffuse map has `ρ_d ⊙ t(uv)` in place of its Lambertian
//! part's `ρ_d` at a vertex of texture coordinates `uv`: `f_r` is shifted by
//! `(t − 1) ⊙ ρ_d / π` there. The
//! BRDF is evaluated as `f_r(ωi, ωo)` in the vertex's shading frame, the
//! order non-reciprocal models (Phong) need.

use glam::{DVec3, Vec3};
use lustre_brdf::{BoxedBrdf, Brdf};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, MeshId, Rgb, Scene, triangle_area};
use rayon::prelude::*;

use crate::boundary::{DiscPattern, Surfaces};
use crate::error::{DensityError, Result};
use crate::glossy::{IncidentRay, RayList, glossy_meshes};
use crate::kdtree::{KdTree, Neighbour};
use crate::ray_set::{RaySegment, RaySet};

/// The incident ray of an impact in world coordinates (section 2.10): `ωi = −direction`, the direction back towards the light side, and the power.
fn world_incident(segment: &RaySegment) -> IncidentRay {
    IncidentRay {
        wi: -segment.direction,
        power: segment.power,
    }
}

/// One term of equation 2.1 at a vertex with shading frame `frame` and local eye direction `wo`: `f_r(ωi, ωo) φ`, `ωi` the world incident direction; with a diffuse map, `f_r` is the textured `f_r + shift` of [`lustre_geometry::Material::diffuse_shift`] where the Lambertian part lives (both directions above the surface).
fn term(
    brdf: &dyn Brdf,
    frame: &Frame,
    wo: Vec3,
    wi: Vec3,
    power: Rgb,
    shift: Option<Rgb>,
) -> DVec3 {
    let wi = frame.to_local(wi);
    let mut f = brdf.eval(wi, wo);
    if let Some(shift) = shift {
        if wi.z > 0.0 && wo.z > 0.0 {
            f = (f + shift).max(Rgb::ZERO);
        }
    }
    (f * power).as_dvec3()
}

/// The local eye direction at a vertex, `None` for a degenerate normal or an eye on the vertex.
fn view_frame(normal: Vec3, x: Vec3, eye: Vec3) -> Option<(Frame, Vec3)> {
    let n = normal.normalize_or_zero();
    let wo = (eye - x).normalize_or_zero();
    if n == Vec3::ZERO || wo == Vec3::ZERO {
        return None;
    }
    let frame = Frame::from_normal(n);
    let wo = frame.to_local(wo);
    Some((frame, wo))
}

/// The BRDF of a mesh's material (`brdfs` from `lustre_photon::trace::scene_brdfs`); an error names the material without one.
fn mesh_brdf<'a>(scene: &Scene, brdfs: &'a [BoxedBrdf], mesh: MeshId) -> Result<&'a BoxedBrdf> {
    let material = scene.meshes()[mesh as usize].material;
    brdfs
        .get(material as usize)
        .ok_or_else(|| DensityError::InvalidOption {
            option: "brdfs",
            message: format!("no BRDF for material {material}"),
        })
}

/// Impact Count's per-triangle impact lists of the glossy meshes (section 2.5.1's per-triangle `Add`/`Substract`, kept as ray lists as section 2.10 keeps DETP's), for the view-dependent estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleImpacts {
    /// Impacts per scene-wide triangle (world incident directions), empty for triangles of the other meshes.
    lists: Vec<RayList>,
    /// World area of every scene-wide triangle (rigid motions keep it).
    area: Vec<f64>,
    /// The meshes holding lists.
    meshes: Vec<MeshId>,
}

impl TriangleImpacts {
    /// The lists of the triangles of `meshes` from every impact of the ray set (figure 2.3, first frame). Fails on a mesh id that does not exist.
    pub fn build(scene: &Scene, rays: &RaySet, meshes: &[MeshId]) -> Result<Self> {
        if let Some(&m) = meshes.iter().find(|&&m| m as usize >= scene.meshes().len()) {
            return Err(DensityError::InvalidOption {
                option: "meshes",
                message: format!("mesh {m} does not exist"),
            });
        }
        let n = scene.triangle_count();
        let mut area = vec![0.0f64; n];
        let mut kept = vec![false; n];
        for (m, mesh) in scene.meshes().iter().enumerate() {
            let positions = scene.world_positions(m as MeshId);
            let glossy = meshes.contains(&(m as MeshId));
            for (t, idx) in mesh.indices.iter().enumerate() {
                let id = scene.triangle_id(m as MeshId, t as u32) as usize;
                area[id] = triangle_area(idx.map(|i| positions[i as usize])) as f64;
                kept[id] = glossy;
            }
        }
        let mut rays_of: Vec<Vec<IncidentRay>> = vec![Vec::new(); n];
        for (segment, hit) in rays.impacts() {
            let t = hit.triangle as usize;
            if kept.get(t).copied().unwrap_or(false) {
                rays_of[t].push(world_incident(segment));
            }
        }
        Ok(Self {
            lists: rays_of.iter().map(|r| RayList::from_rays(r)).collect(),
            area,
            meshes: meshes.to_vec(),
        })
    }

    /// One frame's update (figure 2.4 on the lists, as section 2.10 updates DETP's): the Old Rays' impacts leave their triangle's list, the New Rays' join it. Returns the Old Rays' impacts that were not in their list (zero for a consistent update).
    pub fn update(&mut self, old: &[RaySegment], new: &[RaySegment]) -> usize {
        let mut missing = 0;
        for s in old {
            if let Some(list) = self.list_of(s)
                && !list.remove(&world_incident(s))
            {
                missing += 1;
            }
        }
        for s in new {
            if let Some(list) = self.list_of(s) {
                list.insert(world_incident(s));
            }
        }
        missing
    }

    /// The list of the triangle a segment ends on, when that triangle's mesh is kept.
    fn list_of(&mut self, s: &RaySegment) -> Option<&mut RayList> {
        let hit = s.hit?;
        if !self.meshes.contains(&hit.mesh) {
            return None;
        }
        self.lists.get_mut(hit.triangle as usize)
    }

    /// The impacts on one scene-wide triangle.
    pub fn impacts(&self, triangle: usize) -> &[IncidentRay] {
        self.lists.get(triangle).map_or(&[], |l| l.rays())
    }

    /// Impact Count's view-dependent radiance towards `eye` at every vertex of the kept meshes, `L_v = Σ_{t∋v} Σ_{j∈t} f_r(ωi_j, ωo) φ_j / Σ_{t∋v} A_t` (section 1.2 with equation 2.1), `[mesh][vertex]`, empty for the other meshes. Fails when a kept mesh's material has no BRDF.
    pub fn radiance(&self, scene: &Scene, brdfs: &[BoxedBrdf], eye: Vec3) -> Result<Vec<Vec<Rgb>>> {
        (0..scene.meshes().len() as MeshId)
            .map(|m| {
                if !self.meshes.contains(&m) {
                    return Ok(Vec::new());
                }
                let brdf = mesh_brdf(scene, brdfs, m)?.as_ref();
                let mesh = &scene.meshes()[m as usize];
                let material = scene.materials().get(mesh.material as usize);
                let positions = scene.world_positions(m);
                let normals = scene.world_normals(m);
                // The triangles meeting at each vertex, in triangle order (a fixed summation order).
                let mut around: Vec<Vec<usize>> = vec![Vec::new(); positions.len()];
                for (t, idx) in mesh.indices.iter().enumerate() {
                    let id = scene.triangle_id(m, t as u32) as usize;
                    for &v in idx {
                        around[v as usize].push(id);
                    }
                }
                Ok(positions
                    .par_iter()
                    .zip(normals.par_iter())
                    .zip(around.par_iter())
                    .zip(mesh.uvs.par_iter())
                    .map(|(((&x, &n), tris), &uv)| {
                        let Some((frame, wo)) = view_frame(n, x, eye) else {
                            return Rgb::ZERO;
                        };
                        let shift = material.and_then(|m| m.diffuse_shift(uv));
                        let mut sum = DVec3::ZERO;
                        let mut area = 0.0f64;
                        for &t in tris {
                            area += self.area[t];
                            for r in self.impacts(t) {
                                sum += term(brdf, &frame, wo, r.wi, r.power, shift);
                            }
                        }
                        if area > 0.0 {
                            (sum / area).as_vec3()
                        } else {
                            Rgb::ZERO
                        }
                    })
                    .collect())
            })
            .collect()
    }
}

/// Smallest cosine between an impact's surface normal (turned to the side the photon arrived on) and the vertex normal for the impact to count in a Photon Maps estimate (Jensen, "Realistic Image Synthesis Using Photon Mapping", 2001, the radiance estimate; beyond García et al.'s text).
pub const NORMAL_FILTER_COSINE: f32 = 0.9;

/// Largest radius of the filtered search, in units of the unfiltered `k`-th nearest radius (Jensen 2001's maximum search distance): where fewer than `k` compatible impacts lie within it, the estimate is their power over the area of that disc.
pub const MAX_RADIUS_FACTOR: f32 = 3.0;

/// The impacts of a ray set in a kd-tree with their powers, world incident directions and surface sides (Jensen's photon map, section 1.2).
///
/// The `k`-nearest search keeps only the impacts *compatible* with the
/// query's surface: those whose geometric normal, turned towards the side the
/// photon arrived from, makes a cosine of at least [`NORMAL_FILTER_COSINE`]
/// with the vertex normal. This is Jensen's practice (Jensen 2001, radiance
/// estimate: photons on other surfaces or arriving from behind are
/// discarded), not part of García, Ureña & Lastra's section 1.2: without it
/// the sphere around a vertex near an edge gathers the impacts of the
/// adjoining face (the lit top of a box brightens the top of its sides, the
/// floor brightens the foot of the walls). The search stops at
/// [`MAX_RADIUS_FACTOR`] times the unfiltered `k`-th radius. A vertex with a
/// zero normal keeps every impact. The kd-tree keeps each impact's turned
/// normal and skips the subtrees where none passes the filter
/// ([`KdTree::nearest_facing`]).
///
/// The estimates divide by the area of the disc of radius `r_k` that lies on
/// surfaces passing the same filter, measured in the scene given as
/// [`Surfaces`] (the boundary correction, [`crate::boundary`]): half the disc
/// on an edge against a wall, a quarter in a corner, so a vertex there is not
/// a half or a quarter as bright as it should be. Given no surfaces they
/// divide by `π r_k²`, García et al.'s text.
#[derive(Debug, Clone)]
pub struct ImpactMap {
    tree: Option<KdTree>,
    /// The probes of the boundary correction ([`crate::boundary`]).
    pattern: DiscPattern,
    powers: Vec<Rgb>,
    incident: Vec<Vec3>,
}

impl ImpactMap {
    /// The map of every impact of the ray set; empty when there is none or an impact is not finite.
    pub fn build(rays: &RaySet) -> Self {
        Self::try_build(rays).unwrap_or(Self {
            tree: None,
            pattern: DiscPattern::default(),
            powers: Vec::new(),
            incident: Vec::new(),
        })
    }

    /// The map of every impact of the ray set; fails on a non-finite impact position or normal.
    pub fn try_build(rays: &RaySet) -> Result<Self> {
        let mut positions = Vec::new();
        let mut powers = Vec::new();
        let mut incident = Vec::new();
        let mut sides = Vec::new();
        for (s, h) in rays.impacts() {
            positions.push(h.position);
            powers.push(s.power);
            incident.push(-s.direction);
            sides.push(if h.normal.dot(s.direction) > 0.0 {
                -h.normal
            } else {
                h.normal
            });
        }
        Ok(Self {
            tree: Some(KdTree::build_oriented(&positions, &sides)?),
            pattern: DiscPattern::default(),
            powers,
            incident,
        })
    }

    /// Photon Maps irradiance at `x` with unit normal `normal` (section 1.2; section 2.9.1, `PME = E / (π R²)`): `Σ φ_j / A` over the `k` nearest compatible impacts ([`ImpactMap`]), `A` the area of compatible surface within `r_k` probed in `surfaces` ([`crate::boundary`]), or `π r_k²` without them (García et al.'s text); zero where no impact lies at a positive distance.
    pub fn irradiance(
        &self,
        surfaces: Option<&dyn Surfaces>,
        x: Vec3,
        normal: Vec3,
        k: usize,
    ) -> DVec3 {
        self.weighted(surfaces, x, normal, k, |j| self.powers[j].as_dvec3())
    }

    /// Jensen's radiance estimate at `x` towards the world direction `eye − x` (section 1.2 with equation 2.1): `Σ f_r(ωi_j, ωo) φ_j / A` over the `k` nearest compatible impacts ([`ImpactMap`]), in the shading frame of `normal`, `A` as in [`ImpactMap::irradiance`]; zero where no impact lies at a positive distance or the normal is degenerate.
    pub fn radiance(
        &self,
        surfaces: Option<&dyn Surfaces>,
        brdf: &dyn Brdf,
        x: Vec3,
        normal: Vec3,
        eye: Vec3,
        k: usize,
    ) -> DVec3 {
        self.radiance_shifted(surfaces, brdf, None, x, normal, eye, k)
    }

    /// [`ImpactMap::radiance`] with the BRDF shifted by a diffuse map's `shift` ([`lustre_geometry::Material::diffuse_shift`]).
    fn radiance_shifted(
        &self,
        surfaces: Option<&dyn Surfaces>,
        brdf: &dyn Brdf,
        shift: Option<Rgb>,
        x: Vec3,
        normal: Vec3,
        eye: Vec3,
        k: usize,
    ) -> DVec3 {
        let Some((frame, wo)) = view_frame(normal, x, eye) else {
            return DVec3::ZERO;
        };
        self.weighted(surfaces, x, normal, k, |j| {
            term(brdf, &frame, wo, self.incident[j], self.powers[j], shift)
        })
    }

    /// The `k` impacts nearest to `x` among those compatible with `normal` and the squared radius of their disc (the `k`-th's distance, or the maximum search distance where fewer lie within it).
    fn nearest(&self, x: Vec3, normal: Vec3, k: usize) -> (Vec<Neighbour>, f32) {
        let Some(tree) = &self.tree else {
            return (Vec::new(), 0.0);
        };
        let n = normal.normalize_or_zero();
        if n == Vec3::ZERO {
            let nearest = tree.nearest(x, k);
            let r2 = nearest.last().map_or(0.0, |f| f.distance_squared);
            return (nearest, r2);
        }
        // Jensen's maximum search distance, relative to the unfiltered k-th radius: it bounds the search where few impacts are compatible (a face no photon reaches would otherwise scan every impact); fewer than k within it estimate over its whole disc.
        let search = tree.nearest_facing(
            x,
            k,
            MAX_RADIUS_FACTOR * MAX_RADIUS_FACTOR,
            n,
            NORMAL_FILTER_COSINE,
        );
        let r2 = if search.found.len() < search.unfiltered {
            search.max_squared
        } else {
            search.found.last().map_or(0.0, |f| f.distance_squared)
        };
        (search.found, r2)
    }

    /// The area the impacts within `√r2` of `x` spread over: `π r2` times the compatible fraction probed in `surfaces` ([`crate::boundary`]), or `π r2` without them.
    fn disc_area(&self, surfaces: Option<&dyn Surfaces>, x: Vec3, normal: Vec3, r2: f32) -> f64 {
        let full = std::f64::consts::PI * r2 as f64;
        let Some(surfaces) = surfaces else {
            return full;
        };
        let n = normal.normalize_or_zero();
        full * self
            .pattern
            .fraction(surfaces, x, n, r2.sqrt())
            .unwrap_or(1.0)
    }

    /// `Σ w(j) / A` over the `k` impacts `j` nearest to `x` among those compatible with `normal`, `A` their disc's area ([`ImpactMap::disc_area`]).
    fn weighted(
        &self,
        surfaces: Option<&dyn Surfaces>,
        x: Vec3,
        normal: Vec3,
        k: usize,
        w: impl Fn(usize) -> DVec3,
    ) -> DVec3 {
        let (found, r2) = self.nearest(x, normal, k);
        if !(r2 > 0.0) || found.is_empty() {
            return DVec3::ZERO;
        }
        let sum: DVec3 = found.iter().map(|n| w(n.index as usize)).sum();
        sum / self.disc_area(surfaces, x, normal, r2)
    }

    /// Jensen's radiance estimate towards `eye` at every vertex of `meshes`, `[mesh][vertex]`, empty for the other meshes, each disc's area probed in `surfaces` as in [`ImpactMap::radiance`]. Fails when a mesh's material has no BRDF.
    pub fn mesh_radiance(
        &self,
        surfaces: Option<&dyn Surfaces>,
        scene: &Scene,
        brdfs: &[BoxedBrdf],
        meshes: &[MeshId],
        eye: Vec3,
        k: usize,
    ) -> Result<Vec<Vec<Rgb>>> {
        (0..scene.meshes().len() as MeshId)
            .map(|m| {
                if !meshes.contains(&m) {
                    return Ok(Vec::new());
                }
                let brdf = mesh_brdf(scene, brdfs, m)?.as_ref();
                let mesh = &scene.meshes()[m as usize];
                let material = scene.materials().get(mesh.material as usize);
                let positions = scene.world_positions(m);
                let normals = scene.world_normals(m);
                Ok(positions
                    .par_iter()
                    .zip(normals.par_iter())
                    .zip(mesh.uvs.par_iter())
                    .map(|((&x, &n), &uv)| {
                        let shift = material.and_then(|m| m.diffuse_shift(uv));
                        self.radiance_shifted(surfaces, brdf, shift, x, n, eye, k)
                            .as_vec3()
                    })
                    .collect())
            })
            .collect()
    }
}

/// Impact Count's view-dependent radiance towards `eye` at every vertex of the glossy meshes ([`glossy_meshes`]) over a ray set, `[mesh][vertex]`, empty for the other meshes (section 1.2 with equation 2.1; see [`TriangleImpacts::radiance`]). Fails when a material has no BRDF.
pub fn impact_count_radiance(scene: &Scene, rays: &RaySet, eye: Vec3) -> Result<Vec<Vec<Rgb>>> {
    let brdfs = lustre_photon::trace::scene_brdfs(scene)?;
    TriangleImpacts::build(scene, rays, &glossy_meshes(scene))?.radiance(scene, &brdfs, eye)
}

/// Jensen's radiance estimate with the `k` nearest impacts towards `eye` at every vertex of the glossy meshes ([`glossy_meshes`]), `[mesh][vertex]`, empty for the other meshes, each disc's area taken on the scene's compatible surfaces (section 1.2 with equation 2.1; see [`ImpactMap::radiance`] and [`crate::boundary`]). Fails when `k` is zero or a material has no BRDF.
pub fn photon_maps_radiance(
    scene: &Scene,
    rays: &RaySet,
    k: usize,
    eye: Vec3,
) -> Result<Vec<Vec<Rgb>>> {
    if k == 0 {
        return Err(DensityError::InvalidOption {
            option: "k",
            message: "the number of nearest impacts must be at least 1".into(),
        });
    }
    let brdfs = lustre_photon::trace::scene_brdfs(scene)?;
    let bvh = Bvh::build(scene);
    ImpactMap::build(rays).mesh_radiance(Some(&bvh), scene, &brdfs, &glossy_meshes(scene), eye, k)
}
