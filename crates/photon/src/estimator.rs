//! The CPU splat estimator (section 2.2, equation 2): outgoing radiance from the photons around a point, for any view direction.
//!
//! `L(x, ω) = Σ_p f_r(x, ω_p, ω) φ_p K((x - x_p)/h) / h²`
//!
//! **Normalisation.** The paper writes `1/h` in front of the sum. With a
//! unit-volume *2D* kernel `K` (Silverman's `K₂`), `K((x - x_p)/h)`
//! integrates to `h²` over the surface, so dividing by `h` leaves a length
//! in the result: `φ` (W) times `f_r` (1/sr) times `1/h` (1/m) is not a
//! radiance. Dividing by `h²` makes `K(·/h)/h²` a density per m² and the
//! sum a radiance in W/(m² sr); this crate implements `1/h²`.
//!
//! The support `h` of each surface comes from equation 3, `h = C √(A/n)`,
//! with `n` the number of photons the estimator splats on that surface (all
//! of them, or only those with more than one bounce for the optimised method
//! of section 2.2.1), or is fixed by the caller. Photons are indexed per
//! surface in a [`PointGrid`]: planar surfaces by `(u, v)`, curved ones by
//! world position (the kernel then uses the straight-line distance, a good
//! approximation of the distance along the surface while `h` is small
//! against the curvature radius). Near a surface's edges part of the kernel
//! falls outside the surface and the estimate is biased low, as in the paper
//! ([`Edges::Truncated`]); [`Edges::Normalised`] divides it by the kernel's
//! mass on the surface ([`crate::edge`]), the paper's future work on the
//! appearance of polygon edges.
//!
//! **Noise on glossy surfaces.** Equation 3 keeps the expected number of
//! photons under one kernel fixed (`π C²` on a uniformly lit surface), so as
//! photons are added only the bias shrinks; the variance of each estimate
//! stays. On a diffuse surface every photon under the kernel counts and the
//! variance is small; on a glossy one only the photons arriving inside the
//! BRDF's lobe around the mirror of `ω` count, a few per cent of them, and
//! the estimate stays speckled however many photons are traced.
//! [`Support::Silverman`] shrinks `h` at Silverman's (1986) `n^(-1/6)` rate
//! instead, so that both the variance and the bias fall.
//!
//! The BRDF is evaluated in the same two-sided frame as the tracer: the
//! normal is flipped to the viewer's side, and photons that arrived on the
//! other side contribute nothing.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use lustre_brdf::BoxedBrdf;
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Hit, Material, Rgb, Scene, SurfaceId};

use crate::edge::KernelMass;
use crate::error::{PhotonError, Result};
use crate::grid::PointGrid;
use crate::hit_record::{HitRecord, PhotonMap};
use crate::kernel::{Kernel, kernel_support, kernel_support_silverman};
use crate::parameterisation::{SurfaceParam, SurfaceParams, UvMap};
use crate::tally::SplatTally;
use crate::trace::scene_brdfs;

/// Which photons are splatted (section 2.2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BounceSelection {
    /// Every photon: the full global illumination of section 2.2.
    #[default]
    All,
    /// Only photons reflected at least once (`bounce > 1`): the indirect term of the optimised method (section 2.2.1).
    Indirect,
    /// Only first hits (`bounce == 1`): the direct term the optimised method renders otherwise.
    Direct,
}

impl BounceSelection {
    /// Whether a record is selected.
    pub fn selects(&self, r: &HitRecord) -> bool {
        match self {
            Self::All => true,
            Self::Indirect => r.bounce > 1,
            Self::Direct => r.bounce == 1,
        }
    }
}

