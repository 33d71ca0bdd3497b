//! Per-vertex radiance of García Hernández, Ureña & Lastra (2003) for
//! `lustre render --technique detp|impact|photonmap`: the ray set of section
//! 2.3, one of the density estimators of section 1.2 at every mesh vertex
//! (section 2.4.1, figure 2.3), `L_r = ρ/π E` per triangle corner (section
//! 2.4, equation 2.2) for the Gouraud pass, on a scene meshed finely enough
//! for per-vertex lighting (section 2.9).

use anyhow::Context;
use lustre_density::artifact::ArtifactOptions;
use lustre_density::glossy::GlossyMode;
use lustre_density::quadtree::QuadTreeOptions;
use lustre_density::{Acceleration, PreTest, QuasiStatic, QuasiStaticOptions};
use lustre_geometry::Scene;
use lustre_geometry::obj::Studio;
use lustre_mpr::passes::gouraud::corner_radiance;

/// Default DETP disc radius as a fraction of the scene's size ([`scene_size`], the longest side of its bounding box; section 1.2): 2.5 %, 0.05 m in the 2 m Cornell box and half the default mesh edge (the paper's reference uses 1 % of the scene with 100 M rays, where a smaller disc holds as many rays as ours at 1 M). With artifact control (on by default), `cornell` at 256×256 and 1 M photons measures relMSE 0.00173, 0.00140, 0.00131, 0.00127, 0.00128, 0.00133 at r = 0.03, 0.04, 0.05, 0.06, 0.07, 0.08 m (seed 1): flat from 0.05 on, where the floor's error grows with the blur and the boxes' falls with the noise; without it 0.0029 at 0.05 and at best 0.0028, the bias of the discs cut by walls. A fraction rather than a length, so that a model in millimetres or kilometres gets the image it gets in metres.
pub const DETP_RADIUS_FRACTION: f32 = 0.025;
/// Default DETP glossy disc radius as a multiple of the disc radius (section 2.10; beyond the paper, which uses one radius): only the rays inside a glossy lobe count towards the non-diffuse part of the radiance, so its estimate on a 0.05 m disc is speckled (coloured blotches on `glosbox`'s floor, a noisy gold box). `glosbox` (1 M photons, 256×256, artifact control) measures relMSE 0.0059, 0.0034, 0.0027, 0.0026, 0.0027 with glossy radii 0.05, 0.1, 0.15, 0.2, 0.25 m; the floor (α = 0.05) is best at 0.2–0.25, the gold box (α = 0.1, 0.6 m faces) at 0.15–0.2, and 0.2 costs a third more time than 0.15 for 4 % less error. Both radii scale alike with the photon count (the kernel's bias–variance balance), hence a factor rather than a length.
pub const DEFAULT_GLOSSY_RADIUS_FACTOR: f32 = 3.0;
/// Default number `k` of nearest impacts of Photon Maps (section 1.2, Jensen): with the normal filter and the boundary correction (`lustre_density::boundary`), 300 at the default 1 M photons gives `cornell` relMSE 0.0022 against the reference and `glosbox` 0.0085 (0.0083–0.0085 over seeds 1–3), the smallest k tried under 0.0050 and 0.0100 with a margin (k = 200: 0.0024 and 0.0101; k = 400: 0.0022 and 0.0065); `glosbox`'s error is the variance of the glossy floor's and gold box's view-dependent estimate. About 1.1 s of CPU for `cornell`'s estimate, less than half of what k = 200 cost before the kd-tree split on the widest axis and skipped subtrees by their normals.
pub const DEFAULT_PHOTONMAP_K: usize = 300;
/// Default longest edge after subdivision for per-vertex lighting, as a fraction of the scene's size (section 2.9 meshes into 0.02 m squares): 5 %, 0.1 m in `cornell`, which gives it about 6,500 vertices and keeps DETP's every-segment-at-every-vertex cost near ten seconds on two cores.
pub const MESH_EDGE_FRACTION: f32 = 0.05;

/// The scene's size for the relative defaults: the longest side of its bounding box, lights included (`cornell` 2.01 m), or for a model in the default studio the model's (the studio is five times as wide, and the model is what is looked at).
pub fn scene_size(scene: &Scene, studio: Option<&Studio>) -> f32 {
    studio.map_or_else(|| scene.bounds().extent().max_element(), |s| s.model_size)
}

