//! `lustre view`: the interactive window. It draws every frame through [`GpuFrame`], the code `lustre render` uses, from a lighting solution refined in the background ([`lighting`]), with orbit and fly cameras ([`camera_control`]), the keys of [`input`] and an egui panel ([`panel`]).

pub mod camera_control;
pub mod input;
pub mod lighting;
pub mod panel;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, bail};
use lustre_geometry::Camera;
use lustre_geometry::camera_path::{CameraKeyframe, CameraPath};
use lustre_mpr::passes::tonemap::{ToneOperator, Tonemap};
use lustre_mpr::{AdapterPreference, GpuContext};
use serde_json::json;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::gpu_frame::GpuFrame;
use crate::render::{Lit, Prepared, RenderArgs, prepare_scene, render_settings, write_image};
use camera_control::{Controller, Orbit};
use input::Action;
use lighting::{LightingEvent, LightingRun, LiveView};
use panel::{Drawn, Panel, PanelRequest};

/// Options of `lustre view`: every option of `lustre render` (the same frame), and the window's own.
#[derive(Debug, Clone, clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    /// Play this camera path (`lustre-camera-path` JSON) at once, at 25 frames a second of path time whatever the frame rate (Space plays it again).
    #[arg(long)]
    pub play: Option<PathBuf>,
    /// Frames of `--play` (default: 25 a second of the path).
    #[arg(long, requires = "play")]
    pub play_frames: Option<usize>,
    /// Write a screenshot (PNG or EXR, with the JSON sidecar and the window's own pixels as NAME-window.png) once the lighting is complete and any `--play` has ended.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Close the window after `--screenshot` is written.
    #[arg(long, requires = "screenshot")]
    pub exit: bool,
    /// Where R (stop recording) writes the recorded camera path.
    #[arg(long, default_value = "camera-path.json")]
    pub record: PathBuf,
    /// Render at the window's image area (the default) or at `--size` exactly, the window sized to fit it.
    #[arg(long)]
    pub fixed_size: bool,
    /// Per-vertex techniques: hold the mobile objects at this time along
    /// their paths (seconds from each path's start) instead of moving them
    /// with the clock.
    #[arg(long)]
    pub object_time: Option<f32>,
}

/// Width of the panel in logical pixels.
const PANEL_WIDTH: f32 = 250.0;

/// Frames a second of camera-path time played back.
const PLAY_FPS: f32 = 25.0;

/// Checks the options, loads the scene (a bad file fails here, before any window) and runs the window until it is closed.
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let render = &args.render;
    if let Some(t) = args.object_time {
        if !render.technique.per_vertex() {
            bail!(
                "--object-time: only the per-vertex techniques (detp, impact-count, photon-maps) move objects in the window"
            );
        }
        if !t.is_finite() {
            bail!("--object-time {t}: seconds must be finite");
        }
    }
    if render.photons_file.is_some() {
        bail!(
            "--photons-file: the window traces its photons itself (use lustre render for a photon file)"
        );
    }
    if render.frames.is_some() || render.camera_path.is_some() {
        bail!(
            "--frames and --camera-path belong to lustre render; the window plays a path with --play"
        );
    }
    if render.timing_only {
        bail!("--timing-only belongs to lustre render --frames; the window always draws");
    }
    if render.out != Path::new("render.png") {
        bail!(
            "--out {}: the window writes images with F12 or --screenshot FILE; --out belongs to lustre render",
            render.out.display()
        );
    }
    if let Some(shot) = &args.screenshot {
        crate::render::check_output(shot, "--screenshot")?;
    }
    let play = match &args.play {
        Some(file) => Some(
            CameraPath::load(file)
                .with_context(|| format!("cannot read the camera path {}", file.display()))?,
        ),
        None => None,
    };
    if args.play_frames == Some(0) {
        bail!("--play-frames 0: at least one frame");
    }
    // Checked before any window opens; the window derives them again from the panel's options.
    render_settings(render)?;
    let prepared = Arc::new(prepare_scene(render)?);
    let event_loop = EventLoop::<LightingEvent>::with_user_event()
        .build()
        .context("cannot open a window: no display (set DISPLAY or WAYLAND_DISPLAY, or run under xvfb-run)")?;
    let proxy = event_loop.create_proxy();
    let mut app = App::new(args.clone(), prepared, play, proxy);
    event_loop
        .run_app(&mut app)
        .context("the window's event loop failed")?;
    match app.error.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// A camera path being played: its cameras at fixed time steps and the next one's index.
