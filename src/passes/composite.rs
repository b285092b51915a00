//! composite: direct light from the punctual lights plus emission, in linear HDR
//! (shaders-glsl/composite.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "composite";
pub const COLOR: &str = "composite.color";

pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let inputs = [
        "gbuffer.depth",
        "gbuffer.normal",
        "gbuffer.base_color",
        "gbuffer.metal_rough",
        "gbuffer.emissive",
        "gbuffer.ids",
        super::shadows::VISIBILITY,
    ]
    .map(|n| (n.to_string(), Read::Texel))
    .to_vec();
    let outputs = vec![OutputDesc::storage(NAME, "color", vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    FullscreenPass::new(b, NAME, "composite.comp", inputs, outputs, Vec::new())
}
