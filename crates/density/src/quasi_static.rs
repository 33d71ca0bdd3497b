//! The quasi-static loop of section 2: a first frame traced and estimated in full (figures 2.1 and 2.3), then, each time the mobile objects move, the ray set recalculated (figure 2.2) and the irradiance updated incrementally on static vertices (equations 2.4–2.15; figure 2.4 for Impact Count) and in full on the mobile objects' vertices (section 2.5.2).

use std::borrow::Cow;
use std::sync::{Mutex, OnceLock, PoisonError};
use std::time::{Duration, Instant};

use glam::{Affine3A, DVec3, Vec3};
use lustre_geometry::{Aabb, MeshId, ObjectId, Rgb, Scene, triangle_area};
use lustre_photon::trace::scene_brdfs;
use rayon::prelude::*;

use crate::VertexIrradiance;
use crate::accel::{Acceleration, DiscSet, DiscSetOptions, PreTest, mean_edge};
use crate::artifact::{ArtifactOptions, inward_directions, mesh_triangles, reachable_area_near};
use crate::detp::{Disc, segment_meets_box};
use crate::error::{DensityError, Result};
use crate::glossy::{GlossyMode, GlossyVertices, glossy_meshes};
use crate::path_cells::PathCells;
use crate::points::{EstimationPoint, EstimationPoints};
use crate::radiance::{ImpactMap, TriangleImpacts};
use crate::ray_set::{PrimaryRay, RaySegment, RaySet, RaySetOptions, trace_ray_set_in};
use crate::triangle_grid::TriangleGrid;
use crate::update::{RayUpdate, update_ray_set, update_ray_set_paths};
use crate::world::World;

/// The density estimator a [`QuasiStatic`] keeps up to date (section 3.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Estimator {
    /// Impact Count (section 1.2), updated per triangle (figure 2.4).
    ImpactCount,
    /// Photon Maps with the `k` nearest impacts (section 1.2), estimated again in full every frame (section 2.5.2), each disc's area taken on the frame's surfaces, the mobile objects at their pose ([`crate::boundary`]).
    PhotonMaps {
        /// Nearest impacts per estimate.
        k: usize,
    },
    /// Density Estimation on the Tangent Plane with discs of radius `radius` (section 1.2), incremental on static vertices (equation 2.4).
    Detp {
        /// Disc radius in metres.
        radius: f32,
    },
}

impl Estimator {
    /// The estimator's short name: `detp`, `impact` or `photonmap`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Detp { .. } => "detp",
            Self::ImpactCount => "impact",
            Self::PhotonMaps { .. } => "photonmap",
        }
    }
}

/// Settings of a [`QuasiStatic`] simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuasiStaticOptions {
    /// The photosimulation (figure 2.1).
    pub rays: RaySetOptions,
    /// The density estimator.
    pub estimator: Estimator,
    /// Artifact control of DETP (section 1.2.1): reachable disc areas (of the diffuse discs, and of the glossy discs of glossy vertices) and the concave extension of [`RaySetOptions::extension`] (set to `max_extension` times the larger radius); `None` for plain DETP. Static vertices' areas are measured once against the static scene, the mobile objects' every frame.
    pub artifact: Option<ArtifactOptions>,
    /// DETP's disc radius for the ray lists of glossy vertices (section 2.10; beyond the paper, which uses one radius): the non-diffuse part of their BRDF is estimated on discs of this radius ([`GlossyVertices::lobe_radiance`]), the diffuse part `ρ/π E` from the irradiance on the estimator's discs; `None` uses the estimator's radius for both. Positive and finite.
    pub glossy_radius: Option<f32>,
    /// View-dependent estimate of glossy vertices (section 2.10): DETP's per-vertex ray lists in the given store, updated with OldRays and NewRays on static vertices and rebuilt on mobile ones; Impact Count's per-triangle impact lists updated with OldRays and NewRays, and Photon Maps' radiance estimate over the frame's impacts (these two take [`GlossyMode::List`] only); `None` keeps only the irradiance.
    pub glossy: Option<GlossyMode>,
    /// How DETP finds the rays crossing each disc (sections 2.6–2.7, and the segment grid beyond the paper); `None` picks disc indexing tuned by the radius and the scene's mean edge ([`Acceleration::tuned_disc_index`]), which suits both the frame's few changed rays against every static disc and every ray against the mobile object's discs.
    pub acceleration: Option<Acceleration>,
    /// DETP's pre-intersection test (section 2.8).
    pub pretest: PreTest,
    /// Most rays the glossy vertices' lists may hold in all (a memory bound, [`crate::glossy::BYTES_PER_STORED_RAY`] each); more fails with [`DensityError::TooManyRays`] before the lists are built. `None`: no bound.
    pub max_glossy_rays: Option<u64>,
}

impl QuasiStaticOptions {
    /// DETP, Impact Count or Photon Maps over `photons` photons with the default settings: no artifact control, no glossy estimate, tuned disc indexing, no pre-test.
    pub fn new(estimator: Estimator, photons: u64) -> Self {
        Self {
            rays: RaySetOptions {
                photons,
                ..RaySetOptions::default()
            },
            estimator,
            artifact: None,
            glossy_radius: None,
            glossy: None,
            acceleration: None,
            pretest: PreTest::None,
            max_glossy_rays: None,
        }
    }
}

