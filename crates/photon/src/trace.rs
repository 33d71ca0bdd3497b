//! Particle tracing (section 2.1): photons leave the lights, bounce by the BRDFs' samplers, and every surface hit becomes a [`HitRecord`].
//!
//! ## Absorption and reflection (Russian roulette)
//!
//! At a hit the photon arrives from `ω_in` (pointing away from the surface)
//! with attenuation `ρ`. Light travels from `ω_in` to `ω_out`, so in the
//! radiance convention `f(wi, wo)` of lustre-brdf the photon scatters with
//! `f(ω_in, ω_out)`: the adjoint BSDF `f*(ω_out, ω_in) = f(ω_in, ω_out)` of
//! the importance that particle tracing transports (Veach 1997, sections
//! 3.7.6 and 5.3.2). [`lustre_brdf::Brdf::sample_adjoint`], called with
//! `wi = ω_in`, draws `ω_out` with density `p` and weight
//! `w = f(ω_in, ω_out) |cos θ_out| / p` (RGB), the weight with which the
//! photon's power leaves along `ω_out`; `E[w]` is the fraction of the power
//! arriving from `ω_in` that the surface scatters (the directional albedo
//! `a(ω_in)` for a reciprocal model). Drawing with `wo = ω_in` and weighting
//! with `f(ω_out, ω_in)` instead would be right only for reciprocal models.
//! A random number `ξ` then decides between absorption
//! and reflection (section 2.1): the photon survives with probability
//! `q = min(1, max_c w_c)` and its attenuation becomes `ρ' = ρ w / q`. The
//! estimator stays unbiased: `E[ρ'] = q · ρ E[w | sampled] / q = ρ a(ω_in)`,
//! which is the power a real surface reflects. For a grey Lambertian surface
//! of albedo `a`, `w = a` and `q = a`, so `ρ` stays exactly 1 and the photon
//! survives with probability `a`: the paper's scheme. Coloured surfaces
//! survive with the largest channel and tint `ρ` by `w / q ≤ 1`. A sampler
//! that returns nothing (a draw where the BRDF is zero) absorbs the photon,
//! which is also unbiased since that draw contributes zero.
//!
//! Non-reciprocal models (the original Phong, Diefenbach's fit, Strauss) are
//! thus traced with their adjoint; refraction lacks the η² radiance scaling. A photon stops after
//! [`TraceOptions::max_bounces`] hits (a truncation bias below `a^max` of the
//! power), or when it leaves the scene.
//!
//! ## Diffuse texture maps
//!
//! A material's BRDF is built once, untextured; at a hit on a material with
//! a diffuse map its Lambertian part `ρ_d / π` is scaled by the map's tint
//! `t(uv)`, so the photon scatters with `f' = f + (t − 1) ⊙ ρ_d / π`. The
//! direction is still drawn by the untextured sampler and a smooth draw is
//! reweighted to `f' |cos θ_out| / p` (importance sampling with the
//! untextured proposal, unbiased since `f' > 0` only where `p > 0`); delta
//! draws are unchanged, and untextured materials take the path above.
//!
//! Surfaces are two-sided: the shading normal is flipped to the side the
//! photon arrives from. Planar surfaces use their [`crate::PlanarFrame`]
//! (tangent `u_axis`); curved ones the interpolated shading normal. A model
//! that is not two-sided ([`lustre_brdf::Brdf::is_two_sided`]: a smooth
//! dielectric) is the exception: its frame stays on its outside (the side of
//! the triangles' wound normal), so that a photon inside the medium leaves
//! it with η's inverse or is totally reflected (the pool's water traps a
//! good part of the light its floor sends up).

use lustre_brdf::{BoxedBrdf, BrdfSample, from_model};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, Hit, Ray, Scene};
use rayon::prelude::*;

