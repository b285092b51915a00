//! gi_fill: at half or quarter rate, completes gi's signals (shaders-glsl/gi_fill.comp): each
//! pixel gi left untraced takes the mean of its traced neighbours that show the same surface,
//! which gi marked in its radiance's alpha (common/gi_fill.glsl); every other pixel is copied.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gi;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "gi_fill";
/// gi's radiance, every pixel.
pub const RADIANCE: Output = Output::new(NAME, "radiance");
/// gi's specular signal, every pixel.
pub const SPECULAR: Output = Output::new(NAME, "specular");

pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let inputs = vec![Input::texel(gi::RADIANCE), Input::texel(gi::SPECULAR)];
    let outputs = vec![
        OutputDesc::storage(RADIANCE, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(SPECULAR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
    ];
    FullscreenPass::new(b, NAME, "gi_fill.comp", inputs, outputs, &())
}