/// The lengths of the per-vertex techniques: given on the command line, or relative to the scene's size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensityLengths {
    /// The scene's size they were chosen from ([`scene_size`]).
    pub scene_size: f32,
    /// DETP's disc radius (section 1.2).
    pub radius: f32,
    /// DETP's disc radius for the non-diffuse part of glossy meshes (section 2.10).
    pub glossy_radius: f32,
    /// Longest mesh edge after subdivision (section 2.9).
    pub mesh_edge: f32,
}

impl DensityLengths {
    /// Each length given, or its default relative to the size of `scene` (in `studio` if it has one, [`scene_size`]): [`DETP_RADIUS_FRACTION`], [`DEFAULT_GLOSSY_RADIUS_FACTOR`] × the radius and [`MESH_EDGE_FRACTION`]; an error names the option to give when the scene has no size to scale by.
    pub fn for_scene(
        scene: &Scene,
        studio: Option<&Studio>,
        radius: Option<f32>,
        glossy_radius: Option<f32>,
        mesh_edge: Option<f32>,
    ) -> anyhow::Result<Self> {
        let size = scene_size(scene, studio);
        let relative = |fraction: f32, option: &str| {
            if size.is_finite() && size > 0.0 {
                Ok(fraction * size)
            } else {
                anyhow::bail!(
                    "scene `{}` has no extent ({size}) to scale the default {option} by; give {option}",
                    scene.name
                )
            }
        };
        let radius = match radius {
            Some(r) => r,
            None => relative(DETP_RADIUS_FRACTION, "--radius")?,
        };
        let mesh_edge = match mesh_edge {
            Some(e) => e,
            None => relative(MESH_EDGE_FRACTION, "--mesh-edge")?,
        };
        let lengths = Self {
            scene_size: size,
            radius,
            glossy_radius: glossy_radius.unwrap_or(DEFAULT_GLOSSY_RADIUS_FACTOR * radius),
            mesh_edge,
        };
        check_lengths(
            Some(lengths.radius),
            Some(lengths.glossy_radius),
            Some(lengths.mesh_edge),
        )?;
        Ok(lengths)
    }
}

/// Fails naming the first of `--radius`, `--glossy-radius` and `--mesh-edge` that is given and not a positive finite length.
pub fn check_lengths(
    radius: Option<f32>,
    glossy_radius: Option<f32>,
    mesh_edge: Option<f32>,
) -> anyhow::Result<()> {
    for (option, value) in [
        ("--radius", radius),
        ("--glossy-radius", glossy_radius),
        ("--mesh-edge", mesh_edge),
    ] {
        if let Some(v) = value.filter(|v| !(*v > 0.0 && v.is_finite())) {
            anyhow::bail!("{option} {v}: must be positive and finite");
        }
    }
    Ok(())
}

pub use lustre_density::{Estimator, vertex_lit_scene};

/// Per-corner radiance for the Gouraud pass and what producing it cost.
#[derive(Debug, Clone)]
pub struct VertexRadiance {
    /// `L_r = ρ/π E` per scene triangle corner, in `SceneBuffers` order (W/(m² sr), RGB).
    pub corners: Vec<[f32; 3]>,
    /// Primary rays of the ray set (photons that carried power).
    pub primary_rays: usize,
    /// Segments of the ray set (primary rays and reflections).
    pub segments: usize,
    /// Time to trace the ray set (section 2.3), ms.
    pub ray_set_ms: f64,
    /// Time of the estimator over every vertex (section 2.4.1), ms.
    pub estimate_ms: f64,
}

/// Traces the ray set of `photons` photons (section 2.3, figure 2.1) and runs `estimator` at every vertex (section 2.4.1, figure 2.3), returning `L_r = ρ/π E` per triangle corner with the time of each phase. Every object is static here; `--frames` moves the mobile ones ([`crate::render_frames`]).
pub fn vertex_radiance(
    estimator: Estimator,
    scene: &Scene,
    settings: &DensitySettings,
) -> anyhow::Result<VertexRadiance> {
    let sim = QuasiStatic::new(scene.clone(), &[], settings.options(estimator))
        .map_err(explain_too_many_rays)
        .with_context(|| format!("{} on `{}`", estimator.name(), scene.name))?;
    let first = sim.first_frame();
    let corners = corners(&sim)?;
    let radiance = VertexRadiance {
        corners,
        primary_rays: sim.rays().rays.len(),
        segments: sim.rays().segments().count(),
        ray_set_ms: first.photosimulation.as_secs_f64() * 1e3,
        estimate_ms: first.radiosity.as_secs_f64() * 1e3,
    };
    drop_in_background(sim);
    Ok(radiance)
}