struct Playback {
    cameras: Vec<Camera>,
    next: usize,
}

/// The window, its surface and egui, once resumed.
struct Shown {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    egui: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    /// The output texture as egui draws it, and the size it was registered at.
    image: Option<(egui::TextureId, (u32, u32))>,
    ctx: GpuContext,
    gpu: Option<GpuFrame>,
}

/// The application: settings, camera, lighting runs and the window.
struct App {
    args: ViewArgs,
    prepared: Arc<Prepared>,
    proxy: EventLoopProxy<LightingEvent>,
    shown: Option<Shown>,
    /// The scene's camera (the lens of every controller).
    template: Camera,
    controller: Controller,
    bookmarks: [Option<Controller>; 9],
    held: HashSet<KeyCode>,
    dragging: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    panel: Panel,
    lighting: Option<LightingRun>,
    next_run: u64,
    /// Photons of the solution on screen, and whether it is the last stage.
    shown_photons: Option<(u64, bool)>,
    camera_drawn: Option<(Camera, (u32, u32), Drawn)>,
    refined: bool,
    last_tick: Instant,
    play: Option<CameraPath>,
    playback: Option<Playback>,
    recording: Option<(Instant, Vec<CameraKeyframe>)>,
    screenshots: u32,
    pending_screenshot: Option<PathBuf>,
    status: String,
    /// The lighting phases' times (ms) of the solution on screen.
    lighting_ms: serde_json::Map<String, serde_json::Value>,
    /// A per-vertex technique's live run: the eye it computes towards and its pending pose.
    live: Option<LiveView>,
    /// A live run's scene, moved to each pose it sends.
    posed_scene: Option<lustre_geometry::Scene>,
    /// The live run's frame on screen, its seconds along the objects' paths and the eye of its glossy radiance.
    shown_pose: Option<(u64, f32, glam::Vec3)>,
    error: Option<anyhow::Error>,
}

impl App {
    fn new(
        args: ViewArgs,
        prepared: Arc<Prepared>,
        play: Option<CameraPath>,
        proxy: EventLoopProxy<LightingEvent>,
    ) -> Self {
        let template = *prepared.scene.camera();
        let panel = Panel::from_args(&args.render);
        let playback = play.as_ref().map(|p| playback_of(p, args.play_frames));
        let pending_screenshot = args.screenshot.clone();
        Self {
            args,
            prepared,
            proxy,
            shown: None,
            template,
            controller: Controller::Orbit(Orbit::from_camera(&template)),
            bookmarks: [None; 9],
            held: HashSet::new(),
            dragging: None,
            cursor: None,
            panel,
            lighting: None,
            next_run: 0,
            shown_photons: None,
            camera_drawn: None,
            refined: false,
            last_tick: Instant::now(),
            play,
            playback,
            recording: None,
            screenshots: 0,
            pending_screenshot,
            status: String::new(),
            lighting_ms: serde_json::Map::new(),
            live: None,
            posed_scene: None,
            shown_pose: None,
            error: None,
        }
    }

    /// The render options the panel's settings give.
    fn render_args(&self) -> RenderArgs {
        self.panel.apply(&self.args.render)
    }

    /// Starts lighting the scene with the panel's settings (dropping any run in progress); settings `render` would refuse stop here, with the reason in the panel.
    fn start_lighting(&mut self) {
        let args = self.render_args();
        let settings = match render_settings(&args) {
            Ok(settings) => settings,
            Err(e) => {
                eprintln!("lustre: {e:#}");
                self.status = format!("{e:#}");
                self.lighting = None;
                return;
            }
        };
        // The run in progress stops whatever follows.
        self.lighting = None;
        self.shown_pose = None;
        self.next_run += 1;
        let proxy = self.proxy.clone();
        // The window may be closing; nothing is lost then.
        let send = move |event| {
            let _ = proxy.send_event(event);
        };
        self.lighting = Some(if self.prepared.density.is_some() {
            let live = LiveView::new(self.camera(self.render_size()).position);
            self.live = Some(live.clone());
            self.posed_scene = Some(self.prepared.scene.clone());
            lighting::spawn_quasi_static(
                self.next_run,
                args,
                Arc::clone(&self.prepared),
                live,
                self.args.object_time,
                send,
            )
        } else {
            self.live = None;
            self.posed_scene = None;
            let Some(shown) = &self.shown else {
                return;
            };
            let size = self.render_size();
            let target = lighting::FrameTarget {
                ctx: shown.ctx.clone(),
                size,
                camera: self.camera(size),
            };
            lighting::spawn(
                self.next_run,
                args,
                Arc::clone(&self.prepared),
                settings,
                target,
                send,
            )
        });
        self.status = "lighting…".into();
    }

