//! The viewer's own camera: fly (WASD and mouse look) and orbit (around a target point), one
//! state for both: a position, a heading (yaw, pitch) and the distance to the orbit target in
//! front of it, so switching modes never moves the picture.

use crate::render::{View, ViewOverride};
use glam::{Mat4, Vec3};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The scene's camera (a glTF camera or the framing camera): the renderer's own.
    Scene,
    Fly,
    Orbit,
}

/// Radians of turn per pixel of mouse movement.
const LOOK_PER_PIXEL: f32 = 0.004;
/// Pitch stays short of straight up and down, where the heading would be undefined.
const MAX_PITCH: f32 = 1.55;

#[derive(Clone, Debug)]
pub struct Controller {
    pub mode: Mode,
    pub position: Vec3,
    /// Heading around +Y; 0 looks down -Z.
    pub yaw: f32,
    /// Up-down angle; positive looks up.
    pub pitch: f32,
    /// Distance from the position to the orbit target, along the heading.
    pub distance: f32,
    /// Fly speed, scene units per second.
    pub speed: f32,
    pub yfov: f32,
    pub znear: f32,
    /// The scene's bounding sphere: the far plane always takes all of it in.
    pub scene: (Vec3, f32),
}

impl Controller {
    /// Starts where `view` is (roll dropped), orbiting a point `distance` ahead; `scene` is
    /// the scene's bounding sphere (centre, radius).
    pub fn from_view(mode: Mode, view: &View, distance: f32, scene: (Vec3, f32)) -> Self {
        let forward = -view.view.inverse().z_axis.truncate().normalize_or(Vec3::NEG_Z);
        let distance = distance.max(1e-3);
        Self {
            mode,
            position: view.position,
            yaw: forward.x.atan2(-forward.z),
            pitch: forward.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            distance,
            // Crosses the distance to the scene's centre in four seconds.
            speed: distance * 0.25,
            yfov: view.yfov,
            znear: view.znear,
            scene,
        }
    }

    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, -cy * cp)
    }

    fn right(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        Vec3::new(cy, 0.0, sy)
    }

    pub fn target(&self) -> Vec3 {
        self.position + self.forward() * self.distance
    }

    /// Moves along the heading: `dir` is (right, up, forward) in [-1, 1] each, for `dt`
    /// seconds at the fly speed (`fast`: four times it). Up is the world's.
    pub fn fly(&mut self, dir: Vec3, dt: f32, fast: bool) {
        let step = self.speed * dt * if fast { 4.0 } else { 1.0 };
        self.position += (self.right() * dir.x + Vec3::Y * dir.y + self.forward() * dir.z) * step;
    }

    /// Mouse look (fly): turns the heading in place by a mouse movement of (dx, dy) pixels.
    pub fn look(&mut self, dx: f32, dy: f32) {
        self.yaw += dx * LOOK_PER_PIXEL;
        self.pitch = (self.pitch - dy * LOOK_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Orbit: turns around the target, which stays put.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let target = self.target();
        self.look(dx, dy);
        self.position = target - self.forward() * self.distance;
    }

    /// Orbit: slides the camera and its target sideways and up by (dx, dy) pixels.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let up = self.right().cross(self.forward());
        let per_pixel = self.distance * 0.0015;
        self.position += (-self.right() * dx + up * dy) * per_pixel;
    }

    /// Mouse wheel: in orbit, moves towards (positive steps) or away from the target; in fly,
    /// changes the speed.
    pub fn wheel(&mut self, steps: f32) {
        let factor = 1.2f32.powf(steps);
        match self.mode {
            Mode::Orbit => {
                let target = self.target();
                self.distance = (self.distance / factor).max(1e-3);
                self.position = target - self.forward() * self.distance;
            }
            _ => self.speed = (self.speed * factor).clamp(1e-4, 1e6),
        }
    }

    pub fn view_matrix(&self) -> Mat4 {
        Mat4::look_to_rh(self.position, self.forward(), Vec3::Y)
    }

    /// What the renderer should see: `None` in scene mode.
    pub fn view_override(&self) -> Option<ViewOverride> {
        (self.mode != Mode::Scene).then(|| ViewOverride {
            view: self.view_matrix(),
            yfov: self.yfov,
            znear: self.znear,
            // Finite (the frame's shading goes black with an infinite far plane) and as far as
            // the far side of the scene, wherever the camera flies.
            zfar: (self.position.distance(self.scene.0) + self.scene.1) * 2.0 + self.znear,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::perspective;

    fn view_from(position: Vec3, target: Vec3) -> View {
        perspective(Mat4::look_at_rh(position, target, Vec3::Y), position, 0.8, 1.0, 0.1, 100.0)
    }

    #[test]
    fn starts_where_the_view_is() {
        let v = view_from(Vec3::new(1.0, 2.0, 5.0), Vec3::new(0.0, 1.0, 0.0));
        let c = Controller::from_view(Mode::Fly, &v, 3.0, (Vec3::ZERO, 1.0));
        let m = c.view_matrix();
        assert!(m.abs_diff_eq(v.view, 1e-5), "{m} vs {}", v.view);
    }

    #[test]
    fn orbit_keeps_the_target_and_distance() {
        let v = view_from(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
        let mut c = Controller::from_view(Mode::Orbit, &v, 5.0, (Vec3::ZERO, 1.0));
        let target = c.target();
        assert!(target.abs_diff_eq(Vec3::ZERO, 1e-5));
        c.orbit(120.0, -40.0);
        assert!(c.target().abs_diff_eq(target, 1e-4));
        assert!((c.position.distance(target) - 5.0).abs() < 1e-4);
        c.wheel(2.0);
        assert!(c.target().abs_diff_eq(target, 1e-4));
        assert!((c.position.distance(target) - 5.0 / 1.44).abs() < 1e-4);
    }

    #[test]
    fn fly_moves_along_the_heading() {
        let v = view_from(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
        let mut c = Controller::from_view(Mode::Fly, &v, 2.0, (Vec3::ZERO, 1.0));
        c.speed = 1.0;
        c.fly(Vec3::new(0.0, 0.0, 1.0), 1.0, false);
        assert!(c.position.abs_diff_eq(Vec3::new(0.0, 0.0, -1.0), 1e-5), "{}", c.position);
        c.fly(Vec3::new(1.0, 0.0, 0.0), 1.0, false);
        assert!(c.position.abs_diff_eq(Vec3::new(1.0, 0.0, -1.0), 1e-5), "{}", c.position);
        c.look(100.0, 0.0);
        assert!(c.forward().x > 0.0, "moving the mouse right turns right");
    }
}
