//! composite: the frame in linear HDR (shaders-glsl/composite.comp): emission, punctual lights
//! with their ray-traced visibility, the diffuse signal remodulated by the albedo, and the
//! specular signal.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "composite";
pub const COLOR: &str = "composite.color";

/// `diffuse`: demodulated diffuse light (gi, denoised or not); `specular`: the specular lobe's
/// ray-traced light (reflections, denoised or not).
/// `visibility`: the shadows chain's output (see shadows::Chain).
pub fn new(b: &PassBuilder, visibility: &str, diffuse: &str, specular: &str) -> Result<FullscreenPass> {
    let inputs = [
        "gbuffer.depth",
        "gbuffer.normal",
        "gbuffer.base_color",
        "gbuffer.metal_rough",
        "gbuffer.emissive",
        "gbuffer.ids",
        visibility,
        diffuse,
        specular,
    ]
    .map(|n| (n.to_string(), Read::Texel))
    .to_vec();
    let outputs = vec![OutputDesc::storage(NAME, "color", vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    FullscreenPass::new(b, NAME, "composite.comp", inputs, outputs, Vec::new())
}
