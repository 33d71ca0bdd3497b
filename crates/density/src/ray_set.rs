//! The ray set of section 2.3 (figure 2.1): primary rays from the lights, each owning the list of its reflections.
//!
//! Every photon of a light is one [`PrimaryRay`]; its [`RaySegment`]s are the
//! primary ray followed by its successive reflections (the paper's "simply
//! linked list of rays produced by subsequent reflections", stored here as a
//! `Vec`). Each segment keeps its origin, direction, hit (point and triangle,
//! or none when it leaves the scene) and the power it carries. Photons
//! are traced as in `lustre-photon` (section 2.1 of Stürzlinger & Bastos,
//! reused as section 2.3 allows): powers `φ = Φ_i / m_i ρ`, absorption by
//! Russian roulette on the BRDF sample weight, so a grey Lambertian surface of
//! albedo `a` reflects with probability `a` and the power stays unchanged.

use glam::Vec3;
use lustre_brdf::BoxedBrdf;
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, MeshId, Ray, Rgb, Scene, TriangleId};
use lustre_photon::trace::scene_brdfs;
use lustre_photon::{allocate_photons, photon_stream};
use rayon::prelude::*;

use crate::artifact::{extension, is_concave, mesh_triangles};
use crate::error::{DensityError, Result};
use crate::world::{World, WorldHit};

/// Settings of the photosimulation that builds a ray set (section 2.3, figure 2.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaySetOptions {
    /// Photons (primary rays) over all lights, split in proportion to the lights' power (figure 2.1).
    pub photons: u64,
    /// Seed of every random choice.
    pub seed: u64,
    /// Largest number of segments per primary ray (1 or more).
    pub max_segments: u32,
    /// Artifact control on concave surfaces (section 1.2.1): the longest [`RaySegment::extension`] in metres measured for each segment through the mesh it hit, against the static scene, when that mesh is concave ([`crate::artifact::is_concave`]; on any other the extension could change no crossing and stays 0); 0 turns it off.
    pub extension: f32,
}

impl Default for RaySetOptions {
    fn default() -> Self {
        Self {
            photons: 100_000,
            seed: 0,
            max_segments: 64,
            extension: 0.0,
        }
    }
}

/// Where a ray segment ends on the scene (section 2.3: "we know which triangle intersected the ray").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentHit {
    /// Scene-wide index of the triangle hit.
    pub triangle: TriangleId,
    /// The mesh that triangle belongs to.
    pub mesh: MeshId,
    /// Whether that triangle belongs to a mobile object (section 2.3: each ray keeps "which triangle intersected the ray" and whether it is the mobile object's).
    pub mobile: bool,
    /// The hit point in world space.
    pub position: Vec3,
    /// Unit geometric normal of the triangle hit.
    pub normal: Vec3,
    /// Distance from the segment's origin to the hit point.
    pub distance: f32,
}

/// One ray of the ray set (section 2.3): a primary ray or one of its reflections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaySegment {
    /// Origin (on the light, or just off the surface that reflected it).
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
    /// The first intersection with the scene; `None` when the ray leaves the scene (it is then a half-line).
    pub hit: Option<SegmentHit>,
    /// Power `φ` (W, RGB) carried along the segment and delivered at its hit.
    pub power: Rgb,
    /// Artifact control on concave surfaces (section 1.2.1): how far the segment may be followed past its hit, through the mesh it hit, before it meets any other part of the scene; zero when artifact control is off or the mesh is not concave.
    pub extension: f32,
}

impl RaySegment {
    /// A segment with no artifact-control extension.
    pub fn new(origin: Vec3, direction: Vec3, hit: Option<SegmentHit>, power: Rgb) -> Self {
        Self {
            origin,
            direction,
            hit,
            power,
            extension: 0.0,
        }
    }

    /// Length of the segment: the hit distance, or infinity for a ray that leaves the scene.
    pub fn length(&self) -> f32 {
        self.hit.map_or(f32::INFINITY, |h| h.distance)
    }
}

/// A primary ray and the list of its reflections (section 2.3, the two-level ray list).
#[derive(Debug, Clone, PartialEq)]
pub struct PrimaryRay {
    /// Index of the emitting light in [`Scene::lights`].
    pub light: u32,
    /// Index of the photon among its light's photons (it keys the photon's random streams).
    pub index: u64,
    /// The primary ray first, then each reflection in order (figure 2.1, `Ray ← REFLECT(Ray)`).
    pub segments: Vec<RaySegment>,
}

/// The ray list of section 2.3: every primary ray of every light, with the number of photons each light emitted.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RaySet {
    /// The primary rays (first level of the two-level list).
    pub rays: Vec<PrimaryRay>,
    /// Photons `m_i` emitted per light (figure 2.1), including those that produced no segment.
    pub emitted_per_light: Vec<u64>,
}

impl RaySet {
    /// Total photons emitted over all lights.
    pub fn emitted(&self) -> u64 {
        self.emitted_per_light.iter().sum()
    }

    /// Every segment of every primary ray (the whole ray set `S^t` of section 2.4.2).
    pub fn segments(&self) -> impl Iterator<Item = &RaySegment> {
        self.rays.iter().flat_map(|r| r.segments.iter())
    }

