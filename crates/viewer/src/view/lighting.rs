//! Progressive refinement (Stürzlinger & Bastos 1997, section 2.1): the lighting phase runs on a background thread at growing photon counts, each solution handed to the window as it is done, so the first frame appears at once and the image refines while the user looks. Per-vertex techniques run live instead ([`spawn_quasi_static`]): the mobile objects move with the quasi-static update of García et al. 2003, section 2.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Context;
use glam::{Affine3A, Vec3};
use lustre_density::QuasiStatic;
use lustre_geometry::{Camera, ObjectId, ObjectPath, Scene};
use lustre_mpr::GpuContext;
use lustre_mpr::passes::glossy_image::GlossySettings;
use serde_json::{Map, Value};

use crate::gpu_frame::GpuFrame;
use crate::render::{Prepared, RenderArgs, light};
use crate::render_density::{corners_towards, explain_too_many_rays};

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

/// The mobile objects' transforms in one pose (García et al. 2003, section 2.2.2).
pub type ObjectPose = Vec<(ObjectId, Affine3A)>;

/// What the lighting thread sends the window.
pub enum LightingEvent {
    /// A quasi-static frame of a per-vertex technique ([`spawn_quasi_static`]): the mobile objects' pose and the per-vertex radiance towards the window's eye.
    Pose {
        /// The run it belongs to.
        run: u64,
        /// The mobile objects' transforms in this pose (none without mobile objects).
        pose: ObjectPose,
        /// Per-corner radiance for the Gouraud pass.
        corners: Vec<[f32; 3]>,
        /// Frames of the run so far, this one included.
        frame: u64,
        /// Seconds along the mobile objects' paths (from each path's start) of this pose.
        seconds: f32,
        /// The eye the glossy radiance was computed towards.
        eye: Vec3,
        /// The ray-set recalculation and radiosity update of this frame (ms), or the first frame's.
        update_ms: f64,
    },
    /// One stage's solution.
    Stage {
        /// The run it belongs to (older runs' stages are dropped).
        run: u64,
        /// Its GPU frame, built on the lighting thread with everything it
        /// uploads and captures (splats, diffuse textures, radiance maps),
        /// so that the window keeps drawing the last one meanwhile.
        gpu: Box<GpuFrame>,
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

/// Where a stage's GPU frame is built: the window's device, the render's size and the camera when the run started (the splats' `auto` resolution).
pub struct FrameTarget {
    /// The window's device.
    pub ctx: GpuContext,
    /// The render's size.
    pub size: (u32, u32),
    /// The camera.
    pub camera: Camera,
}

/// Starts the lighting of `prepared` for `args` at every stage of [`stage_photons`], building each stage's frame for `target` and sending it through `send`.
pub fn spawn(
    id: u64,
    args: RenderArgs,
    prepared: Arc<Prepared>,
    (shadow_depth, glossy_images): (u32, GlossySettings),
    target: FrameTarget,
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
            let frame = light(
                &stage_args,
                scene,
                shadow_depth,
                prepared.density,
                prepared.lengths,
                &mut timings,
            )
            .and_then(|lit| {
                let start = Instant::now();
                let gpu = GpuFrame::new(
                    &stage_args,
                    lit.lighting(scene, shadow_depth, glossy_images),
                    target.ctx.clone(),
                    target.size,
                    &target.camera,
                )?;
                timings.insert(
                    "gpu_frame".into(),
                    Value::from(start.elapsed().as_secs_f64() * 1e3),
                );
                Ok(gpu)
            });
            match frame {
                Ok(gpu) => send(LightingEvent::Stage {
                    run: id,
                    gpu: Box::new(gpu),
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

/// The window's state a quasi-static run reads and writes.
#[derive(Clone)]
pub struct LiveView {
    /// The eye the glossy per-vertex radiance is computed towards (section 2.10), written by the window each frame.
    pub eye: Arc<Mutex<Vec3>>,
    /// A pose sent and not yet drawn: the run waits for the window before it computes the next.
    pub pending: Arc<AtomicBool>,
}

impl LiveView {
    /// A view from `eye` with nothing pending.
    pub fn new(eye: Vec3) -> Self {
        Self {
            eye: Arc::new(Mutex::new(eye)),
            pending: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The eye now.
    pub fn eye(&self) -> Vec3 {
        *self.eye.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Moves the eye.
    pub fn set_eye(&self, eye: Vec3) {
        *self.eye.lock().unwrap_or_else(|e| e.into_inner()) = eye;
    }
}

/// Time along `path` after `seconds` of wall-clock time: the path played from its start and repeated (a clamped path jumps back to its start).
pub fn path_time(path: &ObjectPath, seconds: f32) -> f32 {
    let duration = path.duration();
    if duration > 0.0 {
        path.start() + seconds.rem_euclid(duration)
    } else {
        path.start()
    }
}

/// Runs a per-vertex technique live (García et al. 2003, section 2): the ray
/// set and the per-vertex estimate once (section 2.3–2.4), then, while the
/// window is open, the mobile objects moved along their paths at wall-clock
/// time with the quasi-static recalculation (figure 2.2, equation 2.4) and
/// the glossy radiance recomputed towards the window's eye, each frame sent
/// as a [`LightingEvent::Pose`] once the window has drawn the one before.
/// With `object_time` the objects hold that pose (seconds from their
/// paths' starts); then, as in a scene without mobile objects, a frame is
/// computed only when the eye moves.
pub fn spawn_quasi_static(
    id: u64,
    args: RenderArgs,
    prepared: Arc<Prepared>,
    view: LiveView,
    object_time: Option<f32>,
    send: impl Fn(LightingEvent) + Send + 'static,
) -> LightingRun {
    let cancel = Arc::new(AtomicBool::new(false));
    let stop = Arc::clone(&cancel);
    std::thread::spawn(move || {
        let run = QuasiStaticRun {
            id,
            args: &args,
            prepared: &prepared,
            view: &view,
            object_time,
        };
        if let Err(e) = run.run(&stop, &send) {
            send(LightingEvent::Failed {
                run: id,
                message: format!("{e:#}"),
            });
        }
    });
    LightingRun { id, cancel }
}

/// What [`spawn_quasi_static`]'s thread works with.
struct QuasiStaticRun<'a> {
    id: u64,
    args: &'a RenderArgs,
    prepared: &'a Prepared,
    view: &'a LiveView,
    object_time: Option<f32>,
}

impl QuasiStaticRun<'_> {
    /// The thread's body: the first frame, then a frame per pose or eye until `stop`.
    fn run(&self, stop: &AtomicBool, send: &impl Fn(LightingEvent)) -> anyhow::Result<()> {
        let (Some(estimator), Some(lengths)) =
            (self.prepared.density, self.prepared.lengths.as_ref())
        else {
            anyhow::bail!("a quasi-static run needs a per-vertex technique");
        };
        let scene = self.prepared.scene.clone();
        let paths = scene.mobile_objects().to_vec();
        let ids: Vec<ObjectId> = paths.iter().map(|m| m.object).collect();
        let mut sim = QuasiStatic::new(
            scene,
            &ids,
            self.args.density_settings(lengths).options(estimator),
        )
        .map_err(explain_too_many_rays)
        .with_context(|| format!("{} first frame", estimator.name()))?;
        let first = sim.first_frame();
        let mut update = first.photosimulation + first.radiosity;
        let moving = !paths.is_empty() && self.object_time.is_none();
        let clock = Instant::now();
        let mut last_eye = None;
        let mut frame = 0u64;
        let mut seconds = self.object_time.unwrap_or(0.0);
        let mut pose = ObjectPose::new();
        while !stop.load(Ordering::Relaxed) {
            let eye = self.view.eye();
            let waiting = self.view.pending.load(Ordering::Acquire)
                || (frame > 0 && !moving && last_eye == Some(eye));
            if waiting {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
            // The first frame's pose, then every frame's while they move.
            if !paths.is_empty() && (frame == 0 || moving) {
                if moving {
                    seconds = clock.elapsed().as_secs_f32();
                }
                pose = paths
                    .iter()
                    .map(|m| (m.object, m.path.at(path_time(&m.path, seconds))))
                    .collect();
                let stats = sim.set_pose(&pose)?;
                let this = stats.photosimulation + stats.radiosity;
                update = if frame == 0 { update + this } else { this };
            }
            let corners = corners_towards(&sim, eye)?;
            last_eye = Some(eye);
            frame += 1;
            self.view.pending.store(true, Ordering::Release);
            send(LightingEvent::Pose {
                run: self.id,
                pose: pose.clone(),
                corners,
                frame,
                seconds,
                eye,
                update_ms: update.as_secs_f64() * 1e3,
            });
        }
        Ok(())
    }
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

    /// The next pose of a live run (the window's part: marks it drawn).
    fn next_pose(
        events: &std::sync::mpsc::Receiver<LightingEvent>,
        view: &LiveView,
    ) -> (ObjectPose, Vec<[f32; 3]>, u64, f32) {
        match events
            .recv_timeout(Duration::from_secs(300))
            .expect("a pose within 5 minutes")
        {
            LightingEvent::Pose {
                pose,
                corners,
                frame,
                seconds,
                ..
            } => {
                view.pending.store(false, Ordering::Release);
                (pose, corners, frame, seconds)
            }
            LightingEvent::Failed { message, .. } => panic!("{message}"),
            LightingEvent::Stage { .. } => panic!("a live run sends poses, not stages"),
        }
    }

    #[test]
    fn a_live_run_moves_the_objects_with_the_clock_or_holds_them() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            render: RenderArgs,
        }
        let args = Cli::parse_from([
            "lustre",
            "cornell",
            "--technique",
            "detp",
            "--photons",
            "2000",
        ])
        .render;
        let prepared = Arc::new(crate::render::prepare_scene(&args).unwrap());
        let small_box = prepared.scene.mobile_objects()[0].object;
        let triangles = prepared.scene.triangle_count();
        // The small box's transform in a pose.
        let transform = |pose: &[(ObjectId, Affine3A)]| {
            assert_eq!(pose.len(), 1, "cornell moves one object");
            assert_eq!(pose[0].0, small_box);
            pose[0].1
        };
        let start = |held: Option<f32>, view: &LiveView| {
            let (send, events) = std::sync::mpsc::channel();
            let run = spawn_quasi_static(
                7,
                args.clone(),
                Arc::clone(&prepared),
                view.clone(),
                held,
                move |e| {
                    let _ = send.send(e);
                },
            );
            (run, events)
        };

        // With the clock: each pose later along the path, the box moved.
        let view = LiveView::new(prepared.scene.camera().position);
        let (run, events) = start(None, &view);
        let poses: Vec<_> = (0..3).map(|_| next_pose(&events, &view)).collect();
        drop(run);
        for (i, (_, corners, frame, _)) in poses.iter().enumerate() {
            assert_eq!(*frame, i as u64 + 1);
            assert_eq!(corners.len(), 3 * triangles);
        }
        assert!(poses[0].3 < poses[1].3 && poses[1].3 < poses[2].3);
        assert_ne!(transform(&poses[0].0), transform(&poses[2].0));
        assert_ne!(poses[0].1, poses[2].1, "the radiance follows the box");

        // Held at 4 s: one pose, and another only when the eye moves.
        let view = LiveView::new(prepared.scene.camera().position);
        let (run, events) = start(Some(4.0), &view);
        let held = next_pose(&events, &view);
        assert_eq!((held.2, held.3), (1, 4.0));
        let path = &prepared.scene.mobile_objects()[0].path;
        assert_eq!(transform(&held.0), path.at(path.start() + 4.0));
        assert!(
            events.recv_timeout(Duration::from_millis(300)).is_err(),
            "a held pose with the eye at rest is sent once"
        );
        view.set_eye(view.eye() + Vec3::new(0.2, 0.0, 0.0));
        let moved_eye = next_pose(&events, &view);
        drop(run);
        assert_eq!((moved_eye.2, moved_eye.3), (2, 4.0));
        assert_eq!(transform(&moved_eye.0), transform(&held.0));
    }

    #[test]
    fn path_time_repeats_the_path_from_its_start() {
        use lustre_geometry::{Keyframe, PathEnd};
        let key =
            |time: f32, x: f32| Keyframe::new(time, Vec3::new(x, 0.0, 0.0), glam::Quat::IDENTITY);
        let path = ObjectPath::new(vec![key(1.0, 0.0), key(3.0, 2.0)], PathEnd::Clamp).unwrap();
        assert_eq!(path_time(&path, 0.0), 1.0);
        assert_eq!(path_time(&path, 0.5), 1.5);
        assert_eq!(path_time(&path, 2.5), 1.5);
        assert_eq!(path_time(&path, 4.0), 1.0);
        let still = ObjectPath::new(vec![key(2.0, 1.0)], PathEnd::Loop).unwrap();
        assert_eq!(path_time(&still, 7.0), 2.0);
    }
}
