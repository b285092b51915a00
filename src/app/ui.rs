//! The overlay (egui): what the frame costs and runs on, what it shows, and the controls. It
//! draws from a read-only picture of the viewer ([`Info`]) and a copy of the settings, and
//! hands back what the user asked for ([`Action`]); the viewer applies it.

use super::camera::Mode;
use super::tunables::{self, Kind};
use crate::graph::{PassTime, Resource};
use crate::render::Settings;

/// What the overlay shows about the running viewer.
pub struct Info<'a> {
    pub device: &'a str,
    pub backend: &'a str,
    pub backend_why: &'a str,
    pub pass_times: &'a [PassTime],
    /// The last frame's wall clock, recording to fence (timestamps can miss compute passes).
    pub frame_wall_ms: f64,
    /// Every named output of the frame, in capture order.
    pub outputs: &'a [Resource],
    pub view: Resource,
    /// The scene's cameras by name.
    pub cameras: &'a [String],
    pub scene_camera: Option<usize>,
    pub camera_mode: Mode,
    pub frame: u32,
    pub frame_ms: f32,
    pub size: (u32, u32),
    pub vsync: bool,
    pub present_mode: &'a str,
    pub playing: bool,
    pub time: f32,
    pub shader_dir: Option<&'a str>,
    pub compiling: bool,
    /// The last failed compile's message; the old shaders are still in use.
    pub shader_error: Option<&'a str>,
    /// The last thing done (a saved screenshot, a reload), for the user to see.
    pub message: &'a str,
    /// The radiance cache's live and updated cells in the last frame, when the frame has one.
    pub radiance_cache: Option<crate::passes::radiance_cache::CacheStats>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    View(Resource),
    SceneCamera(usize),
    CameraMode(Mode),
    Play(bool),
    Step,
    Vsync(bool),
    Reload,
    Screenshot,
    Capture,
}

/// Draws the overlay. `settings` is the viewer's editable copy: the caller compares it with
/// the renderer's after the call.
pub fn draw(ctx: &egui::Context, info: &Info, settings: &mut Settings) -> Vec<Action> {
    let mut actions = Vec::new();
    egui::Window::new("hybrid-rt").default_pos([8.0, 8.0]).default_width(280.0).default_open(true).vscroll(true).show(
        ctx,
        |ui| {
            ui.label(format!("{} — {} backend", info.device, info.backend));
            ui.small(info.backend_why);
            ui.label(format!(
                "frame {}  {}x{}  {:.1} ms ({:.1} fps)  {}",
                info.frame,
                info.size.0,
                info.size.1,
                info.frame_ms,
                1000.0 / info.frame_ms.max(1e-3),
                info.present_mode
            ));
            if let Some(c) = info.radiance_cache {
                ui.label(format!(
                    "radiance cache: {} live cells, {} updated, {} restarted on a change",
                    c.live, c.updated, c.restarted
                ));
            }
            ui.horizontal(|ui| {
                if ui.button("Screenshot").on_hover_text("saves the shown image, without this overlay").clicked() {
                    actions.push(Action::Screenshot);
                }
                if ui.button("Capture dump").on_hover_text("every pass output as EXR + PNG + manifest").clicked() {
                    actions.push(Action::Capture);
                }
                let mut vsync = info.vsync;
                if ui.checkbox(&mut vsync, "vsync").changed() {
                    actions.push(Action::Vsync(vsync));
                }
            });
            if !info.message.is_empty() {
                ui.small(info.message);
            }

            let mut view = info.view;
            egui::ComboBox::from_label("view").selected_text(view.to_string()).height(400.0).show_ui(ui, |ui| {
                for name in info.outputs {
                    ui.selectable_value(&mut view, *name, name.to_string());
                }
            });
            if view != info.view {
                actions.push(Action::View(view));
            }

            camera_controls(ui, info, &mut actions);

            // Everything below starts folded, so the picture stays visible in small windows.
            egui::CollapsingHeader::new("GPU time per pass").default_open(false).show(ui, |ui| {
                let total: f64 = info.pass_times.iter().map(|t| t.gpu_ms).sum();
                egui::Grid::new("pass_times").striped(true).show(ui, |ui| {
                    for t in info.pass_times {
                        ui.monospace(&t.pass);
                        ui.monospace(format!("{:8.3} ms", t.gpu_ms));
                        ui.end_row();
                    }
                    ui.strong("total");
                    ui.monospace(format!("{total:8.3} ms"));
                    ui.end_row();
                    ui.strong("frame, wall clock");
                    ui.monospace(format!("{:8.3} ms", info.frame_wall_ms));
                    ui.end_row();
                });
            });

            let mut groups: Vec<&str> = tunables::ALL.iter().map(|t| t.group).collect();
            groups.dedup();
            for group in groups {
                egui::CollapsingHeader::new(group).default_open(false).show(ui, |ui| {
                    for t in tunables::ALL.iter().filter(|t| t.group == group) {
                        tunable_widget(ui, t, settings);
                    }
                });
            }

            egui::CollapsingHeader::new("Shaders")
                .default_open(false)
                .open(info.shader_error.is_some().then_some(true))
                .show(ui, |ui| shader_status(ui, info, &mut actions));
        },
    );
    actions
}