use crate::emission::{EmissionSampling, allocate_photons, emission_numbers, photon_stream};
use crate::error::{PhotonError, Result};
use crate::hit_record::{HitRecord, PhotonMap};
use crate::parameterisation::{SurfaceParam, SurfaceParams};
use crate::progress::Progress;

/// Photons traced per task: the unit of parallel work and of progress reports; it does not change the result.
pub const PHOTONS_PER_CHUNK: u64 = 1024;

/// Photons traced per block of [`PhotonTracer::trace_streamed`]: the records of one block are what it holds in memory; it does not change the result.
pub const PHOTONS_PER_BLOCK: u64 = 1 << 18;

/// The photon range of batch `index` of `of` of a run that emits `counts[i]` photons from light `i` (section 2.1: photons are independent given their light and index): per light, the first photon index and the count, `⌊counts·index/of⌋ .. ⌊counts·(index+1)/of⌋`. The batches of one run tile its photons exactly.
pub fn batch_range(counts: &[u64], index: u64, of: u64) -> Result<(Vec<u64>, Vec<u64>)> {
    if of == 0 || index >= of {
        return Err(PhotonError::InvalidOption {
            option: "batch",
            message: format!("batch {index} of {of}: need 0 <= index < count"),
        });
    }
    let at = |c: u64, k: u64| (u128::from(c) * u128::from(k) / u128::from(of)) as u64;
    Ok(counts
        .iter()
        .map(|&c| {
            let lo = at(c, index);
            (lo, at(c, index + 1) - lo)
        })
        .unzip())
}

/// Receives each block of [`PhotonTracer::trace_streamed`]: the photons each light emitted in it and their hit records.
pub type BlockSink<'a> = dyn FnMut(&[u64], Vec<HitRecord>) -> Result<()> + 'a;

/// Settings of a particle-tracing run (section 2.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceOptions {
    /// Photons to emit over all lights, split in proportion to power.
    pub photons: u64,
    /// Seed of every random choice.
    pub seed: u64,
    /// Largest number of hits recorded per photon (1 to 255, the on-disk bounce field is one byte).
    pub max_bounces: u8,
    /// Pseudo-random or quasi-random emission.
    pub emission: EmissionSampling,
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self {
            photons: 100_000,
            seed: 0,
            max_bounces: 64,
            emission: EmissionSampling::Random,
        }
    }
}

/// A scene prepared for particle tracing: its BVH, one BRDF per material and the surface parameterisations (section 2.1).
#[derive(Debug)]
pub struct PhotonTracer<'a> {
    /// The scene.
    scene: &'a Scene,
    /// Its BVH (current pose).
    bvh: &'a Bvh,
    /// One BRDF per material.
    brdfs: Vec<BoxedBrdf>,
    /// Surface parameterisations.
    params: SurfaceParams,
    /// Offset of ray origins from surfaces, relative to the scene size.
    epsilon: f32,
}

/// The BRDF of every material of a scene, with the material named on failure.
pub fn scene_brdfs(scene: &Scene) -> Result<Vec<BoxedBrdf>> {
    scene
        .materials()
        .iter()
        .map(|m| {
            from_model(&m.model).map_err(|source| PhotonError::Brdf {
                material: m.name.clone(),
                source,
            })
        })
        .collect()
}

