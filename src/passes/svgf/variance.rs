//! svgf_variance_<signal>: variance from the temporal moments, or a 7x7 spatial estimate while
//! the history is shorter than 4 frames (shaders-glsl/svgf_variance.comp).

use super::{SvgfSettings, signal, temporal};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "svgf_variance";
/// The luminance variance (of one chain: `VARIANCE.of(svgf::signal(signal))`).
pub const VARIANCE: Output = Output::new(NAME, "variance");

pub fn new(b: &PassBuilder, signal_name: &'static str, s: &SvgfSettings) -> Result<FullscreenPass> {
    let run = signal(signal_name);
    let inputs = vec![
        Input::texel(temporal::COLOR.of(run)),
        Input::texel(temporal::MOMENTS.of(run)),
        Input::texel(temporal::HISTORY_LENGTH.of(run)),
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::NORMAL),
        Input::texel(gbuffer::IDS),
    ];
    let outputs = vec![OutputDesc::storage(VARIANCE.of(run), vk::Format::R32_SFLOAT, Preview::Scalar)];
    let push = s.push_constants(0);
    FullscreenPass::new(b, &VARIANCE.of(run).pass_name(), "svgf_variance.comp", inputs, outputs, &push)
}