fn camera_controls(ui: &mut egui::Ui, info: &Info, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        for (mode, label) in [(Mode::Scene, "scene camera"), (Mode::Fly, "fly"), (Mode::Orbit, "orbit")] {
            if ui.selectable_label(info.camera_mode == mode, label).clicked() && info.camera_mode != mode {
                actions.push(Action::CameraMode(mode));
            }
        }
    });
    if !info.cameras.is_empty() {
        let current = info.scene_camera.and_then(|i| info.cameras.get(i)).map(String::as_str).unwrap_or("framing");
        egui::ComboBox::from_label("scene camera").selected_text(current).show_ui(ui, |ui| {
            for (i, name) in info.cameras.iter().enumerate() {
                if ui.selectable_label(info.scene_camera == Some(i), format!("{i}: {name}")).clicked() {
                    actions.push(Action::SceneCamera(i));
                }
            }
        });
    }
    ui.small("fly: WASD, Q/E down/up, Shift faster, drag to look, wheel = speed");
    ui.small("orbit: drag turns, right-drag pans, wheel zooms; O: fly/orbit, C: next scene camera");
    ui.small("Space: play/pause, '.': step, V: vsync, H: overlay, P: screenshot, Esc: quit");
    ui.horizontal(|ui| {
        let label = if info.playing { "pause" } else { "play" };
        if ui.button(label).clicked() {
            actions.push(Action::Play(!info.playing));
        }
        if ui.add_enabled(!info.playing, egui::Button::new("step")).clicked() {
            actions.push(Action::Step);
        }
        ui.label(format!("t = {:.3} s", info.time));
    });
}

fn tunable_widget(ui: &mut egui::Ui, t: &tunables::Tunable, settings: &mut Settings) {
    let value = (t.get)(settings);
    let response = match t.kind {
        Kind::Bool => {
            let mut on = value != 0.0;
            let r = ui.checkbox(&mut on, t.name);
            (t.set)(settings, if on { 1.0 } else { 0.0 });
            r
        }
        Kind::Int { min, max } => {
            let mut v = value as u32;
            let r = ui.add(egui::Slider::new(&mut v, min..=max).text(t.name));
            (t.set)(settings, v as f64);
            r
        }
        Kind::Float { min, max, log } => {
            let mut v = value as f32;
            let r = ui.add(egui::Slider::new(&mut v, min..=max).logarithmic(log).text(t.name));
            (t.set)(settings, v as f64);
            r
        }
    };
    response.on_hover_text(t.help);
}

fn shader_status(ui: &mut egui::Ui, info: &Info, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        match info.shader_dir {
            Some(dir) => ui.small(format!("shaders: watching {dir}")),
            None => ui.small("shaders: embedded (no folder watched)"),
        };
        if info.shader_dir.is_some() && ui.add_enabled(!info.compiling, egui::Button::new("reload")).clicked() {
            actions.push(Action::Reload);
        }
    });
    if info.compiling {
        ui.small("compiling…");
    }
    if let Some(e) = info.shader_error {
        ui.colored_label(
            egui::Color32::from_rgb(255, 110, 110),
            "shader compile failed; the previous shaders stay in use:",
        );
        ui.add(egui::Label::new(egui::RichText::new(e).monospace().small()).wrap());
    }
}
