//! shadows: one shadow ray per punctual light (the first four) from every G-buffer surface,
//! through the trace interface (shaders-glsl/shadows.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "shadows";
pub const VISIBILITY: &str = "shadows.visibility";
/// Lights beyond this many are shaded without shadows.
pub const MAX_SHADOWED_LIGHTS: usize = 4;

pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let inputs = ["gbuffer.depth", "gbuffer.normal_geo", "gbuffer.ids"].map(|n| (n.to_string(), Read::Texel)).to_vec();
    let outputs = vec![OutputDesc::storage(NAME, "visibility", vk::Format::R16G16B16A16_SFLOAT, Preview::Color)];
    FullscreenPass::new(b, NAME, &b.traced_shader("shadows.comp"), inputs, outputs, Vec::new())
}
