//! shadows_penumbra: the per-light variation dv over the cached frames and its 5x5 maximum
//! (shaders-glsl/shadows_penumbra.comp).

use super::RING;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use anyhow::Result;

pub const NAME: &str = "shadows_penumbra";

pub fn new(b: &PassBuilder, push: Vec<u8>) -> Result<FullscreenPass> {
    let inputs = ["shadows.ring0", "shadows.ring1", "shadows.ring2", "shadows.ring3", "gbuffer.ids"]
        .map(|n| (n.to_string(), Read::Texel))
        .to_vec();
    let outputs = vec![
        OutputDesc::storage(NAME, "dv_raw", RING, Preview::Scalar),
        OutputDesc::storage(NAME, "dv_max", RING, Preview::Scalar),
    ];
    FullscreenPass::new(b, NAME, "shadows_penumbra.comp", inputs, outputs, push)
}
