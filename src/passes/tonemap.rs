//! tonemap: exposure, ACES filmic curve and sRGB encoding into 8 bits
//! (shaders-glsl/tonemap.comp). Its output is what PNG files and the window show.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "tonemap";
pub const COLOR: &str = "tonemap.color";

/// `input` is the HDR image to display.
pub fn new(b: &PassBuilder, input: &str) -> Result<FullscreenPass> {
    let outputs = vec![OutputDesc::storage(NAME, "color", vk::Format::R8G8B8A8_UNORM, Preview::Display)];
    FullscreenPass::new(b, NAME, "tonemap.comp", vec![(input.to_string(), Read::Texel)], outputs, Vec::new())
}
