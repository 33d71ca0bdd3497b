//! The window's egui panel: the lighting terms switched on and off, the technique and its main parameters, the frame's refinement, exposure and resolution, the frame time graph, the camera and its paths; [`Panel::apply`] turns the settings into `lustre render`'s options.

use std::path::PathBuf;

use crate::gpu_frame::Components;
use crate::render::{ReflectorsArg, RenderArgs, ShadowArg, SplatResolutionArg, Technique};

/// The techniques the window offers (those that light any camera from one solution).
pub const TECHNIQUES: [(Technique, &str); 6] = [
    (Technique::Composed, "composed"),
    (Technique::SplatDirect, "splat-direct"),
    (Technique::Splat, "splat"),
    (Technique::Mpr, "mpr"),
    (Technique::Beams, "beams"),
    (Technique::Ibr, "ibr"),
];

/// Photon counts offered.
pub const PHOTONS: [u64; 6] = [
    100_000, 300_000, 1_000_000, 3_000_000, 10_000_000, 30_000_000,
];

/// Splat resolutions offered.
pub const RESOLUTIONS: [(SplatResolutionArg, &str); 5] = [
    (SplatResolutionArg::Auto, "auto"),
    (SplatResolutionArg::Full, "full"),
    (SplatResolutionArg::Half, "half"),
    (SplatResolutionArg::Quarter, "quarter"),
    (SplatResolutionArg::Eighth, "eighth"),
];

/// Render scales offered (of the image area's pixels).
pub const SCALES: [(f32, &str); 3] = [(1.0, "1"), (0.5, "1/2"), (0.25, "1/4")];

/// Frame times kept for the graph.
const GRAPH_FRAMES: usize = 120;

/// What the panel asks the window to do after a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PanelRequest {
    /// The lighting's settings changed: light again.
    Relight,
    /// The frame's settings changed: draw again.
    Redraw,
    /// Write a screenshot.
    Screenshot,
    /// Orbit ↔ fly.
    ToggleController,
    /// Start or stop recording a camera path.
    ToggleRecording,
    /// Play or stop the camera path.
    TogglePlayback,
}

/// What the panel shows but does not set.
pub struct Info {
    /// The adapter's name, backend and driver.
    pub adapter: String,
    /// The last message.
    pub status: String,
    /// The camera controller's name.
    pub controller: &'static str,
    /// A camera path is being recorded.
    pub recording: bool,
    /// A camera path is playing.
    pub playing: bool,
    /// Photons of the solution on screen, and whether it is the last stage.
    pub photons: Option<(u64, bool)>,
    /// The lighting thread is running.
    pub lighting: bool,
    /// The scene's triangles.
    pub triangles: usize,
}

/// The frame settings that decide whether a drawn frame is still current.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drawn {
    /// Exposure in stops.
    pub exposure: f32,
    /// The lighting terms drawn.
    pub components: Components,
    /// Render scale.
    pub render_scale: f32,
    /// The splats' resolution.
    pub splat_resolution: SplatResolutionArg,
}

/// The panel's settings and state.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Shown (F1 hides it).
    pub visible: bool,
    /// The technique.
    pub technique: Technique,
    /// Photons of the final stage.
    pub photons: u64,
    /// Point lights per area light of the direct pass.
    pub light_samples: u32,
    /// `--shadows` (volumes apply to the multi-pass techniques).
    pub shadows: ShadowArg,
    /// The splats' resolution.
    pub splat_resolution: SplatResolutionArg,
    /// Jittered samples of a resting camera's frame.
    pub aa: u32,
    /// Exposure in stops (as `--exposure`).
    pub exposure: f32,
    /// The render's pixels per image-area pixel.
    pub render_scale: f32,
    /// The lighting terms drawn.
    pub components: Components,
    /// `--reflectors` as given (`composed` draws radiance maps only when it says `maps`).
    pub reflectors: Option<ReflectorsArg>,
    /// Recent frame times (ms), oldest first.
    pub frame_times: Vec<f32>,
    /// GPU time of each pass of the last frame (ms), where the adapter has timestamps.
    pub pass_times: Option<Vec<(&'static str, f64)>>,
    /// Where the window's pixels go after this frame (a screenshot's companion).
    pub window_capture: Option<PathBuf>,
}

