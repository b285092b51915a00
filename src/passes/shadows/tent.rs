//! shadows_tent_h, shadows_tent_v: the two axes of the 13x13 tent over the max-filtered
//! variation (shaders-glsl/shadows_tent.comp).

use super::RING;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub fn new(b: &PassBuilder, axis: u32, push: Vec<u8>) -> Result<FullscreenPass> {
    let (name, input) =
        if axis == 0 { ("shadows_tent_h", "shadows_penumbra.dv_max") } else { ("shadows_tent_v", "shadows_tent_h.dv") };
    let outputs = vec![OutputDesc::storage(name, "dv", RING, Preview::Scalar)];
    FullscreenPass::new(b, name, "shadows_tent.comp", vec![(input.to_string(), Read::Texel)], outputs, push)
}