/// How the support `h` of each surface is chosen (equation 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Support {
    /// `h = C √(A/n)` per surface (equation 3); the paper uses C from 30 to 50.
    Scaled(f32),
    /// The same `h` on every surface, in metres (for tests and studies of the bias).
    Fixed(f32),
    /// `h = c √A n^(-1/6)` per surface: Silverman's (1986, section 4.3.1) rate, under which the error falls as photons are added on glossy surfaces too ([`crate::kernel::kernel_support_silverman`]).
    Silverman(f32),
    /// Equation 3's `h = C √(A/n)` (`kernel_c`) on purely diffuse surfaces and Silverman's rate `h = c √A n^(-1/6)` (`c`) on the others: the diffuse estimate keeps equation 3's small edge bias, while the glossy surfaces, where only the photons inside the BRDF lobe count, get an error that falls as photons are added.
    GlossySilverman {
        /// `C` of equation 3 on diffuse surfaces.
        kernel_c: f32,
        /// `c` of Silverman's rate on glossy surfaces.
        c: f32,
    },
}

/// How the estimate treats the edges of planar surfaces, where part of a kernel falls off the polygon (the paper's future work; [`crate::edge`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Edges {
    /// Kernels cut at the polygon's edges, as in the paper: the estimate falls to ½ along an edge and ¼ at a square corner of a uniformly lit surface.
    #[default]
    Truncated,
    /// The estimate at `x` divided by the kernel's mass on the surface around `x` ([`KernelMass`]): exact for a uniform density up to the edges.
    Normalised,
}

/// Settings of the splat estimator (section 2.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorOptions {
    /// The kernel `k` of equation 2.
    pub kernel: Kernel,
    /// The support rule (equation 3).
    pub support: Support,
    /// Which photons to splat (section 2.2.1).
    pub selection: BounceSelection,
    /// Kernels cut at polygon edges or normalised by their mass on the surface ([`crate::edge`]).
    pub edges: Edges,
}

impl Default for EstimatorOptions {
    fn default() -> Self {
        Self {
            kernel: Kernel::Silverman,
            support: Support::Scaled(40.0),
            selection: BounceSelection::All,
            edges: Edges::Truncated,
        }
    }
}

/// The photons of one surface.
#[derive(Debug, Default)]
struct SurfaceSplats {
    /// Kernel support `h`.
    h: f32,
    /// Index over `points`.
    grid: PointGrid,
    /// Incoming world directions, by photon.
    directions: Vec<Vec3>,
    /// Powers `φ` (equation 1), by photon.
    powers: Vec<Rgb>,
    /// Index-space positions, by photon.
    points: Vec<Vec3>,
    /// Unit surface normals (winding side) at the photons.
    normals: Vec<Vec3>,
    /// On a surface whose material has a diffuse map, the triangle (within the surface) each photon hit; empty on the others.
    triangles: Vec<u32>,
    /// On a surface with a diffuse map, each triangle's texture mapping (by triangle within the surface; `None` where degenerate); empty on the others.
    uv_maps: Vec<Option<UvMap>>,
}

/// One photon as a splat (sections 2.2 and 3.2): a kernel of support `h` on the plane through `position` with normal `normal`, carrying `power` that arrived from `incoming`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Splat {
    /// The surface the photon hit.
    pub surface: SurfaceId,
    /// World position of the hit.
    pub position: Vec3,
    /// Unit normal of the surface's plane (planar surfaces) or of the hit triangle (curved ones), on the winding side.
    pub normal: Vec3,
    /// Unit incoming direction, away from the surface (the BRDF's `wi`).
    pub incoming: Vec3,
    /// Photon power `φ` (equation 1).
    pub power: Rgb,
    /// Kernel support `h` of the surface (equation 3).
    pub h: f32,
    /// On a surface with a diffuse map, the texture mapping of the triangle the photon hit, by which the splat reads the map at each point it covers; `None` on the others.
    pub uv_map: Option<UvMap>,
}