impl<'a> PhotonTracer<'a> {
    /// Prepares a scene; fails when a material has no valid BRDF.
    pub fn new(scene: &'a Scene, bvh: &'a Bvh) -> Result<Self> {
        let scale = scene.bounds().extent().max_element();
        let scale = if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        };
        Ok(Self {
            scene,
            bvh,
            brdfs: scene_brdfs(scene)?,
            params: SurfaceParams::new(scene),
            epsilon: scale * 1e-5,
        })
    }

    /// The surface parameterisations used for the records' positions.
    pub fn params(&self) -> &SurfaceParams {
        &self.params
    }

    /// Traces `options.photons` photons into a new map (section 2.1).
    pub fn trace(&self, options: &TraceOptions, progress: &dyn Progress) -> Result<PhotonMap> {
        let mut map = PhotonMap::for_scene(self.scene);
        self.trace_more(&mut map, options, progress)?;
        Ok(map)
    }

    /// Traces `options.photons` more photons into an existing map (incremental refinement, section 2.1): each light's photon indices continue from its emitted count `m_i`, so no photon repeats an earlier one, and earlier records are not touched.
    pub fn trace_more(
        &self,
        map: &mut PhotonMap,
        options: &TraceOptions,
        progress: &dyn Progress,
    ) -> Result<()> {
        self.check_options(options)?;
        let powers: Vec<_> = self.scene.lights().iter().map(|l| l.power()).collect();
        map.check_same_lights(PhotonMap::new(powers.iter().copied()).lights())?;
        let counts = allocate_photons(&powers, options.photons);
        let first: Vec<u64> = map.lights().iter().map(|l| l.emitted).collect();
        let total: u64 = counts.iter().sum();
        progress.begin(total);
        let (emitted, records) = self.trace_block(&first, &counts, 0..total, options, progress);
        progress.finish();
        map.extend_traced(&emitted, records);
        Ok(())
    }

    /// Traces photons `first[i] .. first[i] + counts[i]` of each light `i`
    /// (section 2.1) in blocks of [`PHOTONS_PER_BLOCK`], handing each block's
    /// emitted counts and hit records to `sink` in emission order, so memory
    /// holds one block whatever the count (the records go to a
    /// [`crate::PhotonFileWriter`]). The records equal those of one
    /// [`PhotonTracer::trace_more`] over the same photons.
    pub fn trace_streamed(
        &self,
        first: &[u64],
        counts: &[u64],
        options: &TraceOptions,
        progress: &dyn Progress,
        sink: &mut BlockSink<'_>,
    ) -> Result<()> {
        self.check_options(options)?;
        let lights = self.scene.lights().len();
        if first.len() != lights || counts.len() != lights {
            return Err(PhotonError::InvalidOption {
                option: "photon ranges",
                message: format!(
                    "{} first indices and {} counts for {lights} lights",
                    first.len(),
                    counts.len()
                ),
            });
        }
        if let Some(i) = (0..lights).find(|&i| first[i].checked_add(counts[i]).is_none()) {
            return Err(PhotonError::InvalidOption {
                option: "photon ranges",
                message: format!("light #{i}: photon indices overflow 64 bits"),
            });
        }
        let total = counts
            .iter()
            .try_fold(0u64, |a, &c| a.checked_add(c))
            .ok_or_else(|| PhotonError::InvalidOption {
                option: "photons",
                message: "more than 2^64 photons".into(),
            })?;
        progress.begin(total);
        let mut lo = 0;
        while lo < total {
            let hi = (lo + PHOTONS_PER_BLOCK).min(total);
            let (emitted, records) = self.trace_block(first, counts, lo..hi, options, progress);
            sink(&emitted, records)?;
            lo = hi;
        }
        progress.finish();
        Ok(())
    }

    /// Fails on options no run can use.
    fn check_options(&self, options: &TraceOptions) -> Result<()> {
        if options.max_bounces == 0 {
            return Err(PhotonError::InvalidOption {
                option: "max_bounces",
                message: "must be at least 1".into(),
            });
        }
        if self.scene.lights().len() > u32::MAX as usize {
            return Err(PhotonError::InvalidOption {
                option: "lights",
                message: "more than 2^32 lights".into(),
            });
        }
        Ok(())
    }

    /// Traces the photons numbered `block` of the run that numbers light
    /// `i`'s photons `first[i] .. first[i] + counts[i]` consecutively, light
    /// by light, in parallel chunks of [`PHOTONS_PER_CHUNK`]: the photons
    /// each light emitted in the block and their records, in order.
    fn trace_block(
        &self,
        first: &[u64],
        counts: &[u64],
        block: std::ops::Range<u64>,
        options: &TraceOptions,
        progress: &dyn Progress,
    ) -> (Vec<u64>, Vec<HitRecord>) {
        // Global photon numbers 0..total, light by light.
        let mut starts = Vec::with_capacity(counts.len() + 1);
        let mut total = 0u64;
        for &c in counts {
            starts.push(total);
            total += c;
        }
        starts.push(total);
        let emitted: Vec<u64> = (0..counts.len())
            .map(|l| {
                block
                    .end
                    .min(starts[l + 1])
                    .saturating_sub(block.start.max(starts[l]))
            })
            .collect();
        let chunks = (block.end - block.start).div_ceil(PHOTONS_PER_CHUNK);
        let records: Vec<Vec<HitRecord>> = (0..chunks)
            .into_par_iter()
            .map(|chunk| {
                let lo = block.start + chunk * PHOTONS_PER_CHUNK;
                let hi = (lo + PHOTONS_PER_CHUNK).min(block.end);
                let mut out = Vec::new();
                let mut light = starts.partition_point(|&s| s <= lo) - 1;
                for g in lo..hi {
                    while g >= starts[light + 1] {
                        light += 1;
                    }
                    let index = first[light] + (g - starts[light]);
                    self.trace_photon(light as u32, index, options, &mut out);
                }
                progress.advance(hi - lo);
                out
            })
            .collect();
        (emitted, records.into_iter().flatten().collect())
    }

    /// The shading frame at a hit, on the side of `side` (two-sided surfaces).
    fn frame_at(&self, hit: &Hit, side: glam::Vec3) -> Frame {
        match self.params.get(hit.surface) {
            Some(SurfaceParam::Planar(frame)) => frame.shading_frame(side),
            _ => {
                let geometric_side = if side.dot(hit.geometric_normal) >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
                let mut n = hit.shading_normal;
                if n.dot(hit.geometric_normal) * geometric_side < 0.0 {
                    n = -n;
                }
                Frame::from_normal(n)
            }
        }
    }

    /// Follows one photon until it is absorbed, leaves the scene or reaches `max_bounces`, pushing a record per hit (section 2.1).
    fn trace_photon(
        &self,
        light: u32,
        index: u64,
        options: &TraceOptions,
        out: &mut Vec<HitRecord>,
    ) {
        let source = &self.scene.lights()[light as usize];
        let mut rng = photon_stream(options.seed, light, index);
        let (u_position, u_direction) =
            emission_numbers(options.emission, options.seed, light, index, &mut rng);
        let e = source.sample_emission(u_position, u_direction);
        let power = source.power();
        // ρ₀ = weight / Φ: 1 for uniform emitters, the fall-off for spot lights.
        let rho0 = glam::Vec3::select(
            power.cmpgt(glam::Vec3::ZERO),
            e.weight / power,
            glam::Vec3::ZERO,
        );
        if !rho0.is_finite() || rho0.max_element() <= 0.0 || !e.direction.is_finite() {
            return;
        }
        let mut rho = rho0;
        let side = if e.direction.dot(e.normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        // Off the emitting surface, point lights too: the cosine point light
        // that replaces an area light (Scene::with_area_lights_as_points) sits
        // on its emitter, which stays as geometry, and a photon leaving it
        // from the surface itself hit it at t = 0 and was trapped between the
        // emitter and the ceiling (a fifth too little light with
        // `--light-samples 1` before this offset).
        let origin = e.position + side * self.epsilon * e.normal;
        let mut ray = Ray::new(origin, e.direction);
        for bounce in 1..=options.max_bounces {
            let Some(hit) = self.bvh.closest_hit(&ray) else {
                return;
            };
            let incoming = -ray.direction;
            let triangle = self.params.local_triangle(hit.triangle);
            out.push(HitRecord {
                surface: hit.surface,
                triangle,
                position: self.params.position_of(
                    hit.surface,
                    hit.position,
                    glam::Vec2::new(hit.u, hit.v),
                ),
                direction: incoming,
                light,
                bounce,
                rho,
            });
            if bounce == options.max_bounces {
                return;
            }
            let Some(brdf) = self.brdfs.get(hit.material as usize) else {
                return;
            };
            // A dielectric knows its inside by the side: its frame stays on
            // the outside (the wound normal's side), so a photon inside the
            // medium arrives with `wi.z < 0` and meets η's inverse and total
            // internal reflection; every other surface is two-sided.
            let frame = self.frame_at(
                &hit,
                if brdf.is_two_sided() {
                    incoming
                } else {
                    hit.geometric_normal
                },
            );
            let wi = frame.to_local(incoming);
            let u = rng.next_vec2();
            let u_lobe = rng.next_f32();
            // The adjoint: the photon leaves along `sample.wi` with f(ω_in, ω_out).
            let Some(sample) = brdf.sample_adjoint(wi, u, u_lobe) else {
                return;
            };
            // A textured material's Lambertian part, applied per hit (module documentation).
            let w = match self.scene.materials().get(hit.material as usize) {
                Some(material) => textured_weight(material, hit.uv, wi, &sample),
                None => sample.weight,
            };
            if !w.is_finite() || !(w.max_element() > 0.0) {
                return;
            }
            // Russian roulette on the sample weight (module documentation).
            let q = w.max_element().min(1.0);
            if rng.next_f32() >= q {
                return;
            }
            rho *= w.max(glam::Vec3::ZERO) / q;
            let direction = frame.to_world(sample.wi).normalize_or_zero();
            if direction == glam::Vec3::ZERO {
                return;
            }
            let n = hit.geometric_normal;
            let offset = if direction.dot(n) >= 0.0 { n } else { -n };
            ray = Ray::new(hit.position + self.epsilon * offset, direction);
        }
    }
}

