//! shadows_tent_h, shadows_tent_v: the two axes of the 13x13 tent over the max-filtered
//! variation (shaders-glsl/shadows_tent.comp).

use super::{Params, RING, penumbra};
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use anyhow::Result;

/// The horizontal axis's result.
pub const DV_H: Output = Output::new("shadows_tent_h", "dv");
/// The vertical axis's result: the 13x13 tent.
pub const DV_V: Output = Output::new("shadows_tent_v", "dv");

/// `axis` 0 filters `shadows_penumbra.dv_max` horizontally, 1 the result vertically.
pub fn new(b: &PassBuilder, axis: u32, push: &Params) -> Result<FullscreenPass> {
    let (input, output) = if axis == 0 { (penumbra::DV_MAX, DV_H) } else { (DV_H, DV_V) };
    let outputs = vec![OutputDesc::storage(output, RING, Preview::Scalar)];
    let inputs = vec![Input::texel(input).bound_as("in_dv")];
    FullscreenPass::new(b, output.pass, "shadows_tent.comp", inputs, outputs, push)
}