/// Equation 2 on the CPU, with a spatial index per surface (section 2.2).
#[derive(Debug)]
pub struct SplatEstimator {
    /// Options used.
    options: EstimatorOptions,
    /// Surface parameterisations (shared by [`SplatEstimator::with_photons`]).
    params: Arc<SurfaceParams>,
    /// Material of each surface.
    materials: Arc<Vec<u32>>,
    /// One BRDF per material (shared by [`SplatEstimator::with_photons`]).
    brdfs: Arc<Vec<BoxedBrdf>>,
    /// The materials with a diffuse map, by material (`None` for the others): each photon's BRDF reads the map at the photon.
    textured: Arc<Vec<Option<Material>>>,
    /// Photons per surface.
    surfaces: Vec<SurfaceSplats>,
    /// The kernel's mass on each planar surface, with [`Edges::Normalised`] (shared by [`SplatEstimator::with_photons`]).
    mass: Option<Arc<KernelMass>>,
}

impl SplatEstimator {
    /// Indexes the selected photons of `map` per surface of `scene` and sets each surface's support (equation 3).
    pub fn build(scene: &Scene, map: &PhotonMap, options: EstimatorOptions) -> Result<Self> {
        Self::build_counted(scene, map, options, None)
    }

    /// [`SplatEstimator::build`] for one batch of a larger map: the supports follow `tally`'s counts over the whole map (equation 3's `n`), so the estimates of the batches add up to the whole map's. The batch's light table must be the whole map's (equation 1).
    pub fn build_tallied(
        scene: &Scene,
        batch: &PhotonMap,
        options: EstimatorOptions,
        tally: &SplatTally,
    ) -> Result<Self> {
        if tally.selection != options.selection {
            return Err(PhotonError::InvalidOption {
                option: "tally",
                message: format!(
                    "counted {:?} bounces, the estimator selects {:?}",
                    tally.selection, options.selection
                ),
            });
        }
        if tally.counts.len() != scene.surfaces().len() {
            return Err(PhotonError::InvalidOption {
                option: "tally",
                message: format!(
                    "{} surfaces counted, the scene has {}",
                    tally.counts.len(),
                    scene.surfaces().len()
                ),
            });
        }
        Self::build_counted(scene, batch, options, Some(&tally.counts))
    }

    /// [`SplatEstimator::build`] with equation 3's `n` per surface from `counts` where given, else from `map`.
    fn build_counted(
        scene: &Scene,
        map: &PhotonMap,
        options: EstimatorOptions,
        counts: Option<&[usize]>,
    ) -> Result<Self> {
        match options.support {
            Support::Scaled(c) | Support::Fixed(c) | Support::Silverman(c)
                if !(c > 0.0 && c.is_finite()) =>
            {
                return Err(PhotonError::InvalidOption {
                    option: "support",
                    message: format!("{c} must be positive and finite"),
                });
            }
            Support::GlossySilverman { kernel_c, c }
                if !(kernel_c > 0.0 && kernel_c.is_finite() && c > 0.0 && c.is_finite()) =>
            {
                return Err(PhotonError::InvalidOption {
                    option: "support",
                    message: format!("C {kernel_c} and c {c} must be positive and finite"),
                });
            }
            _ => {}
        }
        let params = SurfaceParams::new(scene);
        let materials: Vec<u32> = scene.surfaces().iter().map(|s| s.material).collect();
        let textured: Vec<Option<Material>> = scene
            .materials()
            .iter()
            .map(|m| m.diffuse_map.is_some().then(|| m.clone()))
            .collect();
        let textured_surface = textured_surfaces(&materials, &textured);
        let mut surfaces =
            Self::selected_photons(&params, map, options.selection, &textured_surface)?;
        for (id, s) in surfaces.iter_mut().enumerate() {
            let n = counts.map_or(s.points.len(), |c| c[id]);
            s.h = match options.support {
                Support::Scaled(c) => kernel_support(c, params.area(id as SurfaceId), n),
                Support::Fixed(h) => h,
                Support::Silverman(c) => {
                    kernel_support_silverman(c, params.area(id as SurfaceId), n)
                }
                Support::GlossySilverman { kernel_c, c } => {
                    let area = params.area(id as SurfaceId);
                    let diffuse = scene
                        .surfaces()
                        .get(id)
                        .and_then(|surface| scene.materials().get(surface.material as usize))
                        .is_some_and(|m| m.model.is_diffuse());
                    if diffuse {
                        kernel_support(kernel_c, area, n)
                    } else {
                        kernel_support_silverman(c, area, n)
                    }
                }
            };
            s.grid = PointGrid::build(&s.points, s.h);
        }
        let mass = (options.edges == Edges::Normalised).then(|| {
            let supports: Vec<f32> = surfaces.iter().map(|s| s.h).collect();
            Arc::new(KernelMass::build(&params, &supports, options.kernel))
        });
        Ok(Self {
            options,
            materials: Arc::new(materials),
            brdfs: Arc::new(scene_brdfs(scene)?),
            textured: Arc::new(textured),
            params: Arc::new(params),
            surfaces,
            mass,
        })
    }