    /// Every segment that ends on the scene: the impacts used by Impact Count and Photon Maps (section 1.2).
    pub fn impacts(&self) -> impl Iterator<Item = (&RaySegment, &SegmentHit)> {
        self.segments()
            .filter_map(|s| s.hit.as_ref().map(|h| (s, h)))
    }
}

/// Builds the ray set of a static scene (section 2.3, figure 2.1: INITIALPHOTOSIMULATIONCALCULATION) with a BVH over the whole scene; no object is mobile.
pub fn trace_ray_set(scene: &Scene, bvh: &Bvh, options: &RaySetOptions) -> Result<RaySet> {
    trace_with(
        scene,
        &WholeScene { scene, bvh },
        Some(bvh),
        world_epsilon(scene),
        options,
    )
}

/// Builds the ray set of a scene with mobile objects at their current pose (section 2.3, figure 2.1), so that [`crate::update_ray_set`] can recalculate it (figure 2.2).
pub fn trace_ray_set_in(scene: &Scene, world: &World, options: &RaySetOptions) -> Result<RaySet> {
    let statics = (options.extension > 0.0).then(|| world.static_scene_bvh(scene));
    trace_with(scene, world, statics, world.epsilon(), options)
}

/// The offset that steps a reflected ray off its surface: 10⁻⁵ of the scene's size.
pub(crate) fn world_epsilon(scene: &Scene) -> f32 {
    let scale = scene.bounds().extent().max_element();
    if scale.is_finite() && scale > 0.0 {
        scale * 1e-5
    } else {
        1e-5
    }
}

fn check_options(options: &RaySetOptions) -> Result<()> {
    if options.max_segments == 0 {
        return Err(DensityError::InvalidOption {
            option: "max_segments",
            message: "must be at least 1".into(),
        });
    }
    if !(options.extension >= 0.0 && options.extension.is_finite()) {
        return Err(DensityError::InvalidOption {
            option: "extension",
            message: format!("{} is not a finite non-negative length", options.extension),
        });
    }
    if options.photons > u32::MAX as u64 {
        return Err(DensityError::InvalidOption {
            option: "photons",
            message: format!("{} is more than 2^32", options.photons),
        });
    }
    Ok(())
}

fn trace_with(
    scene: &Scene,
    world: &dyn Intersector,
    statics: Option<&Bvh>,
    epsilon: f32,
    options: &RaySetOptions,
) -> Result<RaySet> {
    check_options(options)?;
    let tracer = Tracer::new(scene, world, statics, epsilon, options)?;
    let jobs: Vec<(u32, u64)> = tracer
        .counts
        .iter()
        .enumerate()
        .flat_map(|(light, &m)| (0..m).map(move |i| (light as u32, i)))
        .collect();
    let rays = jobs
        .par_iter()
        .filter_map(|&(light, index)| tracer.primary_ray(light, index))
        .collect();
    Ok(RaySet {
        rays,
        emitted_per_light: tracer.counts,
    })
}

/// First intersections for the tracer: the whole scene's BVH, or a [`World`] with mobile objects.
pub(crate) trait Intersector: Sync {
    /// The first intersection of a ray with the scene.
    fn first_hit(&self, ray: &Ray) -> Option<WorldHit>;
}

struct WholeScene<'a> {
    scene: &'a Scene,
    bvh: &'a Bvh,
}

impl Intersector for WholeScene<'_> {
    fn first_hit(&self, ray: &Ray) -> Option<WorldHit> {
        self.bvh.closest_hit(ray).map(|hit| WorldHit {
            mesh: self.scene.triangle_source(hit.triangle).0,
            hit,
            mobile: false,
        })
    }
}

impl Intersector for World {
    fn first_hit(&self, ray: &Ray) -> Option<WorldHit> {
        self.closest_hit(ray)
    }
}

/// The random stream of bounce `n` (1 = the reflection at the end of the first segment) of a photon: each bounce has its own stream, so a path recalculated from any segment (figure 2.2, FOLLOWRAY) draws the same numbers a full trace of the new pose would.
fn bounce_stream(seed: u64, light: u32, index: u64, n: u32) -> lustre_geometry::sampling::Pcg32 {
    photon_stream(
        seed ^ (n as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        light,
        index,
    )
}

/// What tracing one photon needs.
pub(crate) struct Tracer<'a> {
    scene: &'a Scene,
    world: &'a dyn Intersector,
    /// The static scene with scene-wide triangle ids, for the concave extension (section 1.2.1).
    statics: Option<&'a Bvh>,
    /// Per mesh, whether the concave extension is measured on it ([`crate::artifact::is_concave`]); empty without extension.
    concave: Vec<bool>,
    brdfs: Vec<BoxedBrdf>,
    epsilon: f32,
    pub(crate) counts: Vec<u64>,
    options: &'a RaySetOptions,
}

