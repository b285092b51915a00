//! The view: a camera pose and projection for one frame, from a glTF camera at the current
//! animation pose or, when the scene has none, framed around the scene's bounds.

use crate::scene::{Pose, Scene};
use anyhow::{Result, bail};
use glam::{Mat4, Vec2, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct View {
    /// World-to-view (right-handed, looking down -Z).
    pub view: Mat4,
    /// View-to-clip for Vulkan: depth in [0, 1], +Y down in the image (row 0 at the top).
    pub proj: Mat4,
    pub position: Vec3,
    pub yfov: f32,
    pub znear: f32,
    pub zfar: f32,
}

impl View {
    pub fn view_proj(&self) -> Mat4 {
        self.proj * self.view
    }

    /// The projection shifted by `jitter` pixels (TAA), for an image of `size` pixels.
    pub fn jittered_view_proj(&self, jitter: Vec2, size: Vec2) -> Mat4 {
        let offset = Mat4::from_translation((jitter * 2.0 / size).extend(0.0));
        offset * self.view_proj()
    }

    /// World-space ray direction through a pixel position (pixel centres at +0.5).
    pub fn ray_dir(&self, pixel: Vec2, size: Vec2) -> Vec3 {
        let ndc = pixel / size * 2.0 - 1.0;
        let p = self.view_proj().inverse().project_point3(ndc.extend(1.0));
        (p - self.position).normalize()
    }

    /// Pixel position of a world point (x right, y down, pixel centres at +0.5).
    pub fn project(&self, p: Vec3, size: Vec2) -> Vec2 {
        let ndc = self.view_proj().project_point3(p);
        (ndc.truncate() * 0.5 + 0.5) * size
    }
}

/// How far the camera's motion from `prev` to `view` carries the image, in pixels: the most any
/// of the screen's centre and corners moves, for points at the distance of `focus` (a turn
/// moves every depth alike, a step sideways the near ones more). TAA's jitter follows it
/// (`passes::taa::jitter_scale`).
pub fn image_motion(prev: &View, view: &View, size: Vec2, focus: Vec3) -> f32 {
    let distance = (focus - view.position).length().max(view.znear);
    [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .map(|(u, v)| {
            let pixel = Vec2::new(u, v) * size;
            let p = view.position + view.ray_dir(pixel, size) * distance;
            (prev.project(p, size) - pixel).length()
        })
        .into_iter()
        .fold(0.0f32, |a, b| if b.is_nan() { f32::INFINITY } else { a.max(b) })
}

/// Which camera to use: by name or by index, or automatic.
#[derive(Clone, Debug, Default)]
pub enum CameraChoice {
    /// The scene's first camera, or a framing camera when it has none.
    #[default]
    Default,
    Index(usize),
    Name(String),
}

impl std::str::FromStr for CameraChoice {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(i) => CameraChoice::Index(i),
            Err(_) => CameraChoice::Name(s.to_string()),
        })
    }
}

/// Resolves the camera choice to a scene camera index (None = automatic framing).
pub fn resolve(scene: &Scene, choice: &CameraChoice) -> Result<Option<usize>> {
    let names = || scene.cameras.iter().enumerate().map(|(i, c)| format!("{i}: '{}'", c.name)).collect::<Vec<_>>();
    match choice {
        CameraChoice::Default => Ok((!scene.cameras.is_empty()).then_some(0)),
        CameraChoice::Index(i) if *i < scene.cameras.len() => Ok(Some(*i)),
        CameraChoice::Index(i) => bail!(
            "camera index {i} does not exist; the scene has {} camera(s): [{}]",
            scene.cameras.len(),
            names().join(", ")
        ),
        CameraChoice::Name(n) => match scene.cameras.iter().position(|c| &c.name == n) {
            Some(i) => Ok(Some(i)),
            None => bail!("no camera named '{n}'; the scene has [{}]", names().join(", ")),
        },
    }
}

/// The view at a pose for an output of aspect `aspect` (width / height).
pub fn view_at(scene: &Scene, camera: Option<usize>, pose: &Pose, aspect: f32) -> View {
    match camera {
        Some(i) => {
            let cam = &scene.cameras[i];
            let world = pose.world[cam.node as usize];
            // Scale in the camera's node would skew the view: keep rotation and translation only.
            let (_, rotation, position) = world.to_scale_rotation_translation();
            let view = Mat4::from_rotation_translation(rotation, position).inverse();
            let zfar = cam.zfar.unwrap_or(f32::INFINITY);
            perspective(view, position, cam.yfov, aspect, cam.znear, zfar)
        }
        None => framing_view(scene, pose, aspect),
    }
}

/// Where the chosen camera stands at time 0 (what the default light is decided from).
pub fn start_position(scene: &Scene, choice: &CameraChoice) -> Result<Vec3> {
    // The aspect ratio moves only the framing camera, which stays outside the bounds.
    Ok(view_at(scene, resolve(scene, choice)?, &scene.evaluate(0.0), 1.0).position)
}

/// The chosen camera's view at time 0 for an image of `width` x `height` (what the frame plan
/// ranks the shadows chain's lights by).
pub fn first_view(scene: &Scene, choice: &CameraChoice, width: u32, height: u32) -> Result<View> {
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    Ok(view_at(scene, resolve(scene, choice)?, &scene.evaluate(0.0), aspect))
}