    /// The scene's size (its bounds' diagonal).
    fn scene_size(&self) -> f32 {
        let b = self.prepared.scene.bounds();
        (b.max - b.min).length()
    }

    /// The camera of the current frame at the render's aspect.
    fn camera(&self, size: (u32, u32)) -> Camera {
        let camera = match &self.playback {
            Some(p) => p.cameras[p.next.min(p.cameras.len() - 1)],
            None => self.controller.camera(&self.template),
        };
        camera.with_aspect(size.0 as f32 / size.1.max(1) as f32)
    }

    /// Does `action` (a key's or the panel's); returns whether the window should close.
    fn perform(&mut self, action: Action) -> bool {
        match action {
            Action::ToggleController => {
                self.controller = self.controller.toggled(&self.template, self.scene_size());
            }
            Action::Screenshot => {
                self.screenshots += 1;
                self.pending_screenshot =
                    Some(PathBuf::from(format!("lustre-{:04}.png", self.screenshots)));
            }
            Action::ToggleRecording => self.toggle_recording(),
            Action::TogglePlayback => {
                if self.playback.is_some() {
                    self.playback = None;
                } else if let Some(path) = &self.play {
                    self.playback = Some(playback_of(path, self.args.play_frames));
                } else {
                    self.status = "no camera path: record one with R or pass --play".into();
                }
            }
            Action::ResetCamera => {
                self.playback = None;
                self.controller = Controller::Orbit(Orbit::from_camera(&self.template));
            }
            Action::FrameScene => {
                self.playback = None;
                self.controller = Controller::Orbit(Orbit::framing(
                    &self.prepared.scene.bounds(),
                    self.template.fov_y_degrees,
                ));
            }
            Action::RecallBookmark(i) => {
                if let Some(c) = self.bookmarks[i] {
                    self.playback = None;
                    self.controller = c;
                }
            }
            Action::StoreBookmark(i) => {
                self.bookmarks[i] = Some(self.controller);
                self.status = format!("bookmark {} stored", i + 1);
            }
            Action::TogglePanel => self.panel.visible = !self.panel.visible,
            Action::Quit => return true,
        }
        self.request_redraw();
        false
    }

    fn toggle_recording(&mut self) {
        match self.recording.take() {
            None => {
                let camera = self.controller.camera(&self.template);
                self.recording = Some((Instant::now(), vec![CameraKeyframe::of(&camera, 0.0)]));
                self.status = "recording the camera path (R stops)".into();
            }
            Some((_, keyframes)) => match CameraPath::new(keyframes) {
                Ok(path) => {
                    self.status = match path.save(&self.args.record) {
                        Ok(()) => format!(
                            "camera path of {} keyframes written to {}",
                            path.keyframes().len(),
                            self.args.record.display()
                        ),
                        Err(e) => format!("cannot write the camera path: {e}"),
                    };
                    self.play = Some(path);
                }
                Err(e) => self.status = format!("camera path not kept: {e}"),
            },
        }
        if !self.status.is_empty() {
            eprintln!("{}", self.status);
        }
    }

    fn request_redraw(&self) {
        if let Some(shown) = &self.shown {
            shown.window.request_redraw();
        }
    }

