//! The viewer's input: keys, buttons and mouse movement gathered from window events, the
//! keyboard shortcuts, and the fly/orbit camera they drive.

use super::Viewer;
use super::camera::{Controller, Mode};
use crate::render::CameraChoice;
use anyhow::Result;
use glam::Vec3;
use std::collections::HashSet;
use std::time::Instant;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

/// Keys and buttons held, and mouse movement since the last frame.
#[derive(Default)]
pub(super) struct Input {
    keys: HashSet<KeyCode>,
    /// Keys pressed since the last frame: a tap shorter than a slow frame still moves.
    tapped: HashSet<KeyCode>,
    buttons: HashSet<MouseButton>,
    cursor: Option<(f64, f64)>,
    /// Movement while the left / the right or middle button was held, pixels.
    drag_left: (f32, f32),
    drag_right: (f32, f32),
    wheel: f32,
}

impl Viewer {
    /// Handles a window event; `false` ends the viewer.
    pub(super) fn window_event(&mut self, event: WindowEvent) -> Result<bool> {
        let consumed = self.egui_state.on_window_event(&self.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => return Ok(false),
            WindowEvent::Resized(size) => {
                self.swapchain.resize(size.width, size.height);
                self.resized_at = Some(Instant::now());
            }
            WindowEvent::RedrawRequested => return self.redraw(),
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return Ok(true) };
                if event.state == ElementState::Released {
                    // Releases always count, so a key never sticks when egui took the press.
                    self.input.keys.remove(&code);
                } else if !consumed && !self.egui.wants_keyboard_input() {
                    self.input.keys.insert(code);
                    self.input.tapped.insert(code);
                    if !event.repeat {
                        return self.shortcut(code);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => match state {
                ElementState::Pressed if !consumed && !self.egui.wants_pointer_input() => {
                    self.input.buttons.insert(button);
                }
                _ => {
                    self.input.buttons.remove(&button);
                }
            },
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.input.cursor {
                    let d = ((position.x - x) as f32, (position.y - y) as f32);
                    let add = |acc: &mut (f32, f32)| *acc = (acc.0 + d.0, acc.1 + d.1);
                    if self.input.buttons.contains(&MouseButton::Left) {
                        add(&mut self.input.drag_left);
                    }
                    if self.input.buttons.contains(&MouseButton::Right)
                        || self.input.buttons.contains(&MouseButton::Middle)
                    {
                        add(&mut self.input.drag_right);
                    }
                }
                self.input.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed && !self.egui.wants_pointer_input() => {
                self.input.wheel += match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
            }
            _ => {}
        }
        Ok(true)
    }

    /// Keyboard shortcuts (while the overlay does not take the keyboard).
    pub(super) fn shortcut(&mut self, code: KeyCode) -> Result<bool> {
        match code {
            KeyCode::Escape => return Ok(false),
            // Not Tab: egui takes it for moving the keyboard focus.
            KeyCode::KeyO => {
                let next = if self.camera.mode == Mode::Orbit { Mode::Fly } else { Mode::Orbit };
                self.set_camera_mode(next);
            }
            KeyCode::Space => self.clock.playing = !self.clock.playing,
            KeyCode::Period if !self.clock.playing => self.clock.steps += 1,
            KeyCode::KeyV => self.swapchain.set_vsync(!self.swapchain.vsync),
            KeyCode::F1 | KeyCode::KeyH => self.ui_visible = !self.ui_visible,
            KeyCode::F12 | KeyCode::KeyP => self.pending_screenshot = Some(self.next_free("screenshot_", ".png")),
            KeyCode::KeyC if !self.cameras.is_empty() => {
                let next = self.renderer.camera_index().map_or(0, |i| (i + 1) % self.cameras.len());
                self.switch_camera(&CameraChoice::Index(next))?;
            }
            _ => {}
        }
        Ok(true)
    }

    pub(super) fn set_camera_mode(&mut self, mode: Mode) {
        if self.camera.mode == Mode::Scene && mode != Mode::Scene {
            // Take over from wherever the scene camera is now, orbiting the scene's centre
            // distance.
            let view = self.renderer.last_view.unwrap_or_else(|| self.renderer.view_of(&self.renderer.pose_of(0)));
            let pose = self.renderer.pose_of(self.renderer.frame_index);
            let (lo, hi) = self.renderer.scene.bounds(&pose);
            let (centre, radius) = if lo.is_finite() && hi.is_finite() {
                ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
            } else {
                (Vec3::ZERO, 1.0)
            };
            let distance = (centre - view.position).dot(-view.view.inverse().z_axis.truncate()).max(1e-2);
            self.camera = Controller::from_view(mode, &view, distance, (centre, radius));
        } else {
            self.camera.mode = mode;
        }
    }

    pub(super) fn move_camera(&mut self) {
        let held = |k| self.input.keys.contains(&k) || self.input.tapped.contains(&k);
        let axis = |neg, pos| (held(pos) as i32 - held(neg) as i32) as f32;
        let dir = Vec3::new(
            axis(KeyCode::KeyA, KeyCode::KeyD),
            axis(KeyCode::KeyQ, KeyCode::KeyE),
            axis(KeyCode::KeyS, KeyCode::KeyW),
        );
        let fast = held(KeyCode::ShiftLeft) || held(KeyCode::ShiftRight);
        let (left, right, wheel) = (self.input.drag_left, self.input.drag_right, self.input.wheel);
        self.input.drag_left = (0.0, 0.0);
        self.input.drag_right = (0.0, 0.0);
        self.input.wheel = 0.0;
        self.input.tapped.clear();
        let moved = dir != Vec3::ZERO || left != (0.0, 0.0) || right != (0.0, 0.0) || wheel != 0.0;
        if moved && self.camera.mode == Mode::Scene {
            self.set_camera_mode(Mode::Fly);
        }
        // Slow devices (lavapipe: about a frame a second) still move at the set speed; a stall
        // (a rebuild, a shader compile) does not jump the camera far.
        let dt = (self.frame_ms / 1000.0).min(0.5);
        match self.camera.mode {
            Mode::Scene => {}
            Mode::Fly => {
                self.camera.fly(dir, dt, fast);
                // Either button looks around in fly mode.
                self.camera.look(left.0 + right.0, left.1 + right.1);
            }
            Mode::Orbit => {
                self.camera.fly(dir, dt, fast);
                self.camera.orbit(left.0, left.1);
                self.camera.pan(right.0, right.1);
            }
        }
        if wheel != 0.0 {
            self.camera.wheel(wheel);
        }
    }
}
