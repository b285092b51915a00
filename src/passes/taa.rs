//! taa: temporal anti-aliasing of the composited HDR frame (shaders-glsl/taa.comp): jittered
//! G-buffer, Catmull-Rom history, YCoCg neighbourhood clamp, less history the faster the image
//! moves, history rejected on disocclusion (motion mismatch), a mirror's history fetched where
//! the reflected object was, glass's where what it lets through was.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gbuffer;
use super::history::{self, Kept, Restarts};
use super::reflections;
use crate::gpu::vk;
use crate::graph::{self, Output, OutputDesc, Preview, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

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
    /// 1: `reflections::LET_THROUGH` is full size.
    pub let_through: u32,
}

/// `input` is the HDR image to resolve (bound as `in_color`); `reflections`: whether the frame
/// traces reflection rays, whose hit distance moves a mirror's history with what it reflects;
/// `let_through`: whether they write what surfaces let through, which moves glass's history
/// with what shows through it; `restarts`: where light the history holds is gone, which drops
/// it there.
pub fn new(
    b: &PassBuilder,
    input: Resource,
    reflections: bool,
    let_through: bool,
    restarts: Restarts,
) -> Result<FullscreenPass> {
    let hit_distance = Input::texel(reflections::HIT_DISTANCE).bound_as("in_hit_distance");
    let mut inputs = vec![
        Input::texel(input).bound_as("in_color"),
        Input::texel(gbuffer::MOTION),
        Input::texel(history::of(gbuffer::MOTION)),
        Input::filtered(history::of(COLOR)),
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::METAL_ROUGH),
        if reflections { hit_distance } else { hit_distance.reading(graph::zero(vk::Format::R32_SFLOAT, false)) },
        Input::texel(gbuffer::BASE_COLOR),
    ];
    inputs.extend(restarts.inputs());
    // The shader reads it only with the flag.
    let through = Input::texel(reflections::LET_THROUGH).bound_as("in_let_through");
    inputs.push(if let_through {
        through
    } else {
        through.reading(graph::zero(vk::Format::R32G32B32A32_SFLOAT, true))
    });
    let outputs = vec![OutputDesc::storage(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    let push = Params { blend: BLEND, fast_motion: FAST_MOTION, let_through: let_through as u32 };
    FullscreenPass::new(b, NAME, "taa.comp", inputs, outputs, &push)
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

/// How much of the jitter a frame gets, from `image_motion`, how far the camera's motion carried
/// the image since the last frame in pixels (`render::camera::image_motion`): all of it while the
/// image holds still, none from [`FAST_MOTION`] pixels a frame, linearly between. The jitter is
/// worth what the history averages of it, and taa.comp keeps as much less history as the image
/// moves faster: a frame taken nearly whole shows its jitter as a shake of up to half a pixel.
/// (The stability suite's fast pan, 2.5 pixels a frame, measured the shipped frame at 1.2x the
/// raw frame's error with full jitter, 0.66x with this.)
pub fn jitter_scale(image_motion: f32) -> f32 {
    if image_motion.is_finite() { (1.0 - image_motion / FAST_MOTION).clamp(0.0, 1.0) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_shrinks_as_the_image_moves() {
        assert_eq!(jitter_scale(0.0), 1.0);
        assert_eq!(jitter_scale(FAST_MOTION / 2.0), 0.5);
        assert_eq!(jitter_scale(FAST_MOTION), 0.0);
        assert_eq!(jitter_scale(100.0), 0.0);
        assert_eq!(jitter_scale(f32::NAN), 0.0);
        assert_eq!(jitter_scale(f32::INFINITY), 0.0);
    }
}