/// Times and counts of one frame (the paper's "Photosimulation update" and "Illumination"/"Radiosity recalculation" columns).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Ray-set recalculation (figure 2.2).
    pub photosimulation: Duration,
    /// Radiosity update (equation 2.4, figure 2.4, or the full estimate on mobile vertices).
    pub radiosity: Duration,
    /// Segments in OldRays.
    pub old_rays: usize,
    /// Segments in NewRays.
    pub new_rays: usize,
    /// Primary rays whose paths were recalculated.
    pub recalculated: usize,
}

/// The static glossy vertices' lobe radiance towards the last eye asked for, and which vertices' lists changed since (beyond the paper: section 2.10 recomputes the view-dependent radiance when the camera moves; while it rests, a frame recomputes only the vertices an Old or New Ray crossed, and the others keep theirs exactly). Behind a lock so that [`QuasiStatic::glossy_radiance`] can fill it through `&self`.
#[derive(Debug, Clone, Default)]
struct LobeCache(Locked<Option<CachedLobe>>);

#[derive(Debug, Clone)]
struct CachedLobe {
    eye: Vec3,
    lobe: Vec<Vec<Rgb>>,
    stale: Vec<(MeshId, u32)>,
}

impl LobeCache {
    fn lock(&self) -> std::sync::MutexGuard<'_, Option<CachedLobe>> {
        self.0.lock()
    }

    /// The eye of the cached radiance, if any.
    fn eye(&mut self) -> Option<Vec3> {
        self.0.get_mut().as_ref().map(|c| c.eye)
    }

    /// Marks vertices whose lists changed.
    fn mark_stale(&self, changed: &[(MeshId, u32)]) {
        if let Some(cache) = self.lock().as_mut() {
            cache.stale.extend_from_slice(changed);
        }
    }

    /// The lobe radiance towards `eye`: the cached one with its stale vertices recomputed by `some`, or all of it from `all` when the eye moved.
    fn get(
        &self,
        eye: Vec3,
        all: impl FnOnce() -> Result<Vec<Vec<Rgb>>>,
        some: impl FnOnce(&[(MeshId, u32)]) -> Result<Vec<Rgb>>,
    ) -> Result<Vec<Vec<Rgb>>> {
        let mut guard = self.lock();
        match guard.as_mut() {
            Some(cache) if cache.eye == eye => {
                cache.stale.sort_unstable();
                cache.stale.dedup();
                let values = some(&cache.stale)?;
                for (&(m, v), value) in cache.stale.iter().zip(values) {
                    cache.lobe[m as usize][v as usize] = value;
                }
                cache.stale.clear();
                Ok(cache.lobe.clone())
            }
            _ => {
                let lobe = all()?;
                *guard = Some(CachedLobe {
                    eye,
                    lobe: lobe.clone(),
                    stale: Vec::new(),
                });
                Ok(lobe)
            }
        }
    }
}

/// A value behind a lock, cloned by cloning the value, so that [`QuasiStatic::glossy_radiance`] can change it through `&self`: the static glossy vertices (the rays they deferred while the eye was behind them, [`GlossyVertices::update_towards`]) and the [`LobeCache`].
#[derive(Debug, Default)]
struct Locked<T>(Mutex<T>);

impl<T: Clone> Clone for Locked<T> {
    fn clone(&self) -> Self {
        Self(Mutex::new(self.lock().clone()))
    }
}

impl<T> Locked<T> {
    fn lock(&self) -> std::sync::MutexGuard<'_, T> {
        // Only whole updates are made under the lock (a frame's rays, a cache replaced whole), so a panic elsewhere
        // leaves the value consistent.
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn get_mut(&mut self) -> &mut T {
        self.0.get_mut().unwrap_or_else(PoisonError::into_inner)
    }
}

/// What each estimator keeps between frames.
#[derive(Debug, Clone)]
enum State {
    /// Impact power `Σ φ` and area per scene-wide triangle (figure 2.4's `Add`/`Substract`).
    ImpactCount { power: Vec<DVec3>, area: Vec<f64> },
    /// Nothing: Photon Maps is estimated in full each frame.
    PhotonMaps { k: usize },
    /// Disc sums `Σ φ` per estimation point (equation 2.8), each point's disc area (`π r²`, or its reachable area under artifact control), and the disc radius.
    Detp {
        sums: Vec<DVec3>,
        areas: Vec<f64>,
        radius: f32,
    },
}