/// Drops a simulation on a thread of its own: its ray set and its glossy vertices' lists are millions of allocations, about a second of freeing on a dense model (`dense_glossy`'s blob), which the frame after it and the process's exit (which does not wait for the thread) need not wait for. Dropped at once when no thread can be started.
pub fn drop_in_background(sim: QuasiStatic) {
    let _ = std::thread::Builder::new()
        .name("drop-simulation".into())
        .spawn(move || drop(sim));
}

/// A density error, with the options that lower its memory when the glossy lists would not fit.
pub fn explain_too_many_rays(error: lustre_density::DensityError) -> anyhow::Error {
    if matches!(error, lustre_density::DensityError::TooManyRays { .. }) {
        anyhow::Error::new(error).context(
            "not enough memory for the glossy estimate: give a smaller --glossy-radius, fewer \
             --photons or --glossy-estimate none",
        )
    } else {
        anyhow::Error::new(error)
    }
}

/// How `lustre render` estimates glossy vertices (section 2.10); Impact Count and Photon Maps use their plain impact lists for every value but `none`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GlossyEstimate {
    /// Only the diffuse part `ρ/π E` of every material.
    None,
    /// Every ray crossing the disc, the BRDF evaluated for each (section 2.10).
    List,
    /// The direction QuadTree without summarising, nodes taken whole where the BRDF varies by at most 1 % (section 2.10.1).
    Quadtree,
    /// The QuadTree with the summarising update of section 2.10.1 (approximate, degrades over frames).
    Summarised,
}

impl GlossyEstimate {
    /// The density crate's mode, `None` for the diffuse part only.
    pub fn mode(self) -> Option<GlossyMode> {
        match self {
            Self::None => None,
            Self::List => Some(GlossyMode::List),
            Self::Quadtree => Some(GlossyMode::QuadTree {
                options: QuadTreeOptions::default(),
                tolerance: 0.01,
            }),
            Self::Summarised => Some(GlossyMode::Summarised(QuadTreeOptions::default())),
        }
    }
}

/// Outgoing radiance per triangle corner for the Gouraud pass: `ρ/π E` (equation 2.2), or on glossy meshes under the glossy option the view-dependent estimate towards the scene's camera (section 2.10; DETP's disc, Impact Count's triangles or Photon Maps' nearest impacts).
pub fn corners(sim: &QuasiStatic) -> anyhow::Result<Vec<[f32; 3]>> {
    corners_towards(sim, sim.scene().camera().position)
}

/// [`corners`] with the glossy meshes' radiance towards `eye` (the window's moving camera; section 2.10 recomputes it when the eye moves).
pub fn corners_towards(sim: &QuasiStatic, eye: glam::Vec3) -> anyhow::Result<Vec<[f32; 3]>> {
    let scene = sim.scene();
    let mut corners = corner_radiance(scene, &sim.irradiance())
        .with_context(|| format!("vertex radiance of `{}`", scene.name))?;
    let glossy = sim
        .glossy_radiance(eye)
        .with_context(|| format!("glossy radiance of `{}`", scene.name))?;
    for (m, radiance) in glossy.iter().flatten().enumerate() {
        if radiance.is_empty() {
            continue;
        }
        let first = 3 * scene.triangle_id(m as u32, 0) as usize;
        let mesh = &scene.meshes()[m];
        for (t, tri) in mesh.indices.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                corners[first + 3 * t + k] = radiance[v as usize].to_array();
            }
        }
    }
    Ok(corners)
}

/// The meshes whose Gouraud corner radiance already holds their diffuse map, which the pass must not apply again: the glossy meshes under a glossy estimate ([`corners_towards`]; their view-dependent radiance folds `ρ_d t(uv)` in at each vertex). Every other mesh's corners carry the untextured `ρ_d/π E`, scaled by the map per fragment ([`lustre_mpr::passes::gouraud::corner_layers`]).
pub fn tinted_at_vertices(scene: &Scene, glossy: GlossyEstimate) -> Vec<lustre_geometry::MeshId> {
    if glossy.mode().is_some() {
        lustre_density::glossy::glossy_meshes(scene)
    } else {
        Vec::new()
    }
}

/// How `lustre render` finds the rays crossing each DETP disc (García et al. sections 2.6–2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DetpAcceleration {
    /// Disc indexing, leaf size tuned by the radius and the mean edge (section 2.7).
    DiscIndex,
    /// The ray cache with the sorted query order reused across frames (sections 1.2.1, 2.6).
    RayCache,
    /// The ray cache in the vertices' own order.
    RayCacheUnsorted,
    /// A uniform grid over the ray segments, cells the size of a disc (beyond the paper).
    SegmentGrid,
    /// Every segment against every disc.
    BruteForce,
}

