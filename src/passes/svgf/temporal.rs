//! svgf_temporal_<signal>: reprojected temporal accumulation of colour and luminance moments
//! with a history length (shaders-glsl/svgf_temporal.comp).

use super::{Names, SvgfSettings, prev};
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub fn new(b: &PassBuilder, names: &Names, input: &str, s: &SvgfSettings) -> Result<FullscreenPass> {
    let n = &names.temporal;
    let inputs = [
        input.to_string(),
        "gbuffer.depth".into(),
        "gbuffer.normal_geo".into(),
        "gbuffer.ids".into(),
        "gbuffer.motion".into(),
        prev("gbuffer.depth"),
        prev("gbuffer.normal_geo"),
        prev("gbuffer.ids"),
        prev(&format!("{}.color", names.atrous(0))),
        prev(&format!("{n}.moments")),
        prev(&format!("{n}.history_length")),
    ]
    .map(|i| (i, Read::Texel))
    .to_vec();
    let outputs = vec![
        OutputDesc::storage(n, "color", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(n, "moments", vk::Format::R32G32_SFLOAT, Preview::Scalar),
        OutputDesc::storage(n, "history_length", vk::Format::R32_SFLOAT, Preview::Scalar),
        // Non-finite input samples caught since the first frame (texel 0,0).
        OutputDesc::storage(n, "rejected", vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1),
    ];
    FullscreenPass::new(b, n, "svgf_temporal.comp", inputs, outputs, s.push_constants(0))
}