/// A static scene with mobile objects and its view-independent irradiance, kept up to date as the objects move (section 2).
#[derive(Debug, Clone)]
pub struct QuasiStatic {
    scene: Scene,
    world: World,
    mobile: Vec<ObjectId>,
    rays: RaySet,
    points: EstimationPoints,
    options: QuasiStaticOptions,
    slack: f32,
    state: State,
    first_frame: FrameStats,
    /// Glossy vertices of static meshes (updated) and of mobile meshes (rebuilt each frame), section 2.10.
    glossy: Option<(Locked<GlossyVertices>, GlossyVertices)>,
    /// Irradiance per estimation point of the current frame (computed within the frame's radiosity time).
    irradiance: Vec<DVec3>,
    /// Impact Count's per-triangle impact lists of the glossy meshes (section 2.10 with figure 2.4), when the glossy option is on.
    triangle_impacts: Option<TriangleImpacts>,
    /// Photon Maps' impacts of the current frame in a kd-tree (section 1.2), rebuilt every frame.
    impact_map: Option<ImpactMap>,
    /// DETP's discs at the static points (fixed) and at the mobile points (moved each frame), with their acceleration structures.
    disc_sets: Option<(DiscSet, DiscSet)>,
    /// The static glossy vertices' lobe radiance towards the last eye.
    lobe_cache: LobeCache,
    /// The cells each path passes, so that a frame visits only the paths near the mobile objects (beyond the paper);
    /// `None` without mobile objects, whose simulation never moves.
    paths: Option<PathCells>,
    /// Whether `paths` spans the reach of the mobile objects' paths rather than the whole scene.
    paths_focused: bool,
    /// The static scene's triangles binned for the reachable areas of artifact control (section 1.2.1), per disc
    /// radius (the points' and the glossy vertices'), built on first use: the static scene never moves.
    static_grids: [OnceLock<(f32, TriangleGrid)>; 2],
}

impl QuasiStatic {
    /// The first frame (figures 2.1 and 2.3): traces the ray set with the objects `mobile` at the scene's current pose and estimates every vertex. Fails on an invalid option, an unknown or emitting mobile object, or a material without a BRDF.
    pub fn new(scene: Scene, mobile: &[ObjectId], options: QuasiStaticOptions) -> Result<Self> {
        match options.estimator {
            Estimator::PhotonMaps { k: 0 } => {
                return Err(DensityError::InvalidOption {
                    option: "k",
                    message: "the number of nearest impacts must be at least 1".into(),
                });
            }
            Estimator::Detp { radius } if !(radius > 0.0 && radius.is_finite()) => {
                return Err(DensityError::InvalidOption {
                    option: "radius",
                    message: format!("{radius} is not a positive finite disc radius"),
                });
            }
            _ => {}
        }
        if let Some(r) = options.glossy_radius
            && !(r > 0.0 && r.is_finite())
        {
            return Err(DensityError::InvalidOption {
                option: "glossy_radius",
                message: format!("{r} is not a positive finite disc radius"),
            });
        }
        let mut options = options;
        if let Some(mode) = options.glossy
            && !matches!(options.estimator, Estimator::Detp { .. })
            && mode != GlossyMode::List
        {
            return Err(DensityError::InvalidOption {
                option: "glossy",
                message: format!(
                    "{} keeps plain impact lists on glossy vertices; the QuadTree stores are DETP's",
                    options.estimator.name()
                ),
            });
        }
        if let Some(artifact) = options.artifact {
            let Estimator::Detp { radius } = options.estimator else {
                return Err(DensityError::InvalidOption {
                    option: "artifact",
                    message: format!(
                        "artifact control applies to DETP's discs, not to {}",
                        options.estimator.name()
                    ),
                });
            };
            artifact.validate()?;
            // Followed far enough for the larger of the two discs (section 1.2.1, concave surfaces).
            options.rays.extension = artifact.max_extension * largest_radius(&options, radius);
        }
        let world = World::new(&scene, mobile)?;
        let t0 = Instant::now();
        let rays = trace_ray_set_in(&scene, &world, &options.rays)?;
        let photosimulation = t0.elapsed();
        let points = EstimationPoints::new(&scene, &world);
        let slack = crate::accel::scene_slack(&scene);
        // Cells over the box the mobile objects' paths reach, grown by the larger disc; the whole scene without one.
        let margin = match options.estimator {
            Estimator::Detp { radius } => largest_radius(&options, radius),
            _ => 0.0,
        } + slack;
        let focus = reach_of_paths(&scene, mobile, margin);
        let paths = world
            .has_mobile()
            .then(|| PathCells::new(focus.unwrap_or_else(|| scene.bounds()), slack, &rays));
        let paths_focused = paths.is_some() && focus.is_some();
        let state = match options.estimator {
            Estimator::ImpactCount => State::ImpactCount {
                power: Vec::new(),
                area: Vec::new(),
            },
            Estimator::PhotonMaps { k } => State::PhotonMaps { k },
            Estimator::Detp { radius } => State::Detp {
                sums: Vec::new(),
                areas: Vec::new(),
                radius,
            },
        };
        let mut sim = Self {
            scene,
            world,
            mobile: mobile.to_vec(),
            rays,
            points,
            options,
            slack,
            state,
            first_frame: FrameStats::default(),
            glossy: None,
            irradiance: Vec::new(),
            triangle_impacts: None,
            impact_map: None,
            disc_sets: None,
            lobe_cache: LobeCache::default(),
            paths,
            paths_focused,
            static_grids: Default::default(),
        };
        let t1 = Instant::now();
        if let State::Detp { radius, .. } = sim.state {
            let acceleration = options.acceleration.unwrap_or_else(|| {
                Acceleration::tuned_disc_index(
                    radius,
                    mean_edge(&sim.scene, 0..sim.scene.meshes().len() as MeshId),
                )
            });
            let set_options = DiscSetOptions {
                slack: sim.slack,
                acceleration,
                pretest: options.pretest,
            };
            let first = sim.points.first_mobile;
            let count = sim.points.points.len();
            sim.disc_sets = Some((
                DiscSet::new(sim.discs(0..first, radius), set_options)?,
                DiscSet::new(sim.discs(first..count, radius), set_options)?,
            ));
            let mut areas = sim.point_areas(false, radius)?;
            areas.extend(sim.point_areas(true, radius)?);
            sim.state = State::Detp {
                sums: Vec::new(),
                areas,
                radius,
            };
        }
        sim.state = sim.full_state();
        if let State::PhotonMaps { .. } = sim.state {
            sim.impact_map = Some(ImpactMap::build(&sim.rays));
        }
        sim.irradiance = sim.irradiance_of(&sim.state);
        if options.glossy.is_some() {
            match sim.state {
                State::Detp { .. } => {
                    let fixed = sim.build_glossy(false)?;
                    let moving = sim.build_glossy(true)?;
                    sim.glossy = Some((Locked(Mutex::new(fixed)), moving));
                }
                State::ImpactCount { .. } => {
                    sim.triangle_impacts = Some(sim.build_triangle_impacts()?);
                }
                State::PhotonMaps { .. } => {}
            }
        }
        sim.first_frame = FrameStats {
            photosimulation,
            radiosity: t1.elapsed(),
            old_rays: 0,
            new_rays: sim.rays.segments().count(),
            recalculated: sim.rays.rays.len(),
        };
        Ok(sim)
    }