    /// The estimator of other photons of the same map (one batch of a file read in batches, section 2.1): this estimator's options, supports, kernel mass and BRDFs, shared rather than built again, over `map`'s selected photons. With supports from a [`SplatTally`] of the whole map ([`SplatEstimator::build_tallied`]), the batches' estimates add up to the whole map's.
    pub fn with_photons(&self, map: &PhotonMap) -> Result<Self> {
        let textured_surface = textured_surfaces(&self.materials, &self.textured);
        let mut surfaces =
            Self::selected_photons(&self.params, map, self.options.selection, &textured_surface)?;
        for (s, template) in surfaces.iter_mut().zip(&self.surfaces) {
            s.h = template.h;
            s.grid = PointGrid::build(&s.points, s.h);
        }
        Ok(Self {
            options: self.options,
            params: Arc::clone(&self.params),
            materials: Arc::clone(&self.materials),
            brdfs: Arc::clone(&self.brdfs),
            textured: Arc::clone(&self.textured),
            surfaces,
            mass: self.mass.clone(),
        })
    }

    /// The selected photons of `map` per surface of `params`, without supports or grids, with their texture coordinates on the surfaces where `textured` is true.
    fn selected_photons(
        params: &SurfaceParams,
        map: &PhotonMap,
        selection: BounceSelection,
        textured: &[bool],
    ) -> Result<Vec<SurfaceSplats>> {
        let mut surfaces: Vec<SurfaceSplats> = (0..params.len() as SurfaceId)
            .map(|id| SurfaceSplats {
                uv_maps: if textured.get(id as usize).copied().unwrap_or(false) {
                    (0..params.triangle_count(id) as u32)
                        .map(|t| params.texture_map(id, t))
                        .collect()
                } else {
                    Vec::new()
                },
                ..SurfaceSplats::default()
            })
            .collect();
        for (index, r) in map.records().iter().enumerate() {
            if !selection.selects(r) {
                continue;
            }
            let s =
                surfaces
                    .get_mut(r.surface as usize)
                    .ok_or_else(|| PhotonError::InvalidRecord {
                        index,
                        message: format!("surface {} does not exist in the scene", r.surface),
                    })?;
            let point = match params.get(r.surface) {
                Some(SurfaceParam::Planar(_)) => r.position.extend(0.0),
                _ => params
                    .world_position(r.surface, r.triangle, r.position)
                    .ok_or_else(|| PhotonError::InvalidRecord {
                        index,
                        message: format!("surface {} has no triangle {}", r.surface, r.triangle),
                    })?,
            };
            let normal = match params.get(r.surface) {
                Some(SurfaceParam::Planar(frame)) => frame.normal,
                _ => params
                    .corners(r.surface, r.triangle)
                    .map_or(Vec3::Z, |[a, b, c]| {
                        (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z)
                    }),
            };
            if textured.get(r.surface as usize).copied().unwrap_or(false) {
                if r.triangle as usize >= params.triangle_count(r.surface) {
                    return Err(PhotonError::InvalidRecord {
                        index,
                        message: format!("surface {} has no triangle {}", r.surface, r.triangle),
                    });
                }
                s.triangles.push(r.triangle);
            }
            s.points.push(point);
            s.normals.push(normal);
            s.directions.push(r.direction);
            s.powers.push(map.photon_power(r));
        }
        Ok(surfaces)
    }