    /// Handles a stage of lighting: a new GPU frame from it.
    fn on_lighting(&mut self, event: LightingEvent) {
        match event {
            LightingEvent::Pose {
                run,
                pose,
                corners,
                frame,
                seconds,
                eye,
                update_ms,
            } => {
                if !self.is_current(run) {
                    return;
                }
                match self.show_pose(&pose, corners) {
                    Ok(()) => {
                        let technique = self.prepared.density.map_or("", |d| d.name());
                        self.shown_photons = Some((self.args.render.photons, true));
                        self.shown_pose = Some((frame, seconds, eye));
                        self.status = if pose.is_empty() {
                            format!("{technique}: towards this eye in {update_ms:.0} ms")
                        } else {
                            format!(
                                "{technique}: quasi-static frame {frame}, update {update_ms:.0} ms"
                            )
                        };
                        self.camera_drawn = None;
                        self.refined = false;
                    }
                    Err(e) => {
                        eprintln!("lustre: {e:#}");
                        self.status = format!("{e:#}");
                        self.lighting = None;
                    }
                }
                if let Some(live) = &self.live {
                    live.pending
                        .store(false, std::sync::atomic::Ordering::Release);
                }
            }
            LightingEvent::Failed { run, message } => {
                if self.is_current(run) {
                    eprintln!("lustre: lighting failed: {message}");
                    self.status = format!("lighting failed: {message}");
                    self.lighting = None;
                }
            }
            LightingEvent::Stage {
                run,
                gpu,
                photons,
                stage,
                timings,
            } => {
                if !self.is_current(run) {
                    return;
                }
                let last = stage.0 + 1 == stage.1;
                match self.shown.as_mut() {
                    Some(shown) => {
                        shown.gpu = Some(*gpu);
                        self.shown_photons = Some((photons, last));
                        self.lighting_ms = timings;
                        self.status = if last {
                            format!("lit by {photons} photons")
                        } else {
                            format!(
                                "lit by {photons} photons, refining ({} of {})",
                                stage.0 + 1,
                                stage.1
                            )
                        };
                        self.refined = false;
                        self.camera_drawn = None;
                    }
                    // The window closed meanwhile.
                    None => return,
                }
                if last {
                    self.lighting = None;
                }
            }
        }
        self.request_redraw();
    }

    /// Whether `run` is the lighting run in progress (older runs' events are dropped).
    fn is_current(&self, run: u64) -> bool {
        self.lighting.as_ref().is_some_and(|l| l.id == run)
    }

    /// A live run's pose: the live scene moved to it, and the frame built from it the first time, moved after.
    fn show_pose(
        &mut self,
        pose: &[(lustre_geometry::ObjectId, glam::Affine3A)],
        corners: Vec<[f32; 3]>,
    ) -> anyhow::Result<()> {
        let mut scene = self
            .posed_scene
            .take()
            .context("a pose without a live run")?;
        let shown = pose
            .iter()
            .try_for_each(|&(object, transform)| scene.set_object_transform(object, transform))
            .map_err(anyhow::Error::from)
            .and_then(|()| self.show_posed_scene(&scene, corners));
        self.posed_scene = Some(scene);
        shown
    }

    /// The frame of `scene` in a live run's pose: built the first time, moved after.
    fn show_posed_scene(
        &mut self,
        scene: &lustre_geometry::Scene,
        corners: Vec<[f32; 3]>,
    ) -> anyhow::Result<()> {
        if self.shown_pose.is_some()
            && let Some(gpu) = self.shown.as_mut().and_then(|s| s.gpu.as_mut())
        {
            return gpu.set_pose(scene, &corners);
        }
        let lit = Lit {
            vertex: Some(crate::render_density::VertexRadiance {
                corners,
                primary_rays: 0,
                segments: 0,
                ray_set_ms: 0.0,
                estimate_ms: 0.0,
            }),
            ..Lit::unlit(&self.render_args())
        };
        self.build_frame_of(scene, &lit)
    }

    /// A GPU frame from `lit` at the image area's size.
    fn build_frame(&mut self, lit: &Lit) -> anyhow::Result<()> {
        let prepared = Arc::clone(&self.prepared);
        self.build_frame_of(&prepared.scene, lit)
    }

    /// A GPU frame of `scene` (the prepared scene, or a live run's pose) lit by `lit`.
    fn build_frame_of(&mut self, scene: &lustre_geometry::Scene, lit: &Lit) -> anyhow::Result<()> {
        let args = self.render_args();
        // Derived from the options the lighting was started with (the technique decides them).
        let (shadow_depth, glossy_images) = render_settings(&args)?;
        let size = self.render_size();
        let camera = self.camera(size);
        let Some(shown) = &mut self.shown else {
            return Ok(());
        };
        // Its tone map and lighting terms are set from the panel before every draw (`redraw`).
        shown.gpu = Some(GpuFrame::new(
            &args,
            lit.lighting(scene, shadow_depth, glossy_images),
            shown.ctx.clone(),
            size,
            &camera,
        )?);
        Ok(())
    }

    /// The render's size: `--size` with `--fixed-size`, else the image area in physical pixels scaled by the panel's render scale.
    fn render_size(&self) -> (u32, u32) {
        if self.args.fixed_size {
            return self.args.render.size;
        }
        let Some(shown) = &self.shown else {
            return self.args.render.size;
        };
        let (w, h) = image_area(shown, self.panel.visible);
        let s = self.panel.render_scale;
        (
            ((w as f32 * s).round() as u32).max(1),
            ((h as f32 * s).round() as u32).max(1),
        )
    }

