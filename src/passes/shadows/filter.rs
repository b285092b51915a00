//! shadows_filter: temporal mean and dv-scaled cross-bilateral filter of the visibility, the
//! penumbra measure dv_bar, the filter width, and the budget sum (shaders-glsl/shadows_filter.comp).

use super::{Params, RING, penumbra, tent, trace};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "shadows_filter";
/// The filtered visibility, one channel per light.
pub const VISIBILITY: Output = Output::new(NAME, "visibility");
/// dv_bar per light.
pub const DV: Output = Output::new(NAME, "dv");
/// Filter width per light (1..9).
pub const KERNEL: Output = Output::new(NAME, "kernel");
/// Sum of dv_bar x 64 over the image (texel 0,0).
pub const BUDGET: Output = Output::new(NAME, "budget");

pub fn new(b: &PassBuilder, push: &Params) -> Result<FullscreenPass> {
    let inputs =
        [trace::RING0, penumbra::MEAN, penumbra::DV_RAW, tent::DV_V, gbuffer::DEPTH, gbuffer::NORMAL_GEO, gbuffer::IDS]
            .map(Input::texel)
            .to_vec();
    let outputs = vec![
        OutputDesc::storage(VISIBILITY, RING, Preview::Color),
        OutputDesc::storage(DV, RING, Preview::Scalar),
        OutputDesc::storage(KERNEL, RING, Preview::Scalar),
        OutputDesc::storage(BUDGET, vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1),
    ];
    let mut pass = FullscreenPass::new(b, NAME, "shadows_filter.comp", inputs, outputs, push)?;
    // The budget is a sum over this frame's pixels: start it at zero.
    pass.clear_before_dispatch(BUDGET);
    Ok(pass)
}