/// DETP's pre-intersection test (García et al. section 2.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PreTestArg {
    /// None.
    None,
    /// Badouel's projection test against the tangent triangle.
    Badouel,
    /// Plücker coordinates against the tangent triangle.
    Plucker,
    /// Möller–Trumbore against the tangent triangle.
    Moller,
}

/// The density crate's acceleration for a disc radius; `None` lets it tune disc indexing to the scene.
pub fn acceleration(arg: DetpAcceleration, radius: f32) -> Option<Acceleration> {
    match arg {
        DetpAcceleration::DiscIndex => None,
        DetpAcceleration::RayCache => Some(Acceleration::RayCache { sorted: true }),
        DetpAcceleration::RayCacheUnsorted => Some(Acceleration::RayCache { sorted: false }),
        DetpAcceleration::SegmentGrid => Some(Acceleration::SegmentGrid {
            cell_size: 2.0 * radius,
        }),
        DetpAcceleration::BruteForce => Some(Acceleration::BruteForce),
    }
}

/// The density crate's pre-test.
pub fn pretest(arg: PreTestArg) -> PreTest {
    match arg {
        PreTestArg::None => PreTest::None,
        PreTestArg::Badouel => PreTest::Badouel,
        PreTestArg::Plucker => PreTest::Plucker,
        PreTestArg::Moller => PreTest::MollerTrumbore,
    }
}

/// What `lustre render` sets of a quasi-static simulation besides the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensitySettings {
    /// Photons over all lights.
    pub photons: u64,
    /// Seed of the photon paths.
    pub seed: u64,
    /// DETP artifact control (section 1.2.1).
    pub artifact_control: bool,
    /// DETP's disc radius for the non-diffuse part of glossy meshes (section 2.10).
    pub glossy_radius: f32,
    /// DETP's estimate on glossy meshes (section 2.10).
    pub glossy: GlossyEstimate,
    /// How DETP finds crossing rays (sections 2.6–2.7).
    pub acceleration: DetpAcceleration,
    /// DETP's pre-intersection test (section 2.8).
    pub pretest: PreTestArg,
    /// Most rays DETP's glossy vertices may keep ([`glossy_ray_limit`]); `None`: no bound.
    pub max_glossy_rays: Option<u64>,
}

/// How many rays DETP's glossy lists may keep on this machine: four fifths of the memory Linux reports available (`MemAvailable`), [`lustre_density::glossy::BYTES_PER_STORED_RAY`] each; `None` where that is not known. Beyond it the render stops with an error naming the options to lower, rather than being killed for memory.
pub fn glossy_ray_limit() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024 / 5 * 4 / lustre_density::glossy::BYTES_PER_STORED_RAY as u64)
}

impl DensitySettings {
    /// Plain settings: no artifact control, the QuadTree glossy estimate, tuned disc indexing, no pre-test.
    #[cfg(test)]
    pub fn new(photons: u64, seed: u64) -> Self {
        Self {
            photons,
            seed,
            artifact_control: false,
            glossy_radius: 0.15,
            glossy: GlossyEstimate::Quadtree,
            acceleration: DetpAcceleration::DiscIndex,
            pretest: PreTestArg::None,
            max_glossy_rays: None,
        }
    }