    /// One frame: advance the camera, draw when it or the settings changed (or refine a resting one), draw the panel, present.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f32().min(0.25);
        self.last_tick = now;
        if let Controller::Fly(fly) = &mut self.controller {
            let keys = input::fly_keys(&self.held);
            if keys.moving() {
                fly.advance(keys, dt);
            }
        }
        let size = self.render_size();
        let camera = self.camera(size);
        if let Some(live) = &self.live {
            live.set_eye(camera.position);
        }
        if let Some((start, keyframes)) = &mut self.recording {
            let t = start.elapsed().as_secs_f32();
            let last = keyframes.last().map_or(-1.0, |k| k.time);
            let moved = keyframes
                .last()
                .is_none_or(|k| k.position != camera.position || k.target != camera.target);
            // A keyframe at most every 0.2 s while the camera moves.
            if moved && t - last >= 0.2 {
                keyframes.push(CameraKeyframe::of(&camera, t));
            }
        }
        let aa = self.panel.aa.max(1);
        let settings = self.panel.drawn();
        let mut drew = None;
        if let Some(shown) = &mut self.shown
            && let Some(gpu) = &mut shown.gpu
        {
            gpu.resize(size.0, size.1)?;
            gpu.set_tonemap(display_tonemap(settings.exposure));
            gpu.components = settings.components;
            let same = self
                .camera_drawn
                .as_ref()
                .is_some_and(|(c, s, d)| *c == camera && *s == size && *d == settings);
            // Moving: one sample for speed; a resting camera is refined to `aa` next.
            let samples = if !same {
                Some(
                    if self.playback.is_some() || self.args.screenshot.is_some() {
                        aa
                    } else {
                        1
                    },
                )
            } else {
                (!self.refined).then_some(aa)
            };
            if let Some(samples) = samples {
                let start = Instant::now();
                gpu.store_jittered_volumes(&self.prepared.scene, samples)?;
                gpu.draw(&camera, samples)?;
                drew = Some(start.elapsed());
                self.camera_drawn = Some((camera, size, settings));
                self.refined = samples >= aa;
            }
        }
        if let Some(time) = drew {
            self.panel.push_frame_time(time.as_secs_f32() * 1e3);
            if let Some(gpu) = self.shown.as_ref().and_then(|s| s.gpu.as_ref()) {
                self.panel.pass_times = gpu.pass_times()?;
            }
        }
        let lit_completely = self.shown_photons.is_some_and(|(_, last)| last);
        let mut exit_after = false;
        // Playback: one path frame per drawn frame, at fixed time steps.
        if drew.is_some()
            && let Some(p) = &mut self.playback
        {
            if p.next + 1 < p.cameras.len() {
                p.next += 1;
            } else if lit_completely {
                self.playback = None;
                self.camera_drawn = None;
                // Leave the controller where the path ended.
                self.controller = Controller::Orbit(Orbit::from_camera(&camera));
            }
        }
        // A live run's glossy radiance is towards the eye it was computed for: wait for this one.
        let towards_this_eye = self.live.is_none()
            || self
                .shown_pose
                .is_some_and(|(_, _, eye)| eye == camera.position);
        if self.playback.is_none()
            && self.refined
            && lit_completely
            && towards_this_eye
            && let Some(path) = self.pending_screenshot.take()
        {
            self.screenshot(&path, &camera)?;
            // `--exit`: once the window has shown (and captured) the frame.
            exit_after = self.args.exit && self.args.screenshot.as_deref() == Some(path.as_path());
        }
        self.present()?;
        if exit_after {
            event_loop.exit();
            return Ok(());
        }
        // A live run wakes the window with each pose it sends.
        let busy = self.playback.is_some()
            || !self.refined
            || (self.lighting.is_some() && self.live.is_none())
            || self.recording.is_some()
            || matches!(self.controller, Controller::Fly(_))
                && input::fly_keys(&self.held).moving();
        if busy {
            self.request_redraw();
        }
        Ok(())
    }

    /// Draws the panel and the image into the window and presents it.
    fn present(&mut self) -> anyhow::Result<()> {
        let Self {
            shown,
            panel,
            status,
            controller,
            recording,
            playback,
            shown_photons,
            lighting,
            prepared,
            ..
        } = self;
        let Some(shown) = shown else { return Ok(()) };
        let frame = match shown.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                shown.surface.configure(&shown.ctx.device, &shown.config);
                return Ok(());
            }
            other => bail!("the window's surface gave no image: {other:?}"),
        };
        // The output texture as an egui image (registered again when the frame was rebuilt or resized).
        if let Some(gpu) = &shown.gpu {
            let view = gpu.output().create_view(&wgpu::TextureViewDescriptor {
                format: Some(wgpu::TextureFormat::Rgba8Unorm),
                ..Default::default()
            });
            let size = gpu.size();
            match &mut shown.image {
                Some((id, registered)) => {
                    shown.egui_renderer.update_egui_texture_from_wgpu_texture(
                        &shown.ctx.device,
                        &view,
                        wgpu::FilterMode::Nearest,
                        *id,
                    );
                    *registered = size;
                }
                None => {
                    let id = shown.egui_renderer.register_native_texture(
                        &shown.ctx.device,
                        &view,
                        wgpu::FilterMode::Nearest,
                    );
                    shown.image = Some((id, size));
                }
            }
        }
        let raw = shown.egui_state.take_egui_input(&shown.window);
        let info = panel::Info {
            adapter: shown.ctx.adapter().to_string(),
            status: status.clone(),
            controller: controller.name(),
            recording: recording.is_some(),
            playing: playback.is_some(),
            photons: *shown_photons,
            lighting: lighting.is_some(),
            triangles: prepared.scene.triangle_count(),
        };
        let image = shown.image;
        let mut requests = Vec::new();
        let mut output = shown.egui.run_ui(raw, |ui| {
            requests = panel.show(ui, &info, image);
        });
        shown
            .egui_state
            .handle_platform_output(&shown.window, output.platform_output);
        let jobs = shown
            .egui
            .tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [shown.config.width, shown.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in &deltas {
                shown
                    .egui_renderer
                    .update_texture(&shown.ctx.device, &shown.ctx.queue, id, delta);
            }
        }
        let mut encoder =
            shown
                .ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("lustre-view"),
                });
        let extra = shown.egui_renderer.update_buffers(
            &shown.ctx.device,
            &shown.ctx.queue,
            &mut encoder,
            &jobs,
            &screen,
        );
        let target = frame
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lustre-view-egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            shown.egui_renderer.render(&mut pass, &jobs, &screen);
        }
        shown
            .ctx
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        // Freed after painting (the submitted commands keep what they use alive).
        for id in output.textures_delta.free.drain() {
            shown.egui_renderer.free_texture(&id);
        }
        if let Some(path) = panel.window_capture.take() {
            capture_window(shown, &frame.texture, &path)?;
        }
        shown.window.pre_present_notify();
        shown.ctx.queue.present(frame);
        for request in requests {
            self.on_request(request);
        }
        Ok(())
    }

    fn on_request(&mut self, request: PanelRequest) {
        match request {
            PanelRequest::Relight => self.start_lighting(),
            PanelRequest::Redraw => {
                // The splats' resolution is the frame's, chosen again for the current camera.
                let args = self.render_args();
                let size = self.render_size();
                let camera = self.camera(size);
                if let Some(gpu) = self.shown.as_mut().and_then(|s| s.gpu.as_mut()) {
                    gpu.set_splat_resolution(&args, &camera);
                }
                self.camera_drawn = None;
                self.refined = false;
            }
            PanelRequest::Screenshot => {
                self.perform(Action::Screenshot);
            }
            PanelRequest::ToggleController => {
                self.perform(Action::ToggleController);
            }
            PanelRequest::ToggleRecording => {
                self.perform(Action::ToggleRecording);
            }
            PanelRequest::TogglePlayback => {
                self.perform(Action::TogglePlayback);
            }
        }
        self.request_redraw();
    }

    /// Writes the last frame's HDR image as `path` (PNG or EXR, the other format beside it), its sidecar, and asks for the window's pixels as `NAME-window.png`.
    fn screenshot(&mut self, path: &Path, camera: &Camera) -> anyhow::Result<()> {
        let Some(gpu) = self.shown.as_ref().and_then(|s| s.gpu.as_ref()) else {
            return Ok(());
        };
        let image = gpu.read_hdr()?;
        let exposure = self.panel.exposure;
        write_image(path, exposure, &image)?;
        let other = if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
        {
            path.with_extension("png")
        } else {
            path.with_extension("exr")
        };
        write_image(&other, exposure, &image)?;
        let args = self.render_args();
        let info = json!({
            "scene": self.prepared.scene.name,
            "technique": format!("{:?}", args.technique),
            "photons": self.shown_photons.map(|(p, _)| p),
            "seed": args.seed,
            "aa": self.panel.aa,
            "size": [image.width(), image.height()],
            "exposure": exposure,
            "components": {
                "direct": self.panel.components.direct,
                "diffuse": self.panel.components.diffuse,
                "splats": self.panel.components.splats,
            },
            "splat_resolution": gpu.splat_resolution.map(|r| format!("{r:?}")),
            "camera": {
                "position": camera.position.to_array(),
                "target": camera.target.to_array(),
                "up": camera.up.to_array(),
                "fov_y_degrees": camera.fov_y_degrees,
            },
            "adapter": gpu.ctx.adapter().to_string(),
            "lighting_ms": self.lighting_ms,
            "quasi_static": self.shown_pose.map(|(frame, seconds, eye)| json!({
                "frame": frame,
                "object_seconds": seconds,
                "glossy_eye": eye.to_array(),
            })),
            "images": [path.display().to_string(), other.display().to_string()],
            "window_capture": window_capture_path(path).display().to_string(),
            "version": env!("CARGO_PKG_VERSION"),
        });
        let sidecar = crate::render::sidecar_path(path);
        lustre_image::write_json_atomic(&sidecar, &info)
            .with_context(|| format!("cannot write {}", sidecar.display()))?;
        eprintln!(
            "wrote {}, {} and {}",
            path.display(),
            other.display(),
            sidecar.display()
        );
        self.status = format!("screenshot {}", path.display());
        self.panel.window_capture = Some(window_capture_path(path));
        Ok(())
    }

    /// Closes the window with `error` (reported by `main`).
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        self.error = Some(error);
        event_loop.exit();
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (w, h) = self.args.render.size;
        let attributes = Window::default_attributes()
            .with_title(format!("lustre view — {}", self.prepared.scene.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(
                w + PANEL_WIDTH as u32,
                h.max(200),
            ));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot create the window")?,
        );
        let preference = if self.args.render.software {
            AdapterPreference::Software
        } else {
            AdapterPreference::Hardware
        };
        let (ctx, surface) = GpuContext::with_surface(preference, Arc::clone(&window))?;
        eprintln!("window on {}", ctx.adapter());
        let caps = surface.get_capabilities(ctx.wgpu_adapter());
        let format = caps
            .formats
            .iter()
            .copied()
            .find(wgpu::TextureFormat::is_srgb)
            .or_else(|| caps.formats.first().copied())
            .context("the window's surface offers no format")?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&ctx.device, &config);
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            format,
            egui_wgpu::RendererOptions {
                // The image is shown as rendered: no noise added to it.
                dithering: false,
                ..Default::default()
            },
        );
        self.shown = Some(Shown {
            window,
            surface,
            config,
            egui,
            egui_state,
            egui_renderer,
            image: None,
            ctx,
            gpu: None,
        });
        // The first frame at once: direct light and emitters without photons, while the lighting runs.
        self.build_frame(&Lit::unlit(&self.args.render))?;
        self.shown_photons = None;
        self.start_lighting();
        Ok(())
    }
}

