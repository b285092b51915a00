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
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "taa";
pub const COLOR: Output = Output::new(NAME, "color");
/// Weight of the new frame in the blend where the image holds still (taa.comp raises it with
/// the motion).
pub const BLEND: f32 = 0.1;

/// taa.comp's push-constant block (`TaaParams`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub blend: f32,
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
    FullscreenPass::new(b, NAME, "taa.comp", inputs, outputs, &Params { blend: BLEND })
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