    /// Moves mobile objects to new transforms (relative to their rest pose) and updates the ray set and the irradiance (figure 2.2, equation 2.4). Every object named must be one of the mobile objects.
    pub fn set_pose(&mut self, transforms: &[(ObjectId, Affine3A)]) -> Result<FrameStats> {
        // Check everything first so that a refused pose leaves the simulation as it was.
        for &(object, transform) in transforms {
            if !self.mobile.contains(&object) {
                return Err(DensityError::InvalidOption {
                    option: "mobile",
                    message: format!("object #{object} is not a mobile object of this simulation"),
                });
            }
            if !transform.is_finite() {
                return Err(DensityError::InvalidOption {
                    option: "mobile",
                    message: format!("the transform of object #{object} is not finite"),
                });
            }
        }
        for &(object, transform) in transforms {
            self.scene.set_object_transform(object, transform)?;
        }
        let t0 = Instant::now();
        let before = self.world.mobile_bounds();
        self.world.move_mobile(&self.scene);
        self.points.move_mobile(&self.scene);
        // Only paths through the mobile objects' boxes, before and after the move, can change (figure 2.2); those
        // and the paths through the mobile discs' box (section 2.5.2's gather) are listed once for both passes.
        let moved = before.union(self.world.mobile_bounds());
        let discs = self.mobile_discs();
        let region = discs.as_deref().and_then(|d| disc_region(d, self.slack));
        let near_box = region.map_or(moved, |(min, max)| moved.union(Aabb { min, max }));
        if self.paths_focused
            && self
                .paths
                .as_ref()
                .is_some_and(|p| !p.covers(near_box.min, near_box.max))
        {
            // Moved off their paths' reach: cells over the whole scene from now on (every path when even those do
            // not cover a move).
            self.paths = Some(PathCells::new(self.scene.bounds(), self.slack, &self.rays));
            self.paths_focused = false;
        }
        let mut near = paths_near(self.paths.as_ref(), near_box.min, near_box.max, &self.rays);
        let listed = self.rays.rays.len();
        let update = match &near {
            Some(near) => update_ray_set_paths(
                &self.scene,
                &self.world,
                &mut self.rays,
                &self.options.rays,
                near,
            )?,
            None => update_ray_set(&self.scene, &self.world, &mut self.rays, &self.options.rays)?,
        };
        if let Some(paths) = &mut self.paths {
            paths.refresh(&self.rays, &update.primaries);
        }
        // Paths the update added, if any, have no mask yet: the gather visits them too.
        if let Some(near) = &mut near {
            near.extend(listed..self.rays.rays.len());
        }
        let photosimulation = t0.elapsed();
        let t1 = Instant::now();
        self.update_state(&update, discs.as_deref(), region, near.as_deref())?;
        if let State::PhotonMaps { .. } = self.state {
            self.impact_map = Some(ImpactMap::build(&self.rays));
        }
        self.irradiance = self.irradiance_of(&self.state);
        if let Some(lists) = &mut self.triangle_impacts {
            lists.update(&update.old, &update.new);
        }
        if self.glossy.is_some() {
            let moving = self.build_glossy(true)?;
            // Vertices facing away from the last eye asked for defer the frame's rays until an eye in front of
            // them asks (`glossy_radiance` applies them); their radiance towards that eye stays zero.
            let eye = self.lobe_cache.eye();
            if let Some((fixed, mobile)) = &mut self.glossy {
                match fixed
                    .get_mut()
                    .update_towards(&update.old, &update.new, &update.twins, eye)
                {
                    Ok((_, changed)) => self.lobe_cache.mark_stale(&changed),
                    Err(error) => {
                        // Some vertices may have changed: forget every cached radiance.
                        self.lobe_cache = LobeCache::default();
                        return Err(error);
                    }
                }
                *mobile = moving;
            }
        }
        Ok(FrameStats {
            photosimulation,
            radiosity: t1.elapsed(),
            old_rays: update.old.len(),
            new_rays: update.new.len(),
            recalculated: update.primaries.len(),
        })
    }