    /// The simulation options for an estimator; artifact control and the DETP speed-ups apply to DETP only; Impact Count and Photon Maps estimate glossy vertices from plain impact lists unless the glossy estimate is `none` (section 2.10).
    pub fn options(&self, estimator: Estimator) -> QuasiStaticOptions {
        let mut options = QuasiStaticOptions::new(estimator, self.photons);
        options.rays.seed = self.seed;
        options.glossy = self.glossy.mode().map(|_| GlossyMode::List);
        if let Estimator::Detp { radius } = estimator {
            options.artifact = self.artifact_control.then(ArtifactOptions::default);
            options.glossy = self.glossy.mode();
            options.glossy_radius = Some(self.glossy_radius);
            options.acceleration = acceleration(self.acceleration, radius);
            options.pretest = pretest(self.pretest);
            options.max_glossy_rays = self.max_glossy_rays;
        }
        options
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    /// `scene` with every length multiplied by `factor`: vertices, object translations and the camera; area lights keep their radiance, so every irradiance is unchanged.
    fn scaled(scene: &Scene, factor: f32) -> Scene {
        let meshes = scene
            .meshes()
            .iter()
            .map(|m| {
                let mut m = m.clone();
                m.positions.iter_mut().for_each(|p| *p *= factor);
                m
            })
            .collect();
        let mut out = scene.with_meshes(meshes).unwrap();
        for (o, object) in scene.objects().iter().enumerate() {
            let mut t = object.transform;
            t.translation *= factor;
            out.set_object_transform(o as u32, t).unwrap();
        }
        let mut camera = *scene.camera();
        camera.position *= factor;
        camera.target *= factor;
        camera.near *= factor;
        out.set_camera(camera);
        out
    }

    #[test]
    fn default_lengths_are_relative_to_the_scene() {
        let cornell = builtin("cornell").unwrap();
        let l = DensityLengths::for_scene(&cornell, None, None, None, None).unwrap();
        assert!((l.scene_size - 2.01).abs() < 1e-5, "{}", l.scene_size);
        assert!((l.radius - 0.025 * 2.01).abs() < 1e-6);
        assert!((l.glossy_radius - 3.0 * l.radius).abs() < 1e-6);
        assert!((l.mesh_edge - 0.05 * 2.01).abs() < 1e-6);
        let given = DensityLengths::for_scene(&cornell, None, Some(0.2), None, Some(0.3)).unwrap();
        assert_eq!(
            (given.radius, given.glossy_radius, given.mesh_edge),
            (0.2, 0.6, 0.3)
        );
        let big =
            DensityLengths::for_scene(&scaled(&cornell, 1000.0), None, None, None, None).unwrap();
        assert!((big.radius / l.radius - 1000.0).abs() < 0.01);
        assert!((big.mesh_edge / l.mesh_edge - 1000.0).abs() < 0.01);
        let bad = DensityLengths::for_scene(&cornell, None, Some(-1.0), None, None);
        assert!(format!("{:#}", bad.unwrap_err()).contains("--radius -1"));
    }

    /// The same per-corner radiance for `cornell` in metres and in millimetres under the relative defaults: every length of DETP (disc, glossy disc, mesh edge, ray offsets) scales with the scene.
    #[test]
    fn a_scene_scaled_by_1000_gets_the_same_radiance() {
        let metres = builtin("cornell").unwrap();
        let millimetres = scaled(&metres, 1000.0);
        let corners = |scene: &Scene| {
            let l = DensityLengths::for_scene(scene, None, None, None, None).unwrap();
            let meshed = vertex_lit_scene(scene, 4.0 * l.mesh_edge).unwrap();
            let mut settings = DensitySettings::new(20_000, 1);
            settings.artifact_control = true;
            settings.glossy_radius = l.glossy_radius;
            let r = vertex_radiance(
                Estimator::Detp {
                    radius: 4.0 * l.radius,
                },
                &meshed,
                &settings,
            )
            .unwrap();
            (meshed.triangle_count(), r.corners)
        };
        let (n_m, m) = corners(&metres);
        let (n_mm, mm) = corners(&millimetres);
        assert_eq!(n_m, n_mm, "the same subdivision");
        let (mut worst, mut sum, mut total) = (0.0f32, 0.0f64, 0.0f64);
        for (a, b) in m.iter().flatten().zip(mm.iter().flatten()) {
            worst = worst.max((a - b).abs() / a.abs().max(1e-3));
            sum += f64::from((a - b).abs());
            total += f64::from(a.abs());
        }
        assert!(total > 0.0);
        // Measured: 4e-8 mean, 2e-7 worst (float rounding of the scaled coordinates).
        assert!(
            sum / total < 1e-5,
            "mean relative difference {}",
            sum / total
        );
        assert!(worst < 1e-3, "worst corner differs by {worst}");
    }

    #[test]
    fn every_estimator_gives_one_finite_radiance_per_corner() {
        let scene = vertex_lit_scene(&builtin("cornell").unwrap(), 0.5).unwrap();
        for estimator in [
            Estimator::Detp { radius: 0.2 },
            Estimator::ImpactCount,
            Estimator::PhotonMaps { k: 10 },
        ] {
            let r = vertex_radiance(estimator, &scene, &DensitySettings::new(2_000, 1)).unwrap();
            assert_eq!(r.corners.len(), 3 * scene.triangle_count());
            assert!(
                r.corners
                    .iter()
                    .flatten()
                    .all(|c| c.is_finite() && *c >= 0.0)
            );
            assert!(r.corners.iter().any(|c| c[0] > 0.0), "{}", estimator.name());
            assert!(r.segments >= r.primary_rays);
        }
        let bad = vertex_radiance(
            Estimator::Detp { radius: 0.0 },
            &scene,
            &DensitySettings::new(10, 1),
        );
        assert!(format!("{:#}", bad.unwrap_err()).contains("radius"));
    }
}
