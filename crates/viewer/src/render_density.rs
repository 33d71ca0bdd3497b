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
use lustre_geometry::meshing::subdivide;
use lustre_mpr::passes::gouraud::corner_radiance;

/// Default DETP disc radius in m (section 1.2): 2.5 % of the 2 m Cornell box, half the default mesh edge (the paper's reference uses 1 % of the scene with 100 M rays). With artifact control (on by default), `cornell` at 256×256 and 1 M photons measures relMSE 0.00173, 0.00140, 0.00131, 0.00127, 0.00128, 0.00133 at r = 0.03, 0.04, 0.05, 0.06, 0.07, 0.08 (seed 1): flat from 0.05 on, where the floor's error grows with the blur and the boxes' falls with the noise; without it 0.0029 at 0.05 and at best 0.0028, the bias of the discs cut by walls.
pub const DEFAULT_DETP_RADIUS: f32 = 0.05;
/// Default DETP glossy disc radius as a multiple of the disc radius (section 2.10; beyond the paper, which uses one radius): only the rays inside a glossy lobe count towards the non-diffuse part of the radiance, so its estimate on a 0.05 m disc is speckled (coloured blotches on `glosbox`'s floor, a noisy gold box). `glosbox` (1 M photons, 256×256, artifact control) measures relMSE 0.0059, 0.0034, 0.0027, 0.0026, 0.0027 with glossy radii 0.05, 0.1, 0.15, 0.2, 0.25 m; the floor (α = 0.05) is best at 0.2–0.25, the gold box (α = 0.1, 0.6 m faces) at 0.15–0.2, and 0.2 costs a third more time than 0.15 for 4 % less error. Both radii scale alike with the photon count (the kernel's bias–variance balance), hence a factor rather than a length.
pub const DEFAULT_GLOSSY_RADIUS_FACTOR: f32 = 3.0;
/// Default number `k` of nearest impacts of Photon Maps (section 1.2, Jensen): with the normal filter and the boundary correction (`lustre_density::boundary`), 300 at the default 1 M photons gives `cornell` relMSE 0.0022 against the reference and `glosbox` 0.0085 (0.0083–0.0085 over seeds 1–3), the smallest k tried under 0.0050 and 0.0100 with a margin (k = 200: 0.0024 and 0.0101; k = 400: 0.0022 and 0.0065); `glosbox`'s error is the variance of the glossy floor's and gold box's view-dependent estimate. About 1.1 s of CPU for `cornell`'s estimate, less than half of what k = 200 cost before the kd-tree split on the widest axis and skipped subtrees by their normals.
pub const DEFAULT_PHOTONMAP_K: usize = 300;
/// Default longest edge in m after subdivision for per-vertex lighting (section 2.9 meshes into 0.02 m squares; 0.1 m gives `cornell` about 6,500 vertices, keeping DETP's every-segment-at-every-vertex cost near ten seconds on two cores).
pub const DEFAULT_MESH_EDGE: f32 = 0.1;

pub use lustre_density::Estimator;

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

/// `scene` with every non-emissive mesh subdivided regularly to edges of at most `edge` m (section 2.9); emissive meshes keep their shape, so area lights stay the rectangles they were.
pub fn vertex_lit_scene(scene: &Scene, edge: f32) -> anyhow::Result<Scene> {
    let meshes = scene
        .meshes()
        .iter()
        .map(|mesh| {
            if scene.materials()[mesh.material as usize].is_emissive() {
                Ok(mesh.clone())
            } else {
                subdivide(mesh, edge).with_context(|| {
                    format!("cannot subdivide mesh `{}` to {edge} m edges", mesh.name)
                })
            }
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    scene
        .with_meshes(meshes)
        .with_context(|| format!("scene `{}` after subdivision", scene.name))
}

/// Traces the ray set of `photons` photons (section 2.3, figure 2.1) and runs `estimator` at every vertex (section 2.4.1, figure 2.3), returning `L_r = ρ/π E` per triangle corner with the time of each phase. Every object is static here; `--frames` moves the mobile ones ([`crate::render_frames`]).
pub fn vertex_radiance(
    estimator: Estimator,
    scene: &Scene,
    settings: &DensitySettings,
) -> anyhow::Result<VertexRadiance> {
    let sim = QuasiStatic::new(scene.clone(), &[], settings.options(estimator))
        .with_context(|| format!("{} on `{}`", estimator.name(), scene.name))?;
    let first = sim.first_frame();
    let corners = corners(&sim)?;
    Ok(VertexRadiance {
        corners,
        primary_rays: sim.rays().rays.len(),
        segments: sim.rays().segments().count(),
        ray_set_ms: first.photosimulation.as_secs_f64() * 1e3,
        estimate_ms: first.radiosity.as_secs_f64() * 1e3,
    })
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

/// Outgoing radiance per triangle corner for the Gouraud pass: `ρ/π E` (equation 2.2), or on glossy meshes under the glossy option the view-dependent estimate towards the camera (section 2.10; DETP's disc, Impact Count's triangles or Photon Maps' nearest impacts).
pub fn corners(sim: &QuasiStatic) -> anyhow::Result<Vec<[f32; 3]>> {
    let scene = sim.scene();
    let mut corners = corner_radiance(scene, &sim.irradiance())
        .with_context(|| format!("vertex radiance of `{}`", scene.name))?;
    let glossy = sim
        .glossy_radiance(scene.camera().position)
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
        }
        options
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    #[test]
    fn subdivision_keeps_the_light_a_rectangle_and_refines_the_rest() {
        let scene = builtin("cornell").unwrap();
        let fine = vertex_lit_scene(&scene, 0.5).unwrap();
        assert_eq!(fine.lights().len(), scene.lights().len());
        assert_eq!(fine.lights()[0].power(), scene.lights()[0].power());
        assert!(fine.triangle_count() > 10 * scene.triangle_count());
        assert!((fine.bounds().extent() - scene.bounds().extent()).length() < 1e-6);
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