    /// The options used.
    pub fn options(&self) -> &EstimatorOptions {
        &self.options
    }

    /// The kernel support `h` of a surface (equation 3; 0 for a surface without photons or that does not exist).
    pub fn support(&self, surface: SurfaceId) -> f32 {
        self.surfaces.get(surface as usize).map_or(0.0, |s| s.h)
    }

    /// The kernel's mass on each planar surface ([`Edges::Normalised`]); `None` with [`Edges::Truncated`].
    pub fn kernel_mass(&self) -> Option<&KernelMass> {
        self.mass.as_deref()
    }

    /// The divisor of the estimate at the index-space point `q` of `surface`: the kernel's mass there with [`Edges::Normalised`] on a planar surface, else 1.
    fn mass_at(&self, surface: SurfaceId, q: Vec3) -> f32 {
        // Only planar surfaces have a grid; their index-space point is (u, v, 0).
        self.mass
            .as_ref()
            .map_or(1.0, |mass| mass.at(surface, q.truncate()))
    }

    /// Number of photons splatted on a surface.
    pub fn photon_count(&self, surface: SurfaceId) -> usize {
        self.surfaces
            .get(surface as usize)
            .map_or(0, |s| s.points.len())
    }

    /// The surface parameterisations.
    pub fn params(&self) -> &SurfaceParams {
        &self.params
    }

    /// Index-space point and shading frame of a query.
    fn query_frame(
        &self,
        surface: SurfaceId,
        x: Vec3,
        normal: Vec3,
        wo: Vec3,
    ) -> Option<(Vec3, Frame)> {
        match self.params.get(surface)? {
            SurfaceParam::Planar(frame) => {
                Some((frame.to_uv(x).extend(0.0), frame.shading_frame(wo)))
            }
            SurfaceParam::Curved => {
                let n = normal.try_normalize()?;
                let n = if wo.dot(n) >= 0.0 { n } else { -n };
                Some((x, Frame::from_normal(n)))
            }
        }
    }

    /// Outgoing radiance `L(x, ω)` towards the unit direction `wo` at the point `x` of `surface` (equation 2 with the `1/h²` normalisation); `normal` is the shading normal at `x`, used on curved surfaces only. Zero for an unknown surface or a non-finite input.
    pub fn radiance(&self, surface: SurfaceId, x: Vec3, normal: Vec3, wo: Vec3) -> Rgb {
        let Some(s) = self.surfaces.get(surface as usize) else {
            return Rgb::ZERO;
        };
        let Some(brdf) = self.brdf_of(surface) else {
            return Rgb::ZERO;
        };
        let Some((q, frame)) = self.query_frame(surface, x, normal, wo) else {
            return Rgb::ZERO;
        };
        if !(s.h > 0.0) || !wo.is_finite() {
            return Rgb::ZERO;
        }
        let wo_local = frame.to_local(wo.normalize_or_zero());
        let material = self.textured_material(surface);
        let mut sum = Rgb::ZERO;
        let kernel = self.options.kernel;
        s.grid.for_each_within(q, s.h, |i, d2| {
            let k = kernel.scaled(d2, s.h);
            if k > 0.0 {
                let wi = frame.to_local(s.directions[i]);
                sum += photon_brdf(brdf, material, s, i, x, wi, wo_local) * s.powers[i] * k;
            }
        });
        sum / self.mass_at(surface, q)
    }

