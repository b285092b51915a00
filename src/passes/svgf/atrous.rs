//! svgf_atrous_<signal>_<i>: iteration i of the edge-avoiding a-trous filter, step 2^i
//! (shaders-glsl/svgf_atrous.comp).

use super::{SvgfSettings, iteration, temporal, variance};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "svgf_atrous";
/// The filtered colour (of one run: `COLOR.of(svgf::iteration(signal, i))`).
pub const COLOR: Output = Output::new(NAME, "color");
/// The filtered variance.
pub const VARIANCE: Output = Output::new(NAME, "variance");

pub fn new(b: &PassBuilder, signal: &'static str, i: u32, s: &SvgfSettings) -> Result<FullscreenPass> {
    let (color, variance) = if i == 0 {
        (temporal::COLOR.of(super::signal(signal)), variance::VARIANCE.of(super::signal(signal)))
    } else {
        (COLOR.of(iteration(signal, i - 1)), VARIANCE.of(iteration(signal, i - 1)))
    };
    let inputs = vec![
        Input::texel(color),
        Input::texel(variance),
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::NORMAL),
        Input::texel(gbuffer::IDS),
    ];
    let run = iteration(signal, i);
    let outputs = vec![
        OutputDesc::storage(COLOR.of(run), vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(VARIANCE.of(run), vk::Format::R32_SFLOAT, Preview::Scalar),
    ];
    let push = s.push_constants(1 << i);
    FullscreenPass::new(b, &COLOR.of(run).pass_name(), "svgf_atrous.comp", inputs, outputs, &push)
}
