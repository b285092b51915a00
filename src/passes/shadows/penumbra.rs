//! shadows_penumbra: the per-light variation dv over the cached frames, its 5x5 maximum, and
//! the mean of the cached frames (shaders-glsl/shadows_penumbra.comp).

use super::{RING, trace};
use crate::graph::{Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "shadows_penumbra";
/// max - min of the visibility over the ring.
pub const DV_RAW: Output = Output::new(NAME, "dv_raw");
/// Its 5x5 maximum.
pub const DV_MAX: Output = Output::new(NAME, "dv_max");
/// The mean of the visibility over the ring (the filter's temporal term).
pub const MEAN: Output = Output::new(NAME, "mean");

/// No push constants: the shader includes shadows_common.glsl but reads none of its settings.
pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let inputs = [trace::RING0, trace::RING1, trace::RING2, trace::RING3, gbuffer::IDS].map(Input::texel).to_vec();
    let outputs = vec![
        OutputDesc::storage(DV_RAW, RING, Preview::Scalar),
        OutputDesc::storage(DV_MAX, RING, Preview::Scalar),
        OutputDesc::storage(MEAN, RING, Preview::Color),
    ];
    FullscreenPass::new(b, NAME, "shadows_penumbra.comp", inputs, outputs, &())
}