    /// Every selected photon as a [`Splat`], surface by surface (the preprocessing of section 2.2: one splat per photon hit, sized by its surface's `h`).
    pub fn splats(&self) -> Vec<Splat> {
        let mut out = Vec::with_capacity(self.surfaces.iter().map(|s| s.points.len()).sum());
        for (id, s) in self.surfaces.iter().enumerate() {
            let id = id as SurfaceId;
            for i in 0..s.points.len() {
                out.push(Splat {
                    surface: id,
                    position: self.world_point(id, s.points[i]),
                    normal: s.normals[i],
                    incoming: s.directions[i],
                    power: s.powers[i],
                    h: s.h,
                    uv_map: s.uv_map(i),
                });
            }
        }
        out
    }

    /// World position of an index-space point of `surface`.
    fn world_point(&self, surface: SurfaceId, p: Vec3) -> Vec3 {
        match self.params.get(surface) {
            Some(SurfaceParam::Planar(frame)) => frame.to_world(p.truncate()),
            _ => p,
        }
    }

    /// Equation 2 as the splatting of section 2.2 computes it: the BRDF of
    /// each photon evaluated once per splat, towards `eye` from the photon's
    /// own position ("the BRDF w.r.t. the viewing direction for that surface
    /// point"), rather than from `x`. The CPU counterpart of the GPU splat
    /// pass; it differs from [`SplatEstimator::radiance`] by the change of
    /// view direction across one kernel support.
    pub fn radiance_splatted(&self, surface: SurfaceId, x: Vec3, normal: Vec3, eye: Vec3) -> Rgb {
        let Some(s) = self.surfaces.get(surface as usize) else {
            return Rgb::ZERO;
        };
        let Some(brdf) = self.brdf_of(surface) else {
            return Rgb::ZERO;
        };
        let Some((q, _)) = self.query_frame(surface, x, normal, eye - x) else {
            return Rgb::ZERO;
        };
        if !(s.h > 0.0) || !eye.is_finite() {
            return Rgb::ZERO;
        }
        let material = self.textured_material(surface);
        let mut sum = Rgb::ZERO;
        let kernel = self.options.kernel;
        s.grid.for_each_within(q, s.h, |i, d2| {
            let k = kernel.scaled(d2, s.h);
            if k > 0.0 {
                let p = self.world_point(surface, s.points[i]);
                let wo = (eye - p).normalize_or_zero();
                let n = if wo.dot(s.normals[i]) >= 0.0 {
                    s.normals[i]
                } else {
                    -s.normals[i]
                };
                let frame = Frame::from_normal(n);
                let (wi, wo) = (frame.to_local(s.directions[i]), frame.to_local(wo));
                sum += photon_brdf(brdf, material, s, i, x, wi, wo) * s.powers[i] * k;
            }
        });
        sum / self.mass_at(surface, q)
    }

    /// [`SplatEstimator::radiance`] at a ray hit, towards the viewer along `wo`.
    pub fn radiance_at_hit(&self, hit: &Hit, wo: Vec3) -> Rgb {
        self.radiance(hit.surface, hit.position, hit.shading_normal, wo)
    }

    /// Equation 2 summed over every photon of the surface without the index: the reference the index is tested against.
    pub fn radiance_brute_force(&self, surface: SurfaceId, x: Vec3, normal: Vec3, wo: Vec3) -> Rgb {
        let (Some(s), Some(brdf), Some((q, frame))) = (
            self.surfaces.get(surface as usize),
            self.brdf_of(surface),
            self.query_frame(surface, x, normal, wo),
        ) else {
            return Rgb::ZERO;
        };
        let wo_local = frame.to_local(wo.normalize_or_zero());
        let material = self.textured_material(surface);
        let mut sum = Rgb::ZERO;
        for i in 0..s.points.len() {
            let k = self
                .options
                .kernel
                .scaled((s.points[i] - q).length_squared(), s.h);
            if k > 0.0 {
                let wi = frame.to_local(s.directions[i]);
                sum += photon_brdf(brdf, material, s, i, x, wi, wo_local) * s.powers[i] * k;
            }
        }
        sum / self.mass_at(surface, q)
    }