impl<'a> Tracer<'a> {
    pub(crate) fn new(
        scene: &'a Scene,
        world: &'a dyn Intersector,
        statics: Option<&'a Bvh>,
        epsilon: f32,
        options: &'a RaySetOptions,
    ) -> Result<Self> {
        check_options(options)?;
        let powers: Vec<Rgb> = scene.lights().iter().map(|l| l.power()).collect();
        Ok(Self {
            scene,
            world,
            statics,
            concave: match statics {
                Some(_) if options.extension > 0.0 => (0..scene.meshes().len() as MeshId)
                    .map(|m| is_concave(scene, m, epsilon))
                    .collect(),
                _ => Vec::new(),
            },
            brdfs: scene_brdfs(scene)?,
            epsilon,
            counts: allocate_photons(&powers, options.photons),
            options,
        })
    }

    /// Follows one photon (figure 2.1, inner loop), or `None` when it carries no power.
    fn primary_ray(&self, light: u32, index: u64) -> Option<PrimaryRay> {
        let source = &self.scene.lights()[light as usize];
        let mut rng = photon_stream(self.options.seed, light, index);
        let u_position = rng.next_vec2();
        let u_direction = rng.next_vec2();
        let e = source.sample_emission(u_position, u_direction);
        let m = self.counts[light as usize].max(1) as f32;
        // φ = weight / m: the weight's expectation is the light's power Φ_i.
        let power = e.weight / m;
        if !power.is_finite() || !(power.max_element() > 0.0) || !e.direction.is_finite() {
            return None;
        }
        let origin = if source.is_delta() {
            e.position
        } else {
            let side = if e.direction.dot(e.normal) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            e.position + side * self.epsilon * e.normal
        };
        let mut segments = Vec::new();
        self.follow(
            light,
            index,
            0,
            Ray::new(origin, e.direction),
            power,
            &mut segments,
        );
        Some(PrimaryRay {
            light,
            index,
            segments,
        })
    }

    /// FOLLOWRAY (figure 2.2): traces the ray that is segment `first` (0-based) of photon `index` of `light` against the scene, then its reflections, appending them to `segments`.
    pub(crate) fn follow(
        &self,
        light: u32,
        index: u64,
        first: u32,
        mut ray: Ray,
        mut power: Rgb,
        segments: &mut Vec<RaySegment>,
    ) {
        for n in first + 1..=self.options.max_segments {
            let Some(found) = self.world.first_hit(&ray) else {
                segments.push(RaySegment::new(ray.origin, ray.direction, None, power));
                break;
            };
            let hit = found.hit;
            let mut segment = RaySegment::new(
                ray.origin,
                ray.direction,
                Some(SegmentHit {
                    triangle: hit.triangle,
                    mesh: found.mesh,
                    mobile: found.mobile,
                    position: hit.position,
                    normal: hit.geometric_normal,
                    distance: hit.t,
                }),
                power,
            );
            if let Some(statics) = self.statics.filter(|_| {
                self.options.extension > 0.0
                    && self
                        .concave
                        .get(found.mesh as usize)
                        .copied()
                        .unwrap_or(true)
            }) {
                let own = mesh_triangles(self.scene, found.mesh);
                segment.extension = extension(statics, &segment, own, self.options.extension);
            }
            segments.push(segment);
            if n == self.options.max_segments {
                break;
            }
            let Some(brdf) = self.brdfs.get(hit.material as usize) else {
                break;
            };
            let mut rng = bounce_stream(self.options.seed, light, index, n);
            let incoming = -ray.direction;
            let mut normal = hit.shading_normal;
            // Two-sided surfaces shade on the ray's side; a smooth dielectric
            // on its outside (the wound normal's), so that a ray inside the
            // medium meets η's inverse and total internal reflection (as in
            // lustre-photon's tracer).
            let side = if !brdf.is_two_sided() || incoming.dot(hit.geometric_normal) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            if normal.dot(hit.geometric_normal) * side < 0.0 {
                normal = -normal;
            }
            let frame = Frame::from_normal(normal);
            let u = rng.next_vec2();
            let u_lobe = rng.next_f32();
            // The adjoint BSDF f(ω_in, ω_out) carries the photon (Veach 3.7.6), as in lustre-photon's tracer.
            let wi = frame.to_local(incoming);
            let Some(sample) = brdf.sample_adjoint(wi, u, u_lobe) else {
                break;
            };
            // A diffuse map scales the Lambertian part per hit, as in lustre-photon's tracer.
            let w = match self.scene.materials().get(hit.material as usize) {
                Some(material) => {
                    lustre_photon::trace::textured_weight(material, hit.uv, wi, &sample)
                }
                None => sample.weight,
            };
            if !w.is_finite() || !(w.max_element() > 0.0) {
                break;
            }
            // Absorption by Russian roulette (lustre-photon's `trace` module).
            let q = w.max_element().min(1.0);
            if rng.next_f32() >= q {
                break;
            }
            power *= w.max(Rgb::ZERO) / q;
            let direction = frame.to_world(sample.wi).normalize_or_zero();
            if direction == Vec3::ZERO {
                break;
            }
            let g = hit.geometric_normal;
            let offset = if direction.dot(g) >= 0.0 { g } else { -g };
            ray = Ray::new(hit.position + self.epsilon * offset, direction);
        }
    }
}
