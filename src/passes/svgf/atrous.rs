//! svgf_atrous_<signal>_<i>: iteration i of the edge-avoiding a-trous filter, step 2^i
//! (shaders-glsl/svgf_atrous.comp).

use super::{Names, SvgfSettings};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub fn new(b: &PassBuilder, names: &Names, i: u32, s: &SvgfSettings) -> Result<FullscreenPass> {
    let (color, variance) = if i == 0 {
        (format!("{}.color", names.temporal), format!("{}.variance", names.variance))
    } else {
        (format!("{}.color", names.atrous(i - 1)), format!("{}.variance", names.atrous(i - 1)))
    };
    let inputs = [color, variance, "gbuffer.depth".into(), "gbuffer.normal".into(), "gbuffer.ids".into()]
        .map(|n| (n, Read::Texel))
        .to_vec();
    let name = names.atrous(i);
    let outputs = vec![
        OutputDesc::storage(&name, "color", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(&name, "variance", vk::Format::R32_SFLOAT, Preview::Scalar),
    ];
    FullscreenPass::new(b, &name, "svgf_atrous.comp", inputs, outputs, s.push_constants(1 << i))
}
