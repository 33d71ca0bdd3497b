//! What the splats need of the whole photon map before any of them is made (sections 2.1 and 2.2): a map streamed from a file in batches is tallied in a first pass.
//!
//! Equation 3 sizes a surface's kernels from the number `n` of photons on
//! it, so the splats of one batch of a file ([`crate::PhotonFileReader::batches`])
//! need every batch's count; the diffuse textures need to know which sides
//! of each planar surface any photon reached. [`SplatTally`] gathers both,
//! batch by batch, and [`crate::SplatEstimator::build_tallied`] builds one
//! batch's estimator with the whole map's supports, so the batches' splats
//! add up to the splats of the whole map.

use crate::error::{PhotonError, Result};
use crate::estimator::BounceSelection;
use crate::hit_record::HitRecord;
use crate::parameterisation::{SurfaceParam, SurfaceParams};

/// Selected photons per surface, and the sides of planar surfaces they arrive from, over a whole photon map (equation 3's `n`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplatTally {
    /// The bounces counted.
    pub selection: BounceSelection,
    /// Selected photons per `SurfaceId`.
    pub counts: Vec<usize>,
    /// Per `SurfaceId` of a planar surface: whether a selected photon arrived from the side of its frame's normal (`[0]`) or the other side (`[1]`).
    pub lit: Vec<[bool; 2]>,
}

impl SplatTally {
    /// An empty tally of the surfaces of `params`.
    pub fn new(params: &SurfaceParams, selection: BounceSelection) -> Self {
        Self {
            selection,
            counts: vec![0; params.len()],
            lit: vec![[false; 2]; params.len()],
        }
    }

    /// Counts the selected records of one batch; a record on a surface `params` lacks is an error naming it (by its index in `records`).
    pub fn add(&mut self, params: &SurfaceParams, records: &[HitRecord]) -> Result<()> {
        for (index, r) in records.iter().enumerate() {
            if !self.selection.selects(r) {
                continue;
            }
            let s = r.surface as usize;
            let count = self
                .counts
                .get_mut(s)
                .ok_or_else(|| PhotonError::InvalidRecord {
                    index,
                    message: format!("surface {} does not exist in the scene", r.surface),
                })?;
            *count += 1;
            if let Some(SurfaceParam::Planar(frame)) = params.get(r.surface) {
                let d = r.direction.dot(frame.normal);
                if d > 0.0 {
                    self.lit[s][0] = true;
                } else if d < 0.0 {
                    self.lit[s][1] = true;
                }
            }
        }
        Ok(())
    }
}