/// The adjoint weight of `sample`, drawn by [`lustre_brdf::Brdf::sample_adjoint`]
/// for light arriving from the local direction `wi`, on a surface of
/// `material` at texture coordinates `uv`: `sample.weight` itself for an
/// untextured material or a delta draw; for a smooth draw on a material with
/// a diffuse map, `f'(ω_in, ω_out) |cos θ_out| / p` with
/// `f' = f + (t(uv) − 1) ⊙ ρ_d / π` on the upper hemisphere (where the
/// Lambertian part lives), from `sample.weight = f |cos θ_out| / p` and its
/// density `p`. The proposal is the untextured one, so the estimate stays
/// unbiased wherever `f' > 0` implies `p > 0`: `f' ≤ f` for `t ≤ 1`, and a
/// Lambertian part with `ρ_d > 0` is always drawn with positive density.
pub fn textured_weight(
    material: &lustre_geometry::Material,
    uv: glam::Vec2,
    wi: glam::Vec3,
    sample: &BrdfSample,
) -> glam::Vec3 {
    let (w, pdf, wo) = (sample.weight, sample.pdf, sample.wi);
    let Some(shift) = material.diffuse_shift(uv) else {
        return w;
    };
    if sample.delta || !(wi.z > 0.0 && wo.z > 0.0) || !(pdf > 0.0 && pdf.is_finite()) {
        return w;
    }
    (w + shift * (wo.z / pdf)).max(glam::Vec3::ZERO)
}

/// Traces `options.photons` photons through a scene (section 2.1): builds the BRDFs and parameterisations, then runs [`PhotonTracer::trace`] on the current rayon pool.
pub fn trace_photons(
    scene: &Scene,
    bvh: &Bvh,
    options: &TraceOptions,
    progress: &dyn Progress,
) -> Result<PhotonMap> {
    PhotonTracer::new(scene, bvh)?.trace(options, progress)
}