impl ApplicationHandler<LightingEvent> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.shown.is_some() {
            return;
        }
        event_loop.set_control_flow(ControlFlow::Wait);
        if let Err(e) = self.open_window(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, event: LightingEvent) {
        self.on_lighting(event);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(shown) = &mut self.shown else { return };
        let response = shown.egui_state.on_window_event(&shown.window, &event);
        if response.repaint {
            shown.window.request_redraw();
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                shown.config.width = size.width.max(1);
                shown.config.height = size.height.max(1);
                shown.surface.configure(&shown.ctx.device, &shown.config);
                shown.window.request_redraw();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::DroppedFile(path) => {
                let mut render = self.args.render.clone();
                render.scene = path.display().to_string();
                match prepare_scene(&render) {
                    Ok(prepared) => {
                        eprintln!("loaded {}", path.display());
                        self.args.render = render;
                        self.prepared = Arc::new(prepared);
                        self.template = *self.prepared.scene.camera();
                        self.controller = Controller::Orbit(Orbit::from_camera(&self.template));
                        self.playback = None;
                        if let Some(shown) = &self.shown {
                            shown
                                .window
                                .set_title(&format!("lustre view — {}", self.prepared.scene.name));
                        }
                        match self.build_frame(&Lit::unlit(&self.args.render)) {
                            Ok(()) => self.start_lighting(),
                            Err(e) => self.status = format!("{e:#}"),
                        }
                    }
                    Err(e) => {
                        eprintln!("lustre: {e:#}");
                        self.status = format!("{e:#}");
                    }
                }
                self.camera_drawn = None;
                self.request_redraw();
            }
            WindowEvent::KeyboardInput { event: key, .. } if !response.consumed => {
                let PhysicalKey::Code(code) = key.physical_key else {
                    return;
                };
                match key.state {
                    ElementState::Pressed => {
                        let ctrl = self.held.contains(&KeyCode::ControlLeft)
                            || self.held.contains(&KeyCode::ControlRight);
                        self.held.insert(code);
                        if !key.repeat
                            && let Some(action) = input::action(code, ctrl)
                            && self.perform(action)
                        {
                            event_loop.exit();
                        }
                    }
                    ElementState::Released => {
                        self.held.remove(&code);
                    }
                }
                self.request_redraw();
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.dragging = match state {
                    ElementState::Pressed if !response.consumed => Some(button),
                    _ => None,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                let previous = self.cursor.replace((position.x, position.y));
                if let (Some(button), Some((x, y))) = (self.dragging, previous) {
                    let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                    self.playback = None;
                    let shift = self.held.contains(&KeyCode::ShiftLeft)
                        || self.held.contains(&KeyCode::ShiftRight);
                    let height = self.render_size().1 as f32 / self.panel.render_scale;
                    let fov = self.template.fov_y_degrees;
                    match &mut self.controller {
                        Controller::Orbit(o) if shift || button != MouseButton::Left => {
                            o.pan(dx, dy, height, fov);
                        }
                        Controller::Orbit(o) => o.drag(dx, dy),
                        Controller::Fly(f) => f.look(dx, dy),
                    }
                    self.request_redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !response.consumed => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                match &mut self.controller {
                    Controller::Orbit(o) => o.zoom(lines),
                    Controller::Fly(f) => f.speed *= 1.25f32.powf(lines),
                }
                self.request_redraw();
            }
            _ => {}
        }
    }
}

/// The cameras of `path` at [`PLAY_FPS`] frames a second of path time (or `frames` of them).
fn playback_of(path: &CameraPath, frames: Option<usize>) -> Playback {
    let count =
        frames.unwrap_or_else(|| ((path.duration() * PLAY_FPS).round() as usize + 1).max(2));
    Playback {
        cameras: path.frames(count),
        next: 0,
    }
}

/// The window's tone mapping: the PNG files' (exposure in stops, then clamped), so the window shows what a screenshot writes.
fn display_tonemap(exposure_stops: f32) -> Tonemap {
    Tonemap {
        exposure: exposure_stops.exp2(),
        operator: ToneOperator::Clamp,
    }
}

/// The image area of the window in physical pixels: all of it but the panel.
fn image_area(shown: &Shown, panel_visible: bool) -> (u32, u32) {
    let panel = if panel_visible {
        (PANEL_WIDTH * shown.window.scale_factor() as f32).round() as u32
    } else {
        0
    };
    (
        shown.config.width.saturating_sub(panel).max(1),
        shown.config.height.max(1),
    )
}

/// `shot.png` → `shot-window.png`.
fn window_capture_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("lustre");
    path.with_file_name(format!("{stem}-window.png"))
}

/// Writes the presented texture, the whole window with its panel, as an sRGB PNG, when the surface allows copies (the image is its right-hand part, at the top).
fn capture_window(shown: &Shown, texture: &wgpu::Texture, path: &Path) -> anyhow::Result<()> {
    if !shown.config.usage.contains(wgpu::TextureUsages::COPY_SRC) {
        eprintln!(
            "warning: this window's surface cannot be read back: no {}",
            path.display()
        );
        return Ok(());
    }
    let format = texture.format();
    let bgra = match format {
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => true,
        wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => false,
        other => {
            eprintln!(
                "warning: cannot read a {other:?} window back: no {}",
                path.display()
            );
            return Ok(());
        }
    };
    let bytes =
        lustre_mpr::readback::read_texture_bytes(&shown.ctx, texture, wgpu::TextureAspect::All)?;
    let (width, height) = (texture.width(), texture.height());
    let pixels: Vec<[u8; 3]> = bytes
        .chunks_exact(4)
        .map(|p| {
            if bgra {
                [p[2], p[1], p[0]]
            } else {
                [p[0], p[1], p[2]]
            }
        })
        .collect();
    lustre_image::write_png_srgb8(path, width, height, &pixels)
        .with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
