//! svgf_guide: the G-buffer texels the a-trous iterations weigh their taps by (view depth,
//! shading normal, whether there is a surface), packed into one texel per pixel once per frame,
//! so each of an iteration's taps loads one texel instead of three
//! (shaders-glsl/svgf_guide.comp, `svgf_guide_pack` in common/svgf.glsl). The frame runs it
//! once, before any chain.

use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "svgf_guide";
/// The shading normal in rgb, the view depth in alpha (-1: no surface).
pub const GUIDE: Output = Output::new(NAME, "guide");

pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let inputs = vec![Input::texel(gbuffer::DEPTH), Input::texel(gbuffer::NORMAL), Input::texel(gbuffer::IDS)];
    let outputs = vec![OutputDesc::storage(GUIDE, vk::Format::R32G32B32A32_SFLOAT, Preview::Normal)];
    FullscreenPass::new(b, NAME, "svgf_guide.comp", inputs, outputs, &())
}