    /// Bytes held by the ray set (primary rays and their segments, section 2.3) and by everything else kept between frames (estimator state, points, glossy lists are not counted); the ray set's share per emitted photon is the paper's memory per photon.
    pub fn memory_bytes(&self) -> (usize, usize) {
        let rays = self.rays.rays.capacity() * size_of::<PrimaryRay>()
            + self
                .rays
                .rays
                .iter()
                .map(|r| r.segments.capacity() * size_of::<RaySegment>())
                .sum::<usize>();
        let state = match &self.state {
            State::ImpactCount { power, area } => {
                power.capacity() * size_of::<DVec3>() + area.capacity() * size_of::<f64>()
            }
            State::PhotonMaps { .. } => 0,
            State::Detp { sums, areas, .. } => {
                sums.capacity() * size_of::<DVec3>() + areas.capacity() * size_of::<f64>()
            }
        } + self.points.points.capacity() * size_of::<EstimationPoint>()
            + self.irradiance.capacity() * size_of::<DVec3>();
        (rays, state)
    }

    /// The first frame's times and counts.
    pub fn first_frame(&self) -> FrameStats {
        self.first_frame
    }

    /// The scene at its current pose.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The current ray set `S^t`.
    pub fn rays(&self) -> &RaySet {
        &self.rays
    }

    /// The world (static BVH and mobile objects).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The estimation points (section 3.4.2).
    pub fn points(&self) -> &EstimationPoints {
        &self.points
    }

    /// Irradiance `E` at each estimation point in the current frame, from the kept state.
    pub fn point_irradiance(&self) -> Vec<DVec3> {
        self.irradiance.clone()
    }

    /// Irradiance `E` at every vertex, `[mesh][vertex]`, from the kept state.
    pub fn irradiance(&self) -> VertexIrradiance {
        let e: Vec<Rgb> = self
            .point_irradiance()
            .iter()
            .map(|e| e.as_vec3())
            .collect();
        self.points.to_vertices(&e)
    }

    /// Irradiance at each estimation point computed from scratch over the current ray set (figure 2.3), for checking the incremental update.
    pub fn recompute_point_irradiance(&self) -> Vec<DVec3> {
        self.irradiance_of(&self.full_state())
    }

    /// INITIALRADIOSITYCALCULATION (figure 2.3) over the whole current ray set.
    fn full_state(&self) -> State {
        match &self.state {
            State::ImpactCount { .. } => {
                let mut power = vec![DVec3::ZERO; self.scene.triangle_count()];
                add_impacts(&mut power, self.rays.segments(), 1.0);
                let area = match &self.state {
                    // Areas are invariant under the rigid motions of section 2.2.2: keep the first pose's.
                    State::ImpactCount { area, .. } if !area.is_empty() => area.clone(),
                    _ => self.triangle_areas(),
                };
                State::ImpactCount { power, area }
            }
            State::PhotonMaps { k } => State::PhotonMaps { k: *k },
            State::Detp { radius, areas, .. } => {
                let segments: Vec<RaySegment> = self.rays.segments().copied().collect();
                let mut sums = vec![DVec3::ZERO; self.points.points.len()];
                if let Some((fixed, moving)) = &self.disc_sets {
                    let (a, b) = sums.split_at_mut(self.points.first_mobile);
                    // Built from valid discs, so only a mismatched length could fail, which the split rules out.
                    let _ = fixed.accumulate(&segments, 1.0, a);
                    let _ = moving.accumulate(&segments, 1.0, b);
                }
                State::Detp {
                    sums,
                    areas: areas.clone(),
                    radius: *radius,
                }
            }
        }
    }

    /// The DETP discs of the mobile points (section 2.5.2), when the state keeps disc sets.
    fn mobile_discs(&self) -> Option<Vec<Disc>> {
        let (State::Detp { radius, .. }, Some(_)) = (&self.state, &self.disc_sets) else {
            return None;
        };
        let points = &self.points.points[self.points.first_mobile..];
        Some(points.iter().map(|p| point_disc(p, *radius)).collect())
    }

