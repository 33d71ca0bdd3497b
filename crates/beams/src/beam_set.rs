//! The beams of a scene and their evaluation at fragments: the paper's linear traversal over all beams (Duvenhage et al. 2010, section 4.3) and the hierarchical one (section 5.2, future work), which give the same sums.

use glam::Vec3;
use lustre_geometry::{Aabb, Rgb, Scene};
use rayon::prelude::*;

use crate::beam::Beam;
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
        let pieces: Vec<Vec<Aabb>> = beams
            .par_iter()
            .map(|b| b.bounds_within(bounds, SLABS))
            .collect();
        let (mut boxes, mut owner) = (Vec::new(), Vec::new());
        for (i, p) in pieces.into_iter().enumerate() {
            for bb in p.into_iter().filter(|bb| !bb.is_empty()) {
                boxes.push(Aabb {
                    min: bb.min - pad,
                    max: bb.max + pad,
                });
                owner.push(i as u32);
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
        self.beams
            .iter()
            .fold(Rgb::ZERO, |acc, b| acc + b.irradiance(p, normal))
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
        self.candidates(p).into_iter().fold(Rgb::ZERO, |acc, i| {
            acc + self.beams[i as usize].irradiance(p, normal)
        })
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
