//! The beams of a scene and their evaluation at fragments: the paper's linear traversal over all beams (Duvenhage et al. 2010, section 4.3) and the hierarchical one (section 5.2, future work), which give the same sums.

use glam::Vec3;
use lustre_geometry::{Aabb, Rgb, Scene};
use rayon::prelude::*;

use crate::beam::{Beam, BeamSlab};
use crate::construction::{BuildOptions, BuildStats, build_beams};
use crate::error::{BeamError, Result};
use crate::hierarchy::BeamHierarchy;
use crate::scatterer::{BeamInput, PointSource, Scatterer};

/// Relative padding of the beam boxes (of the bounds' diagonal), so that rounding in the point-in-beam test never puts a point outside its beam's box.
const BOX_PADDING: f32 = 1e-4;
/// Boxes per beam at most: slabs along its mean direction, so that a long beam crossing the scene diagonally is not one large box.
const SLABS: usize = 64;

/// Every scattered and shadow beam of a set of point lights and scatterers, with a hierarchy over their volumes clipped to `bounds`.
#[derive(Debug, Clone)]
pub struct BeamSet {
    beams: Vec<Beam>,
    lights: Vec<PointSource>,
    stats: BuildStats,
    bounds: Aabb,
    hierarchy: BeamHierarchy,
    /// The beam of each box in the hierarchy.
    owner: Vec<u32>,
    /// The range of flux-plane offsets of each box's slab ([`crate::BeamSlab::along`]).
    along: Vec<[f32; 2]>,
}

impl BeamSet {
    /// Builds the beams (in parallel) and their hierarchy; `bounds` is the region where fragments are evaluated through the hierarchy (the scene's box; points outside it fall back to the linear traversal). Errors on no light or non-finite input.
    pub fn build(
        lights: &[PointSource],
        scatterers: &[Scatterer],
        bounds: Aabb,
        options: &BuildOptions,
    ) -> Result<Self> {
        if lights.is_empty() {
            return Err(BeamError::NoPointLight { lights: 0 });
        }
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(BeamError::InvalidInput {
                what: "bounds".into(),
                message: "must be a finite, non-empty box".into(),
            });
        }
        let (beams, stats) = build_beams(lights, scatterers, options)?;
        let pad = Vec3::splat(BOX_PADDING * bounds.extent().length());
        let pieces: Vec<Vec<BeamSlab>> = beams
            .par_iter()
            .map(|b| b.slabs_within(bounds, SLABS))
            .collect();
        let (mut boxes, mut owner, mut along) = (Vec::new(), Vec::new(), Vec::new());
        for (i, p) in pieces.into_iter().enumerate() {
            for slab in p.into_iter().filter(|s| !s.bounds.is_empty()) {
                boxes.push(Aabb {
                    min: slab.bounds.min - pad,
                    max: slab.bounds.max + pad,
                });
                owner.push(i as u32);
                along.push(slab.along);
            }
        }
        let hierarchy = BeamHierarchy::build(&boxes);
        Ok(Self {
            beams,
            lights: lights.to_vec(),
            stats,
            bounds,
            hierarchy,
            owner,
            along,
        })
    }

    /// The beams of a scene's point lights through its scatterer triangles ([`BeamInput::from_scene`]), bounded by the scene's box.
    pub fn from_scene(scene: &Scene, options: &BuildOptions) -> Result<Self> {
        let input = BeamInput::from_scene(scene)?;
        Self::build(&input.lights, &input.scatterers, scene.bounds(), options)
    }

    /// The beams, in construction order (light-major, then scatterer).
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }

    /// The point lights.
    pub fn lights(&self) -> &[PointSource] {
        &self.lights
    }

    /// What construction built and skipped.
    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    /// The region the hierarchy covers.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The beam irradiance at a fragment: the sum over every beam of [`Beam::irradiance`] (caustics and glossy light added, shadow beams' blocked light subtracted), visiting all beams in order: the paper's linear traversal (section 4.3).
    pub fn irradiance_at_linear(&self, p: Vec3, normal: Vec3) -> Rgb {
        self.irradiance_summed(p, normal, false)
    }

    /// The indices of the beams the hierarchy offers for `p` (a superset of those whose support holds `p`), ascending; every beam when `p` is outside [`BeamSet::bounds`].
    pub fn candidates(&self, p: Vec3) -> Vec<u32> {
        if !self.bounds.contains(p) {
            return (0..self.beams.len() as u32).collect();
        }
        let mut out = Vec::new();
        self.hierarchy
            .for_each_containing(p, |i| out.push(self.owner[i as usize]));
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The same sum as [`BeamSet::irradiance_at_linear`], over the beams the hierarchy offers, in the same order (so equal to it, not just close).
    pub fn irradiance_at(&self, p: Vec3, normal: Vec3) -> Rgb {
        self.irradiance_summed(p, normal, true)
    }

    /// The sum of [`BeamSet::for_each_arrival`]'s irradiances.
    fn irradiance_summed(&self, p: Vec3, normal: Vec3, hierarchy: bool) -> Rgb {
        let mut sum = Rgb::ZERO;
        self.for_each_arrival(p, normal, hierarchy, |_, e, _| sum += e);
        sum
    }

    /// The hierarchy over the beams' slab boxes.
    pub fn hierarchy(&self) -> &BeamHierarchy {
        &self.hierarchy
    }

    /// The beam of hierarchy item `item` ([`BeamHierarchy::items`]) and its slab's range of flux-plane offsets `[lo, hi)` ([`crate::BeamSlab::along`]).
    pub fn item(&self, item: u32) -> (u32, [f32; 2]) {
        (self.owner[item as usize], self.along[item as usize])
    }

    /// Calls `visit(beam, E, d)` for every beam that lights a fragment at `p` with unit normal `normal`: its irradiance ([`Beam::irradiance`]) and the unit direction its light travels there ([`Beam::arrival`]). With `hierarchy`, over the beams the hierarchy offers, in ascending order (as [`BeamSet::irradiance_at`]); without, over all beams (as [`BeamSet::irradiance_at_linear`]).
    pub fn for_each_arrival(
        &self,
        p: Vec3,
        normal: Vec3,
        hierarchy: bool,
        mut visit: impl FnMut(&Beam, Rgb, Vec3),
    ) {
        let mut one = |b: &Beam| {
            if let Some((e, d)) = b.arrival(p, normal) {
                visit(b, e, d);
            }
        };
        if hierarchy {
            for i in self.candidates(p) {
                one(&self.beams[i as usize]);
            }
        } else {
            self.beams.iter().for_each(one);
        }
    }

    /// The unoccluded direct irradiance `Σ I cos θ / r²` of the point lights at a fragment; with the shadow beams of [`BeamSet::irradiance_at`] it gives first-order shadows (section 3.1).
    pub fn direct_irradiance(&self, p: Vec3, normal: Vec3) -> Rgb {
        direct_irradiance(&self.lights, p, normal)
    }
}

/// `Σ I(ω) cos θ / r²` over point lights, without occlusion.
pub fn direct_irradiance(lights: &[PointSource], p: Vec3, normal: Vec3) -> Rgb {
    lights.iter().fold(Rgb::ZERO, |acc, l| {
        let d = l.position - p;
        let r2 = d.length_squared();
        if !(r2 > 0.0) {
            return acc;
        }
        let w = d / r2.sqrt();
        let cos = normal.dot(w);
        if cos <= 0.0 {
            acc
        } else {
            acc + l.intensity_towards(-w) * cos / r2
        }
    })
}