impl Panel {
    /// The panel's settings as `args` give them.
    pub fn from_args(args: &RenderArgs) -> Self {
        Self {
            visible: true,
            technique: args.technique,
            photons: args.photons,
            light_samples: args.light_samples,
            shadows: args.shadows,
            splat_resolution: args.splat_resolution,
            aa: args.aa,
            exposure: args.exposure,
            render_scale: 1.0,
            components: Components::default(),
            reflectors: args.reflectors,
            frame_times: Vec::new(),
            pass_times: None,
            window_capture: None,
        }
    }

    /// `args` with the panel's settings: the options `lustre render` would be given for the same frame.
    pub fn apply(&self, args: &RenderArgs) -> RenderArgs {
        RenderArgs {
            technique: self.technique,
            photons: self.photons,
            light_samples: self.light_samples,
            splat_resolution: self.splat_resolution,
            aa: self.aa,
            exposure: self.exposure,
            ..args.clone()
        }
    }

    /// The settings a drawn frame depends on.
    pub fn drawn(&self) -> Drawn {
        Drawn {
            exposure: self.exposure,
            components: self.components,
            render_scale: self.render_scale,
            splat_resolution: self.splat_resolution,
        }
    }

    /// Adds a frame time to the graph.
    pub fn push_frame_time(&mut self, ms: f32) {
        self.frame_times.push(ms);
        if self.frame_times.len() > GRAPH_FRAMES {
            self.frame_times.remove(0);
        }
    }

    /// What changed between `before` and now asks for: lighting again, drawing again, or nothing.
    pub fn changes(&self, before: &Panel) -> Option<PanelRequest> {
        if self.technique != before.technique
            || self.photons != before.photons
            || self.light_samples != before.light_samples
        {
            Some(PanelRequest::Relight)
        } else if self.drawn() != before.drawn() || self.aa != before.aa {
            Some(PanelRequest::Redraw)
        } else {
            None
        }
    }