    /// Equation 2.4 on static points and a full estimate on mobile ones (DETP); figure 2.4 (Impact Count); a full estimate (Photon Maps). `discs`: the mobile discs when there are disc sets ([`QuasiStatic::mobile_discs`]); `region`: the box round them ([`disc_region`]); `near` lists the paths that may meet that box, every path when `None`.
    fn update_state(
        &mut self,
        update: &RayUpdate,
        discs: Option<&[Disc]>,
        region: Option<(Vec3, Vec3)>,
        near: Option<&[usize]>,
    ) -> Result<()> {
        let first_mobile = self.points.first_mobile;
        let mobile_areas = match &self.state {
            State::Detp { radius, .. } if self.options.artifact.is_some() => {
                Some(self.point_areas(true, *radius)?)
            }
            _ => None,
        };
        if let (Some(discs), Some((_, moving))) = (discs, &mut self.disc_sets) {
            moving.update_discs(discs)?;
        }
        // Every segment in order, less those that miss the mobile discs' box (equal sums: a skipped segment adds
        // nothing), from the paths whose cells meet the box; gathered in parallel, in order.
        let all: Vec<RaySegment> = match (&self.state, region) {
            (State::Detp { .. }, Some((lo, hi))) => {
                let slack = self.slack;
                fn meeting(
                    r: &PrimaryRay,
                    slack: f32,
                    lo: Vec3,
                    hi: Vec3,
                ) -> impl Iterator<Item = RaySegment> + '_ {
                    r.segments
                        .iter()
                        .filter(move |s| segment_meets_box(s, slack, lo, hi))
                        .copied()
                }
                let meets = |r| meeting(r, slack, lo, hi);
                match near {
                    Some(list) => list
                        .par_iter()
                        .filter_map(|&i| self.rays.rays.get(i))
                        .flat_map_iter(meets)
                        .collect(),
                    None => self.rays.rays.par_iter().flat_map_iter(meets).collect(),
                }
            }
            _ => Vec::new(),
        };
        match &mut self.state {
            State::ImpactCount { power, .. } => {
                add_impacts(power, update.old.iter(), -1.0);
                add_impacts(power, update.new.iter(), 1.0);
            }
            State::PhotonMaps { .. } => {}
            State::Detp { sums, areas, .. } => {
                if let Some(mobile_areas) = mobile_areas {
                    areas[first_mobile..].copy_from_slice(&mobile_areas);
                }
                let Some((fixed_set, moving_set)) = &self.disc_sets else {
                    return Ok(());
                };
                let (fixed, moving) = sums.split_at_mut(first_mobile);
                // E(x, t) = E(x, t-1) + E(x; N^t) - E(x; O^t) (equation 2.4), without the twins' terms that cancel.
                fixed_set.accumulate_net(&update.old, &update.new, &update.twins, fixed)?;
                // Mobile vertices: the initial algorithm over every ray (section 2.5.2).
                moving.fill(DVec3::ZERO);
                moving_set.accumulate(&all, 1.0, moving)?;
            }
        }
        Ok(())
    }

    /// The glossy vertices of the static (`mobile` false) or mobile glossy meshes from the whole current ray set (section 2.10), on discs of the glossy radius with their areas: `π r²`, or under artifact control their reachable areas against the static scene (section 1.2.1).
    fn build_glossy(&self, mobile: bool) -> Result<GlossyVertices> {
        let (Some(mode), State::Detp { radius, .. }) = (self.options.glossy, &self.state) else {
            return Err(DensityError::InvalidOption {
                option: "glossy",
                message: "the view-dependent glossy estimate needs DETP".into(),
            });
        };
        let radius = self.options.glossy_radius.unwrap_or(*radius);
        let meshes: Vec<MeshId> = glossy_meshes(&self.scene)
            .into_iter()
            .filter(|&m| self.world.is_mobile_mesh(m) == mobile)
            .collect();
        let mut vertices = GlossyVertices::build_limited(
            &self.scene,
            &self.rays,
            radius,
            mode,
            &meshes,
            self.options.max_glossy_rays,
        )?;
        if let Some(options) = self.options.artifact
            && !meshes.is_empty()
        {
            let bvh = self.world.static_scene_bvh(&self.scene);
            let grid = self.static_grid(1, radius);
            let mut areas: Vec<Vec<f32>> = vec![Vec::new(); self.scene.meshes().len()];
            for &m in &meshes {
                let own = mesh_triangles(&self.scene, m);
                let inward = inward_directions(
                    &self.scene.world_positions(m),
                    &self.scene.world_normals(m),
                    &self.scene.meshes()[m as usize].indices,
                );
                areas[m as usize] = vertices
                    .vertices(m)
                    .par_iter()
                    .zip(inward.par_iter())
                    .map(|(v, &inward)| match v {
                        Some(v) => {
                            reachable_area_near(bvh, &grid, v.disc(), own.clone(), inward, &options)
                        }
                        None => Ok(0.0),
                    })
                    .collect::<Result<_>>()?;
            }
            vertices.set_areas(&areas)?;
        }
        Ok(vertices)
    }

    /// Radiance towards `eye` of every vertex of a glossy mesh (section 2.10, equation 2.1: on DETP's discs, `ρ/π E` from the diffuse disc plus the non-diffuse part of `f_r` on the glossy disc of [`QuasiStaticOptions::glossy_radius`], over Impact Count's triangles, or over Photon Maps' `k` nearest impacts), `[mesh][vertex]`, empty for the other meshes; `None` without the glossy option.
    pub fn glossy_radiance(&self, eye: Vec3) -> Result<Option<Vec<Vec<Rgb>>>> {
        if self.options.glossy.is_none() {
            return Ok(None);
        }
        let brdfs = scene_brdfs(&self.scene)?;
        if let Some(lists) = &self.triangle_impacts {
            return lists.radiance(&self.scene, &brdfs, eye).map(Some);
        }
        if let (State::PhotonMaps { k }, Some(map)) = (&self.state, &self.impact_map) {
            let meshes = glossy_meshes(&self.scene);
            return map
                .mesh_radiance(Some(&self.world), &self.scene, &brdfs, &meshes, eye, *k)
                .map(Some);
        }
        let Some((fixed, moving)) = &self.glossy else {
            return Ok(None);
        };
        // The rays deferred on vertices this eye sees.
        let mut fixed = fixed.lock();
        let caught_up = fixed.catch_up(eye)?;
        self.lobe_cache.mark_stale(&caught_up);
        // ρ/π E on the diffuse discs plus the non-diffuse part on the glossy discs.
        let a = self.lobe_cache.get(
            eye,
            || fixed.lobe_radiance(&brdfs, eye),
            |stale| fixed.lobe_radiance_of(&brdfs, eye, stale),
        )?;
        let b = moving.lobe_radiance(&brdfs, eye)?;
        let irradiance = self.irradiance();
        Ok(Some(
            a.into_iter()
                .zip(b)
                .enumerate()
                .map(|(m, (a, b))| {
                    let lobe = if a.is_empty() { b } else { a };
                    // ρ ⊙ t(uv) per vertex for a textured material (equation 2.2).
                    let rho = crate::vertex_reflectances(&self.scene, m as MeshId);
                    lobe.iter()
                        .zip(&irradiance[m])
                        .zip(&rho)
                        .map(|((&l, &e), &rho)| l + crate::diffuse_radiance(rho, e))
                        .collect()
                })
                .collect(),
        ))
    }

    /// Old and New Rays the static glossy vertices hold deferred (beyond the paper: frames' rays on vertices facing away from the last eye asked for, applied when an eye in front of them asks; [`GlossyVertices::update_towards`]).
    pub fn deferred_glossy_rays(&self) -> usize {
        self.glossy
            .as_ref()
            .map_or(0, |(fixed, _)| fixed.lock().deferred_rays())
    }

    /// Impact Count's per-triangle impact lists of every glossy mesh from the whole current ray set (section 2.10, first frame).
    fn build_triangle_impacts(&self) -> Result<TriangleImpacts> {
        TriangleImpacts::build(&self.scene, &self.rays, &glossy_meshes(&self.scene))
    }

    /// The glossy radiance of [`QuasiStatic::glossy_radiance`] with Impact Count's lists rebuilt from scratch over the current ray set (figure 2.3), for checking their incremental update; `None` unless the estimator is Impact Count with the glossy option.
    pub fn recompute_glossy_radiance(&self, eye: Vec3) -> Result<Option<Vec<Vec<Rgb>>>> {
        if self.triangle_impacts.is_none() {
            return Ok(None);
        }
        let brdfs = scene_brdfs(&self.scene)?;
        self.build_triangle_impacts()?
            .radiance(&self.scene, &brdfs, eye)
            .map(Some)
    }

    /// Disc areas of the static (`mobile` false) or mobile estimation points: `π r²`, or under artifact control the reachable area against the static scene (section 1.2.1).
    fn point_areas(&self, mobile: bool, radius: f32) -> Result<Vec<f64>> {
        let first = self.points.first_mobile;
        let range = if mobile {
            first..self.points.points.len()
        } else {
            0..first
        };
        let full = std::f64::consts::PI * (radius as f64).powi(2);
        let Some(options) = self.options.artifact else {
            return Ok(vec![full; range.len()]);
        };
        let bvh = self.world.static_scene_bvh(&self.scene);
        let grid = self.static_grid(0, radius);
        // Each point's inward direction (border vertices), from the first vertex that maps to it.
        let mut inward: Vec<Option<Vec3>> = vec![None; range.len()];
        for (m, mesh) in self.scene.meshes().iter().enumerate() {
            if self.world.is_mobile_mesh(m as MeshId) != mobile {
                continue;
            }
            let positions = self.scene.world_positions(m as MeshId);
            let normals = self.scene.world_normals(m as MeshId);
            let dirs = inward_directions(&positions, &normals, &mesh.indices);
            for (&p, &d) in self.points.vertex_point[m].iter().zip(&dirs) {
                inward[p as usize - range.start].get_or_insert(d);
            }
        }
        self.points.points[range.clone()]
            .par_iter()
            .zip(inward.par_iter())
            .map(|(p, inward)| {
                if p.normal == Vec3::ZERO {
                    return Ok(0.0);
                }
                let disc = Disc {
                    centre: p.position,
                    normal: p.normal,
                    radius,
                    mesh: Some(p.mesh),
                };
                let own = mesh_triangles(&self.scene, p.mesh);
                let inward = inward.unwrap_or(Vec3::ZERO);
                let area = reachable_area_near(bvh, &grid, &disc, own, inward, &options)?;
                Ok(area as f64)
            })
            .collect()
    }

    /// The static scene's [`TriangleGrid`] for discs of `radius`, from cache `slot` (0: the points', 1: the glossy
    /// vertices'), which keeps the first one built; a fresh grid when the slot holds another radius.
    fn static_grid(&self, slot: usize, radius: f32) -> Cow<'_, TriangleGrid> {
        let bvh = self.world.static_scene_bvh(&self.scene);
        let (cached, grid) =
            self.static_grids[slot].get_or_init(|| (radius, TriangleGrid::new(bvh, 2.0 * radius)));
        if *cached == radius {
            Cow::Borrowed(grid)
        } else {
            Cow::Owned(TriangleGrid::new(bvh, 2.0 * radius))
        }
    }

    /// Discs at the estimation points `range`.
    fn discs(&self, range: std::ops::Range<usize>, radius: f32) -> Vec<Disc> {
        self.points.points[range]
            .iter()
            .map(|p| point_disc(p, radius))
            .collect()
    }

    /// World area of every scene-wide triangle.
    fn triangle_areas(&self) -> Vec<f64> {
        let mut area = vec![0.0; self.scene.triangle_count()];
        for (m, mesh) in self.scene.meshes().iter().enumerate() {
            let positions = self.scene.world_positions(m as MeshId);
            for (t, idx) in mesh.indices.iter().enumerate() {
                let id = self.scene.triangle_id(m as MeshId, t as u32) as usize;
                area[id] = triangle_area(idx.map(|i| positions[i as usize])) as f64;
            }
        }
        area
    }

    /// Irradiance per estimation point from a state.
    fn irradiance_of(&self, state: &State) -> Vec<DVec3> {
        match state {
            State::ImpactCount { power, area } => {
                // E_v = Σ_t Σφ_t / Σ_t A_t over the triangles meeting at the point (section 1.2).
                let n = self.points.points.len();
                let mut p = vec![DVec3::ZERO; n];
                let mut a = vec![0.0f64; n];
                for (m, mesh) in self.scene.meshes().iter().enumerate() {
                    let map = &self.points.vertex_point[m];
                    for (t, idx) in mesh.indices.iter().enumerate() {
                        let id = self.scene.triangle_id(m as MeshId, t as u32) as usize;
                        for &v in idx {
                            let q = map[v as usize] as usize;
                            p[q] += power[id];
                            a[q] += area[id];
                        }
                    }
                }
                p.iter()
                    .zip(&a)
                    .map(|(&p, &a)| if a > 0.0 { p / a } else { DVec3::ZERO })
                    .collect()
            }
            State::PhotonMaps { k } => self.photon_maps(*k),
            State::Detp { sums, areas, .. } => sums
                .iter()
                .zip(areas)
                .map(|(&s, &a)| if a > 0.0 { s / a } else { DVec3::ZERO })
                .collect(),
        }
    }

    /// Photon Maps at every estimation point over the current impacts (section 1.2), the discs' areas probed in the world at the current pose ([`crate::boundary`]).
    fn photon_maps(&self, k: usize) -> Vec<DVec3> {
        let built;
        let map = match &self.impact_map {
            Some(map) => map,
            None => {
                built = ImpactMap::build(&self.rays);
                &built
            }
        };
        self.points
            .points
            .par_iter()
            .map(|p| map.irradiance(Some(&self.world), p.position, p.normal, k))
            .collect()
    }
}