    /// Irradiance-like density `Σ φ_p K/h²` (W/m², no BRDF) at `x`: what a diffuse surface of albedo ρ turns into radiance ρ/π times this.
    pub fn flux_density(&self, surface: SurfaceId, x: Vec3, normal: Vec3, side: Vec3) -> Rgb {
        let Some(s) = self.surfaces.get(surface as usize) else {
            return Rgb::ZERO;
        };
        let Some((q, frame)) = self.query_frame(surface, x, normal, side) else {
            return Rgb::ZERO;
        };
        let mut sum = Rgb::ZERO;
        s.grid.for_each_within(q, s.h, |i, d2| {
            if frame.to_local(s.directions[i]).z > 0.0 {
                sum += s.powers[i] * self.options.kernel.scaled(d2, s.h);
            }
        });
        sum / self.mass_at(surface, q)
    }

    /// The BRDF of a surface.
    fn brdf_of(&self, surface: SurfaceId) -> Option<&BoxedBrdf> {
        self.brdfs
            .get(*self.materials.get(surface as usize)? as usize)
    }

    /// The material of a surface when it has a diffuse map.
    fn textured_material(&self, surface: SurfaceId) -> Option<&Material> {
        self.textured
            .get(*self.materials.get(surface as usize)? as usize)?
            .as_ref()
    }

    /// The `(u, v)` of a world point on a planar surface (for callers that build query grids).
    pub fn planar_uv(&self, surface: SurfaceId, x: Vec3) -> Option<Vec2> {
        match self.params.get(surface)? {
            SurfaceParam::Planar(frame) => Some(frame.to_uv(x)),
            SurfaceParam::Curved => None,
        }
    }
}

/// Whether each surface's material (`materials`, by surface) has a diffuse map (`textured`, by material).
fn textured_surfaces(materials: &[u32], textured: &[Option<Material>]) -> Vec<bool> {
    materials
        .iter()
        .map(|&m| textured.get(m as usize).is_some_and(Option::is_some))
        .collect()
}

impl SurfaceSplats {
    /// The texture mapping of the triangle photon `i` hit, on a surface with a diffuse map.
    fn uv_map(&self, i: usize) -> Option<UvMap> {
        *self.uv_maps.get(*self.triangles.get(i)? as usize)?
    }
}

/// The BRDF of photon `i` of `s` at the point `x` between the local
/// directions `wi` and `wo`: `brdf` itself, plus on a textured `material`
/// the diffuse map's change `(t(uv(x)) − 1) ⊙ ρ_d / π` where the Lambertian
/// part lives (both directions above the surface). The map is read at `x`,
/// not at the photon: the kernel estimates the light arriving around `x`
/// and the surface at `x` reflects it, so the map stays as sharp as the
/// pixels that show it while the rest of the BRDF is the photon's, once per
/// splat (section 2.2). `uv(x)` is the photon's triangle's mapping
/// extended over its plane ([`UvMap`]): exact across the triangle and the
/// neighbours that share its affine mapping, within a kernel support `h`
/// of the true coordinates on curved meshes and across UV seams.
fn photon_brdf(
    brdf: &BoxedBrdf,
    material: Option<&Material>,
    s: &SurfaceSplats,
    i: usize,
    x: Vec3,
    wi: Vec3,
    wo: Vec3,
) -> Rgb {
    let f = brdf.eval(wi, wo);
    match (material, s.uv_map(i)) {
        (Some(material), Some(map)) if wi.z > 0.0 && wo.z > 0.0 => material
            .diffuse_shift(map.at(x))
            .map_or(f, |shift| (f + shift).max(Rgb::ZERO)),
        _ => f,
    }
}