    /// Draws the panel and the image (`image`, at its size in physical pixels) and returns what was asked.
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        info: &Info,
        image: Option<(egui::TextureId, (u32, u32))>,
    ) -> Vec<PanelRequest> {
        let before = self.clone();
        let mut requests = Vec::new();
        if self.visible {
            egui::Panel::left("lustre-panel")
                .resizable(false)
                .exact_size(super::PANEL_WIDTH)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        self.controls(ui, info, &mut requests);
                    });
                });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE.fill(egui::Color32::BLACK))
            .show(ui, |ui| {
                if let Some((id, (w, h))) = image {
                    let ppp = ui.ctx().pixels_per_point();
                    let area = ui.available_size();
                    // The render fills the area (1:1 pixels at render scale 1).
                    let size = if self.render_scale == 1.0 {
                        egui::vec2(w as f32 / ppp, h as f32 / ppp)
                    } else {
                        area
                    };
                    ui.add(egui::Image::new((id, size)));
                }
            });
        if let Some(change) = self.changes(&before) {
            requests.push(change);
        }
        requests
    }

    fn controls(&mut self, ui: &mut egui::Ui, info: &Info, requests: &mut Vec<PanelRequest>) {
        ui.heading("Lustre");
        ui.small(&info.adapter);
        ui.small(format!("{} triangles", info.triangles));
        match info.photons {
            Some((n, true)) => ui.label(format!("lit by {n} photons")),
            Some((n, false)) => ui.label(format!("lit by {n} photons, refining…")),
            None => ui.label("direct light only, tracing photons…"),
        };
        if info.lighting {
            ui.spinner();
        }
        if !info.status.is_empty() {
            ui.small(&info.status);
        }
        ui.separator();
        ui.strong("Lighting");
        if self.technique.per_vertex() {
            // The scene was meshed for it at start: no other technique here.
            let name = clap::ValueEnum::to_possible_value(&self.technique)
                .map_or_else(String::new, |v| v.get_name().to_owned());
            ui.label(format!("technique: {name} (per-vertex, live)"));
        } else {
            egui::ComboBox::from_label("technique")
                .selected_text(name_of(&TECHNIQUES, self.technique))
                .show_ui(ui, |ui| {
                    for (t, name) in TECHNIQUES {
                        ui.selectable_value(&mut self.technique, t, name);
                    }
                });
        }
        egui::ComboBox::from_label("photons")
            .selected_text(self.photons.to_string())
            .show_ui(ui, |ui| {
                for n in PHOTONS {
                    ui.selectable_value(&mut self.photons, n, n.to_string());
                }
            });
        // A per-vertex technique's estimate holds all the light but the emitters'.
        let splatting = !self.technique.per_vertex();
        let shadows = if self.technique.multipass() && self.shadows == ShadowArg::Volumes {
            "shadow volumes"
        } else {
            "shadow maps"
        };
        if splatting {
            ui.checkbox(
                &mut self.components.direct,
                format!("direct light ({shadows})"),
            );
            ui.add(egui::Slider::new(&mut self.light_samples, 1..=64).text("point lights"));
            ui.checkbox(&mut self.components.diffuse, "indirect diffuse (textures)");
            ui.checkbox(&mut self.components.splats, "glossy and indirect (splats)");
        }
        if self.technique == Technique::Ibr
            || (self.technique == Technique::Composed
                && self.reflectors == Some(ReflectorsArg::Maps))
        {
            ui.checkbox(
                &mut self.components.radiance_maps,
                "glossy reflectors (radiance maps)",
            );
        }
        if matches!(self.technique, Technique::Beams | Technique::Composed) {
            ui.checkbox(&mut self.components.beams, "caustics (beams)");
        }
        ui.checkbox(&mut self.components.emission, "emitters");
        if splatting {
            egui::ComboBox::from_label("splat resolution")
                .selected_text(name_of(&RESOLUTIONS, self.splat_resolution))
                .show_ui(ui, |ui| {
                    for (r, name) in RESOLUTIONS {
                        ui.selectable_value(&mut self.splat_resolution, r, name);
                    }
                });
        }
        ui.separator();
        ui.strong("Frame");
        ui.add(egui::Slider::new(&mut self.aa, 1..=16).text("samples at rest"));
        ui.add(egui::Slider::new(&mut self.exposure, -6.0..=6.0).text("exposure (stops)"));
        egui::ComboBox::from_label("render scale")
            .selected_text(
                SCALES
                    .iter()
                    .find(|(s, _)| *s == self.render_scale)
                    .map_or("1", |(_, n)| n),
            )
            .show_ui(ui, |ui| {
                for (s, name) in SCALES {
                    ui.selectable_value(&mut self.render_scale, s, name);
                }
            });
        frame_graph(ui, &self.frame_times);
        pass_bars(ui, self.pass_times.as_deref());
        ui.separator();
        ui.strong("Camera");
        ui.horizontal(|ui| {
            ui.label(format!("{} (Tab)", info.controller));
            if ui.button("switch").clicked() {
                requests.push(PanelRequest::ToggleController);
            }
        });
        ui.horizontal(|ui| {
            if ui
                .button(if info.recording {
                    "stop recording"
                } else {
                    "record path"
                })
                .clicked()
            {
                requests.push(PanelRequest::ToggleRecording);
            }
            if ui
                .button(if info.playing { "stop" } else { "play path" })
                .clicked()
            {
                requests.push(PanelRequest::TogglePlayback);
            }
        });
        if ui.button("screenshot (F12)").clicked() {
            requests.push(PanelRequest::Screenshot);
        }
        egui::CollapsingHeader::new("keys").show(ui, |ui| {
            for line in KEYS {
                ui.small(*line);
            }
        });
    }
}

/// The window's keys, as the README lists them.
pub const KEYS: &[&str] = &[
    "drag: turn (orbit) or look (fly)",
    "Shift+drag, right drag: pan (orbit)",
    "wheel: zoom (orbit), speed (fly)",
    "W A S D, Q E: fly; Shift faster",
    "Tab: orbit / fly",
    "Home: scene camera; F: frame the scene",
    "1-9: bookmark; Ctrl+1-9: store bookmark",
    "R: record path; Space: play path",
    "F12: screenshot; F1: panel; Esc: quit",
    "drop a scene file on the window to open it",
];

