//! shadows_filter: temporal mean and dv-scaled cross-bilateral filter of the visibility, the
//! penumbra measure dv_bar, the filter width, and the budget sum (shaders-glsl/shadows_filter.comp).

use super::RING;
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub const NAME: &str = "shadows_filter";

pub fn new(b: &PassBuilder, push: Vec<u8>) -> Result<FullscreenPass> {
    let inputs = [
        "shadows.ring0",
        "shadows.ring1",
        "shadows.ring2",
        "shadows.ring3",
        "shadows_penumbra.dv_raw",
        "shadows_tent_v.dv",
        "gbuffer.depth",
        "gbuffer.normal_geo",
        "gbuffer.ids",
    ]
    .map(|n| (n.to_string(), Read::Texel))
    .to_vec();
    let outputs = vec![
        OutputDesc::storage(NAME, "visibility", RING, Preview::Color),
        OutputDesc::storage(NAME, "dv", RING, Preview::Scalar),
        OutputDesc::storage(NAME, "kernel", RING, Preview::Scalar),
        OutputDesc::storage(NAME, "budget", vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1),
    ];
    let mut pass = FullscreenPass::new(b, NAME, "shadows_filter.comp", inputs, outputs, push)?;
    // The budget is a sum over this frame's pixels: start it at zero.
    pass.clear_before_dispatch(&format!("{NAME}.budget"));
    Ok(pass)
}
