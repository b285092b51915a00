//! tonemap: exposure, ACES filmic curve and sRGB encoding into 8 bits
//! (shaders-glsl/tonemap.comp). Its output is what PNG files and the window show.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview, Resource};
use anyhow::Result;

pub const NAME: &str = "tonemap";
pub const COLOR: Output = Output::new(NAME, "color");

/// `input` is the HDR image to display (bound as `in_color`).
pub fn new(b: &PassBuilder, input: Resource) -> Result<FullscreenPass> {
    let outputs = vec![OutputDesc::storage(COLOR, vk::Format::R8G8B8A8_UNORM, Preview::Display)];
    FullscreenPass::new(b, NAME, "tonemap.comp", vec![Input::texel(input).bound_as("in_color")], outputs, &())
}