/// Figure 2.4: adds (`sign` = 1) or subtracts (`sign` = -1) each impact's power on the triangle it hit.
fn add_impacts<'a>(power: &mut [DVec3], segments: impl Iterator<Item = &'a RaySegment>, sign: f64) {
    for s in segments {
        if let Some(h) = s.hit
            && let Some(p) = power.get_mut(h.triangle as usize)
        {
            *p += sign * s.power.as_dvec3();
        }
    }
}

/// The larger of DETP's disc radius `radius` and the glossy discs' radius (section 2.10).
fn largest_radius(options: &QuasiStaticOptions, radius: f32) -> f32 {
    options.glossy_radius.map_or(radius, |g| g.max(radius))
}

/// The box every point of the objects `mobile` stays in as they follow their paths (section 2.2.2: positions between keyframes interpolated linearly, rotations about the pivot), grown by `margin`; `None` when one of them has no path or no vertex. The pivot stays in its keyframes' box and every vertex within its rest distance from the pivot.
fn reach_of_paths(scene: &Scene, mobile: &[ObjectId], margin: f32) -> Option<Aabb> {
    let mut reach = Aabb::EMPTY;
    for &object in mobile {
        let path = &scene
            .mobile_objects()
            .iter()
            .find(|m| m.object == object)?
            .path;
        let radius = scene
            .objects()
            .get(object as usize)?
            .meshes
            .iter()
            .flat_map(|&m| &scene.meshes()[m as usize].positions)
            .map(|p| p.distance(path.pivot()))
            .reduce(f32::max)?;
        let grow = Vec3::splat(radius * (1.0 + 1e-5) + margin);
        for key in path.keyframes() {
            reach = reach.union(Aabb {
                min: key.translation - grow,
                max: key.translation + grow,
            });
        }
    }
    (reach.min.is_finite() && reach.max.is_finite()).then_some(reach)
}

/// The ascending indices of the paths of `rays` that may pass through the box `lo..=hi`, by their cells in
/// `paths`; `None` (every path) when there are no masks.
fn paths_near(paths: Option<&PathCells>, lo: Vec3, hi: Vec3, rays: &RaySet) -> Option<Vec<usize>> {
    paths.map(|p| p.paths_meeting(&p.region(lo, hi), rays.rays.len()))
}

/// The box round `discs` that a ray can cross ([`Disc::bounds`] with the crossing `slack`), `None` when no disc can be crossed: only the segments through it can cross one.
fn disc_region(discs: &[Disc], slack: f32) -> Option<(Vec3, Vec3)> {
    discs
        .iter()
        .filter(|d| d.radius > 0.0)
        .map(|d| d.bounds(slack))
        .reduce(|(a, b), (lo, hi)| (a.min(lo), b.max(hi)))
}

/// The DETP disc of an estimation point (section 1.2); a degenerate point gets a zero radius, which no ray crosses.
fn point_disc(p: &EstimationPoint, radius: f32) -> Disc {
    Disc {
        centre: p.position,
        normal: p.normal,
        radius: if p.normal == Vec3::ZERO { 0.0 } else { radius },
        mesh: Some(p.mesh),
    }
}
