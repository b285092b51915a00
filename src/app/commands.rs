//! What scripts and the overlay ask the viewer for: the shown output, scene cameras, play and
//! step, screenshots and captures (never over an existing file unless --force).

use super::camera::Mode;
use super::script::Command;
use super::{Viewer, tunables, ui};
use crate::capture::Capture;
use crate::graph::Resource;
use crate::render::CameraChoice;
use anyhow::{Result, bail};
use std::collections::VecDeque;
use std::path::PathBuf;

impl Viewer {
    /// Runs script commands up to the next one that draws.
    pub(super) fn script_step(&mut self) -> Result<bool> {
        loop {
            if self.frames_left > 0 {
                self.frames_left -= 1;
                self.render()?;
                self.present(None)?;
                return Ok(true);
            }
            let Some(cmd) = self.script.as_mut().and_then(VecDeque::pop_front) else {
                self.script = None;
                self.message = "script done".into();
                return Ok(true);
            };
            match cmd {
                Command::Frames(n) => self.frames_left = n,
                Command::View(name) => {
                    let view = self.renderer.graph.resource_named(&name)?;
                    self.set_view(view)?
                }
                Command::Screenshot(path) => {
                    if !self.present(Some(&path))? {
                        // Nothing was drawn (the swapchain was being rebuilt): again next time.
                        self.script.as_mut().expect("running").push_front(Command::Screenshot(path));
                    }
                    return Ok(true);
                }
                Command::Capture(dir) => {
                    self.capture(Some(dir))?;
                }
                Command::Camera(name) => match name.as_str() {
                    "fly" => self.set_camera_mode(Mode::Fly),
                    "orbit" => self.set_camera_mode(Mode::Orbit),
                    _ => {
                        let choice: CameraChoice = name.parse().unwrap_or_default();
                        self.switch_camera(&choice)?;
                    }
                },
                Command::Pause => self.clock.playing = false,
                Command::Play => self.clock.playing = true,
                Command::Step => self.clock.steps += 1,
                Command::Reload => self.hot_reload(true)?,
                Command::Ui(on) => self.ui_visible = on,
                Command::Vsync(on) => self.swapchain.set_vsync(on),
                Command::Set(key, value) => {
                    tunables::set(&mut self.edit, &key, &value)?;
                    if let Some(e) = self.apply_settings() {
                        bail!("script: {key}={value}: {e}");
                    }
                }
                Command::Quit => return Ok(false),
            }
        }
    }

    /// Shows the scene through one of its cameras (a camera cut); the shadows chain is ranked
    /// at its view.
    pub(super) fn switch_camera(&mut self, choice: &CameraChoice) -> Result<()> {
        self.renderer.set_camera(choice)?;
        self.camera.mode = Mode::Scene;
        self.rank_chain();
        Ok(())
    }

    pub(super) fn set_view(&mut self, view: Resource) -> Result<()> {
        if self.renderer.graph.image(view).is_none() {
            bail!("no pass output named {view} in this frame");
        }
        self.view = view;
        Ok(())
    }

    /// What the overlay asked for; failures become its message (interactive use goes on).
    pub(super) fn ui_action(&mut self, action: ui::Action) {
        let result = match action {
            ui::Action::View(view) => self.set_view(view),
            ui::Action::SceneCamera(i) => self.switch_camera(&CameraChoice::Index(i)),
            ui::Action::CameraMode(mode) => {
                self.set_camera_mode(mode);
                Ok(())
            }
            ui::Action::Play(on) => {
                self.clock.playing = on;
                Ok(())
            }
            ui::Action::Step => {
                self.clock.steps += 1;
                Ok(())
            }
            ui::Action::Vsync(on) => {
                self.swapchain.set_vsync(on);
                Ok(())
            }
            ui::Action::Reload => {
                if let Some(w) = self.watcher.as_mut() {
                    w.start_compile();
                }
                Ok(())
            }
            ui::Action::Screenshot => {
                self.pending_screenshot = Some(self.next_free("screenshot_", ".png"));
                Ok(())
            }
            ui::Action::Capture => self.capture(None).map(|_| ()),
        };
        if let Err(e) = result {
            self.message = format!("{e:#}");
        }
    }

    /// Dumps every pass output of the current frame (the capture of `render --dump-passes`).
    pub(super) fn capture(&mut self, dir: Option<PathBuf>) -> Result<PathBuf> {
        let dir = dir.unwrap_or_else(|| self.next_free("capture_", ""));
        let scene = self.renderer.scene.name.clone();
        let mut c = Capture::new(&dir, false, self.force, &scene, &self.ctx.caps.device_name)?;
        c.dump(&mut self.renderer)?;
        self.message = format!("captured every pass output into {}", dir.display());
        println!("capture {}", dir.display());
        Ok(dir)
    }

    /// `out_dir/PREFIX0001SUFFIX`, the first number not taken.
    pub(super) fn next_free(&self, prefix: &str, suffix: &str) -> PathBuf {
        (1..)
            .map(|i| self.out_dir.join(format!("{prefix}{i:04}{suffix}")))
            .find(|p| !p.exists())
            .expect("some number is free")
    }
}