/// How many times over its animation a moving camera's views are taken at, time 0 the first
/// (`shot_views`).
const SHOT_VIEWS: u32 = 8;

/// The chosen camera's views that the frame plan ranks the shadows chain's lights by: its
/// view at time 0 or, where the camera moves with the scene's animation, its views at
/// SHOT_VIEWS times evenly over the animation, so that a camera that walks into another room
/// ranks that room's lights too, by how long and how brightly it sees them. (The scene itself
/// is taken at time 0 in all of them, its surfaces and lights: render::light_view.)
pub fn shot_views(scene: &Scene, choice: &CameraChoice, width: u32, height: u32) -> Result<Vec<View>> {
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    let camera = resolve(scene, choice)?;
    // Each animation loops over its own duration: the longest covers every camera path once.
    let duration = scene.animations.iter().map(|a| a.duration()).fold(0.0, f32::max);
    let views: Vec<View> = (0..SHOT_VIEWS)
        .map(|k| view_at(scene, camera, &scene.evaluate(duration * k as f32 / SHOT_VIEWS as f32), aspect))
        .collect();
    // The framing camera follows the scene's bounds, which an animation moves: it stays one view.
    let moves = camera.is_some() && views.iter().any(|v| v.view != views[0].view);
    Ok(if moves { views } else { vec![first_view(scene, choice, width, height)?] })
}

/// A camera on the +Z side of the scene's bounds, seeing all of it.
fn framing_view(scene: &Scene, pose: &Pose, aspect: f32) -> View {
    let (lo, hi) = scene.bounds(pose);
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let yfov = 45f32.to_radians();
    let half = (yfov * 0.5).min((yfov * 0.5 * aspect).atan().max(1e-3));
    let dist = radius / half.sin();
    let position = centre + Vec3::new(0.0, 0.25, 1.0).normalize() * dist;
    let view = Mat4::look_at_rh(position, centre, Vec3::Y);
    perspective(view, position, yfov, aspect, (dist - radius).max(dist * 1e-3), dist + radius * 2.0)
}

pub fn perspective(view: Mat4, position: Vec3, yfov: f32, aspect: f32, znear: f32, zfar: f32) -> View {
    let mut proj = if zfar.is_finite() {
        Mat4::perspective_rh(yfov, aspect, znear, zfar)
    } else {
        Mat4::perspective_infinite_rh(yfov, aspect, znear)
    };
    // Vulkan's image y points down; flipping clip y keeps row 0 at the top of the picture.
    proj.y_axis.y = -proj.y_axis.y;
    View { view, proj, position, yfov, znear, zfar }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera at `x` looking down -Z at the origin, yawed by `yaw` radians.
    fn yawed(x: f32, yaw: f32) -> View {
        let position = Vec3::new(x, 0.0, 5.0);
        let look = Mat4::from_rotation_y(-yaw) * Mat4::look_at_rh(position, Vec3::new(x, 0.0, 0.0), Vec3::Y);
        perspective(look, position, 1.0, 1.0, 0.1, 100.0)
    }

    #[test]
    fn image_motion_measures_turns_and_steps_in_pixels() {
        let size = Vec2::splat(256.0);
        let focus = Vec3::ZERO;
        // Still: nothing but the rounding of the corners' rays through two matrices.
        assert!(image_motion(&yawed(0.0, 0.0), &yawed(0.0, 0.0), size, focus) < 1e-2);
        // yfov 1 rad over 256 pixels: about 233 pixels per radian at the centre, a little more
        // at the corners. A turn of 2 / 233 rad: 2 pixels and a little more.
        let turn = image_motion(&yawed(0.0, 0.0), &yawed(0.0, 2.0 / 233.0), size, focus);
        assert!((2.0..2.8).contains(&turn), "a turn of about 2 pixels: {turn}");
        // Sideways by 0.1 at a distance of 5: 4.7 pixels at the centre, about 5.9 at the
        // corners, whose points (5 along their rays) are nearer in depth.
        let step = image_motion(&yawed(0.0, 0.0), &yawed(0.1, 0.0), size, focus);
        assert!((5.5..6.3).contains(&step), "a step of about 5.9 pixels: {step}");
        // A camera cut to the opposite side: far off the screen or behind it, never a NaN.
        let behind = perspective(
            Mat4::look_at_rh(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, Vec3::Y),
            Vec3::new(0.0, 0.0, -5.0),
            1.0,
            1.0,
            0.1,
            100.0,
        );
        let cut = image_motion(&behind, &yawed(0.0, 0.0), size, focus);
        assert!(cut > 100.0, "a cut: {cut}");
    }

    #[test]
    fn projection_puts_up_at_the_top() {
        let view = Mat4::look_at_rh(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
        let v = perspective(view, Vec3::new(0.0, 0.0, 5.0), 1.0, 1.0, 0.1, 100.0);
        let size = Vec2::splat(100.0);
        let up = v.project(Vec3::new(0.0, 1.0, 0.0), size);
        assert!(up.y < 50.0, "a point above the centre must be in the upper half, got {up}");
        let right = v.project(Vec3::new(1.0, 0.0, 0.0), size);
        assert!(right.x > 50.0);
        let d = v.ray_dir(Vec2::new(50.0, 50.0), size);
        assert!((d - Vec3::NEG_Z).length() < 1e-5);
    }
}
