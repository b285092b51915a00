//! taa: temporal anti-aliasing of the composited HDR frame (shaders-glsl/taa.comp): jittered
//! G-buffer, Catmull-Rom history, YCoCg neighbourhood clamp, less history the faster the image
//! moves, history rejected on disocclusion (motion mismatch), a mirror's history fetched where
//! the reflected object was.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gbuffer;
use super::history::{self, Kept};
use super::reflections;
use crate::gpu::vk;
use crate::graph::{self, Output, OutputDesc, Preview, Resource};
use crate::render::camera::View;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

pub const NAME: &str = "taa";
pub const COLOR: Output = Output::new(NAME, "color");
/// Weight of the new frame in the blend where the image holds still (taa.comp raises it with
/// the motion).
pub const BLEND: f32 = 0.1;

/// Image motion, pixels a frame, from which taa.comp takes the new frame whole and the frame
/// is drawn without jitter ([`jitter_scale`]).
pub const FAST_MOTION: f32 = 4.0;

/// taa.comp's push-constant block (`TaaParams`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub blend: f32,
    pub fast_motion: f32,
}

/// `input` is the HDR image to resolve (bound as `in_color`); `reflections`: whether the frame
/// traces reflection rays, whose hit distance moves a mirror's history with what it reflects.
pub fn new(b: &PassBuilder, input: Resource, reflections: bool) -> Result<FullscreenPass> {
    let hit_distance = Input::texel(reflections::HIT_DISTANCE).bound_as("in_hit_distance");
    let inputs = vec![
        Input::texel(input).bound_as("in_color"),
        Input::texel(gbuffer::MOTION),
        Input::texel(history::of(gbuffer::MOTION)),
        Input::filtered(history::of(COLOR)),
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::METAL_ROUGH),
        if reflections { hit_distance } else { hit_distance.reading(graph::zero(vk::Format::R32_SFLOAT, false)) },
    ];
    let outputs = vec![OutputDesc::storage(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    FullscreenPass::new(b, NAME, "taa.comp", inputs, outputs, &Params { blend: BLEND, fast_motion: FAST_MOTION })
}

/// What TAA needs from the previous frame: its result and the motion of what it showed.
pub fn kept() -> Vec<Kept> {
    vec![
        Kept::new(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        Kept::new(gbuffer::MOTION, vk::Format::R32G32_SFLOAT, Preview::Motion),
    ]
}

/// Halton (2, 3) sub-pixel offsets in [-0.5, 0.5), cycling over 16 frames.
pub fn jitter(frame: u32) -> [f32; 2] {
    let halton = |mut i: u32, base: u32| {
        let (mut f, mut r) = (1.0f32, 0.0f32);
        while i > 0 {
            f /= base as f32;
            r += f * (i % base) as f32;
            i /= base;
        }
        r
    };
    let i = frame % 16 + 1;
    [halton(i, 2) - 0.5, halton(i, 3) - 0.5]
}

/// How much of the jitter a frame gets, from how far the camera moved the image since the last
/// frame (`prev` to `view`; the screen's centre and corners, at the distance of `focus`): all of
/// it while the image holds still, none from [`FAST_MOTION`] pixels a frame, linearly between.
/// The jitter is worth what the history averages of it, and taa.comp keeps as much less
/// history as the image moves faster: a frame taken nearly whole shows its jitter as a shake
/// of up to half a pixel. (The stability suite's fast pan, 2.5 pixels a frame, measured the
/// shipped frame at 1.2x the raw frame's error with full jitter, 0.59x without any.)
pub fn jitter_scale(prev: &View, view: &View, size: Vec2, focus: Vec3) -> f32 {
    let distance = (focus - view.position).length().max(view.znear);
    let speed = [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .map(|(u, v)| {
            let pixel = Vec2::new(u, v) * size;
            let p = view.position + view.ray_dir(pixel, size) * distance;
            (prev.project(p, size) - pixel).length()
        })
        .into_iter()
        .fold(0.0f32, f32::max);
    if speed.is_finite() { (1.0 - speed / FAST_MOTION).clamp(0.0, 1.0) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::perspective;
    use glam::Mat4;

    /// A camera at `x` looking down -Z at the origin, yawed by `yaw` radians.
    fn view(x: f32, yaw: f32) -> View {
        let position = Vec3::new(x, 0.0, 5.0);
        let look = Mat4::from_rotation_y(-yaw) * Mat4::look_at_rh(position, Vec3::new(x, 0.0, 0.0), Vec3::Y);
        perspective(look, position, 1.0, 1.0, 0.1, 100.0)
    }

    #[test]
    fn jitter_shrinks_as_the_camera_moves_the_image() {
        let size = Vec2::splat(256.0);
        let focus = Vec3::ZERO;
        // Still: all of it (to rounding: the corners' rays round-trip through two matrices).
        let still = jitter_scale(&view(0.0, 0.0), &view(0.0, 0.0), size, focus);
        assert!(still > 0.999, "a still camera: {still}");
        // yfov 1 rad over 256 pixels: about 233 pixels per radian at the centre. A turn of half
        // FAST_MOTION's worth moves the centre 2 pixels and the corners a little more.
        let half = 2.0 / 233.0;
        let s = jitter_scale(&view(0.0, 0.0), &view(0.0, half), size, focus);
        assert!((0.3..0.55).contains(&s), "a turn of about 2 pixels a frame: {s}");
        // Sideways by 0.1 at a distance of 5: about 4.7 pixels, past FAST_MOTION.
        assert_eq!(jitter_scale(&view(0.0, 0.0), &view(0.1, 0.0), size, focus), 0.0);
        // A camera cut (the previous view elsewhere entirely) gets no jitter, never a NaN.
        let behind = perspective(
            Mat4::look_at_rh(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, Vec3::Y),
            Vec3::new(0.0, 0.0, -5.0),
            1.0,
            1.0,
            0.1,
            100.0,
        );
        assert_eq!(jitter_scale(&behind, &view(0.0, 0.0), size, focus), 0.0);
    }
}
