//! Progressive refinement (Stürzlinger & Bastos 1997, section 2.1): the lighting phase runs on a background thread at growing photon counts, each solution handed to the window as it is done, so the first frame appears at once and the image refines while the user looks.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use lustre_geometry::Scene;
use serde_json::{Map, Value};

use crate::render::{Lit, Prepared, RenderArgs, light};

/// Fewest photons worth a stage of their own.
pub const MIN_STAGE_PHOTONS: u64 = 10_000;

/// Photon counts of the stages for `total` photons: an eighth of the next each, the smallest at least [`MIN_STAGE_PHOTONS`], the last `total`.
pub fn stage_photons(total: u64) -> Vec<u64> {
    let mut stages = vec![total];
    let mut n = total / 8;
    while n >= MIN_STAGE_PHOTONS && stages.len() < 3 {
        stages.push(n);
        n /= 8;
    }
    stages.reverse();
    stages
}

/// What the lighting thread sends the window.
pub enum LightingEvent {
    /// One stage's solution.
    Stage {
        /// The run it belongs to (older runs' stages are dropped).
        run: u64,
        /// Its lighting.
        lit: Box<Lit>,
        /// Photons it traced.
        photons: u64,
        /// Its index and the number of stages.
        stage: (usize, usize),
        /// The lighting phases' times (ms).
        timings: Map<String, Value>,
    },
    /// The lighting failed; the message names the cause.
    Failed {
        /// The run it belongs to.
        run: u64,
        /// What went wrong.
        message: String,
    },
}

/// A running lighting thread; dropping it asks the thread to stop after its current stage.
pub struct LightingRun {
    /// The run's number.
    pub id: u64,
    cancel: Arc<AtomicBool>,
}

impl Drop for LightingRun {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// Starts the lighting of `prepared` for `args` at every stage of [`stage_photons`], sending each result through `send`.
pub fn spawn(
    id: u64,
    args: RenderArgs,
    prepared: Arc<Prepared>,
    shadow_depth: u32,
    send: impl Fn(LightingEvent) + Send + 'static,
) -> LightingRun {
    let cancel = Arc::new(AtomicBool::new(false));
    let stop = Arc::clone(&cancel);
    std::thread::spawn(move || {
        let stages = stage_photons(args.photons);
        for (i, &photons) in stages.iter().enumerate() {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            let stage_args = RenderArgs {
                photons,
                ..args.clone()
            };
            let mut timings = Map::new();
            let scene: &Scene = &prepared.scene;
            match light(
                &stage_args,
                scene,
                shadow_depth,
                prepared.density,
                prepared.lengths,
                &mut timings,
            ) {
                Ok(lit) => send(LightingEvent::Stage {
                    run: id,
                    lit: Box::new(lit),
                    photons,
                    stage: (i, stages.len()),
                    timings,
                }),
                Err(e) => {
                    send(LightingEvent::Failed {
                        run: id,
                        message: format!("{e:#}"),
                    });
                    return;
                }
            }
        }
    });
    LightingRun { id, cancel }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_grow_by_eight_and_end_at_the_total() {
        assert_eq!(stage_photons(1_000_000), vec![15_625, 125_000, 1_000_000]);
        assert_eq!(stage_photons(100_000), vec![12_500, 100_000]);
        assert_eq!(stage_photons(50_000), vec![50_000]);
        assert_eq!(stage_photons(1), vec![1]);
        assert_eq!(
            stage_photons(100_000_000),
            vec![1_562_500, 12_500_000, 100_000_000]
        );
    }
}