/// The name of `value` in a table of choices.
fn name_of<T: PartialEq + Copy>(table: &[(T, &'static str)], value: T) -> &'static str {
    table
        .iter()
        .find(|(v, _)| *v == value)
        .map_or("?", |(_, n)| n)
}

/// A small graph of recent frame times.
fn frame_graph(ui: &mut egui::Ui, times: &[f32]) {
    let last = times.last().copied().unwrap_or(0.0);
    ui.label(format!("frame {last:.0} ms"));
    let (rect, _) =
        ui.allocate_exact_size(egui::vec2(ui.available_width(), 40.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_gray(30));
    let max = times.iter().copied().fold(1.0f32, f32::max);
    let n = GRAPH_FRAMES as f32;
    let points: Vec<egui::Pos2> = times
        .iter()
        .enumerate()
        .map(|(i, t)| {
            egui::pos2(
                rect.left() + rect.width() * (i as f32 + n - times.len() as f32) / n,
                rect.bottom() - rect.height() * t / max,
            )
        })
        .collect();
    painter.add(egui::Shape::line(
        points,
        egui::Stroke::new(1.0, egui::Color32::LIGHT_GREEN),
    ));
}

/// The last frame's GPU time per pass as bars scaled to the slowest.
fn pass_bars(ui: &mut egui::Ui, times: Option<&[(&'static str, f64)]>) {
    let Some(times) = times else {
        ui.small("no per-pass GPU times: the adapter has no timestamp queries");
        return;
    };
    let max = times.iter().map(|(_, ms)| *ms).fold(1e-6, f64::max);
    for (name, ms) in times {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(60.0, 10.0), egui::Sense::hover());
            let width = rect.width() * (*ms / max) as f32;
            ui.painter().rect_filled(
                egui::Rect::from_min_size(rect.min, egui::vec2(width, rect.height())),
                1.0,
                egui::Color32::LIGHT_BLUE,
            );
            ui.small(format!("{name} {ms:.1} ms"));
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        render: RenderArgs,
    }

    fn args(line: &[&str]) -> RenderArgs {
        Cli::parse_from(std::iter::once("lustre").chain(line.iter().copied())).render
    }

    #[test]
    fn the_panel_starts_from_the_options_and_gives_them_back() {
        let a = args(&[
            "glosbox",
            "--photons",
            "300000",
            "--aa",
            "8",
            "--exposure",
            "1.5",
        ]);
        let panel = Panel::from_args(&a);
        let back = panel.apply(&a);
        assert_eq!(back.photons, 300_000);
        assert_eq!(back.aa, 8);
        assert_eq!(back.exposure, 1.5);
        assert_eq!(back.technique, a.technique);
        assert_eq!(back.scene, "glosbox");
    }

    #[test]
    fn settings_map_to_the_options_of_the_same_render() {
        let a = args(&["cornell"]);
        let mut panel = Panel::from_args(&a);
        panel.technique = Technique::Mpr;
        panel.photons = 3_000_000;
        panel.splat_resolution = SplatResolutionArg::Half;
        panel.light_samples = 4;
        let b = panel.apply(&a);
        assert_eq!(b.technique, Technique::Mpr);
        assert_eq!(b.photons, 3_000_000);
        assert_eq!(b.splat_resolution, SplatResolutionArg::Half);
        assert_eq!(b.light_samples, 4);
        // What the panel does not set is kept.
        assert_eq!(b.seed, a.seed);
        assert_eq!(b.size, a.size);
    }

    #[test]
    fn lighting_settings_relight_and_frame_settings_redraw() {
        let a = args(&["glosbox"]);
        let before = Panel::from_args(&a);
        let mut p = before.clone();
        assert_eq!(p.changes(&before), None);
        p.photons = 100_000;
        assert_eq!(p.changes(&before), Some(PanelRequest::Relight));
        let mut p = before.clone();
        p.technique = Technique::Beams;
        assert_eq!(p.changes(&before), Some(PanelRequest::Relight));
        for change in [
            |p: &mut Panel| p.exposure += 1.0,
            |p: &mut Panel| p.components.splats = false,
            |p: &mut Panel| p.render_scale = 0.5,
            |p: &mut Panel| p.aa = 1,
            |p: &mut Panel| p.splat_resolution = SplatResolutionArg::Full,
        ] {
            let mut p = before.clone();
            change(&mut p);
            assert_eq!(p.changes(&before), Some(PanelRequest::Redraw));
        }
        // The graph and the panel's visibility change no frame.
        let mut p = before.clone();
        p.push_frame_time(12.0);
        assert_eq!(p.changes(&before), None);
    }

    #[test]
    fn the_graph_keeps_the_latest_frames() {
        let mut p = Panel::from_args(&args(&["glosbox"]));
        for i in 0..(GRAPH_FRAMES + 10) {
            p.push_frame_time(i as f32);
        }
        assert_eq!(p.frame_times.len(), GRAPH_FRAMES);
        assert_eq!(p.frame_times[0], 10.0);
    }

    #[test]
    fn every_technique_offered_lights_any_camera() {
        for (t, _) in TECHNIQUES {
            assert!(!t.per_vertex(), "{t:?}");
        }
    }
}
