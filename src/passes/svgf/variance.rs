//! svgf_variance_<signal>: variance from the temporal moments, or a 7x7 spatial estimate while
//! the history is shorter than 4 frames (shaders-glsl/svgf_variance.comp).

use super::{Names, SvgfSettings};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub fn new(b: &PassBuilder, names: &Names, s: &SvgfSettings) -> Result<FullscreenPass> {
    let t = &names.temporal;
    let inputs = [
        format!("{t}.color"),
        format!("{t}.moments"),
        format!("{t}.history_length"),
        "gbuffer.depth".into(),
        "gbuffer.normal".into(),
        "gbuffer.ids".into(),
    ]
    .map(|i| (i, Read::Texel))
    .to_vec();
    let outputs = vec![OutputDesc::storage(&names.variance, "variance", vk::Format::R32_SFLOAT, Preview::Scalar)];
    FullscreenPass::new(b, &names.variance, "svgf_variance.comp", inputs, outputs, s.push_constants(0))
}
