//! svgf_variance_<signal>: variance from the temporal moments, or a 7x7 spatial estimate while
//! the history is shorter than 4 frames (shaders-glsl/svgf_variance.comp), written as the alpha
//! of the temporal colour: each a-trous tap then loads one texel for both.

use super::{SvgfSettings, guide, signal, temporal};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "svgf_variance";
/// The temporal colour in rgb, its luminance variance in alpha (of one chain:
/// `COLOR.of(svgf::signal(signal))`).
pub const COLOR: Output = Output::new(NAME, "color");

pub fn new(b: &PassBuilder, signal_name: &'static str, s: &SvgfSettings) -> Result<FullscreenPass> {
    let run = signal(signal_name);
    let inputs = vec![
        Input::texel(temporal::COLOR.of(run)),
        Input::texel(temporal::MOMENTS.of(run)),
        Input::texel(temporal::HISTORY_LENGTH.of(run)),
        Input::texel(guide::GUIDE),
        Input::texel(gbuffer::DEPTH),
    ];
    let outputs = vec![OutputDesc::storage(COLOR.of(run), vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    let push = s.push_constants(0, 0);
    FullscreenPass::new(b, &COLOR.of(run).pass_name(), "svgf_variance.comp", inputs, outputs, &push)
}
