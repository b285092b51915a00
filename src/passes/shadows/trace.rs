//! shadows: shadow rays with adaptive per-pixel counts and the 4-frame visibility ring
//! (shaders-glsl/shadows.comp).

use super::RING;
use crate::graph::{OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use crate::passes::history;
use anyhow::Result;

pub const NAME: &str = "shadows";

pub fn new(b: &PassBuilder, push: Vec<u8>) -> Result<FullscreenPass> {
    let inputs = [
        "gbuffer.depth".to_string(),
        "gbuffer.normal_geo".into(),
        "gbuffer.ids".into(),
        "gbuffer.motion".into(),
        history::of("gbuffer.depth"),
        history::of("shadows.ring0"),
        history::of("shadows.ring1"),
        history::of("shadows.ring2"),
        history::of("shadows.sample_count"),
        history::of("shadows.stable"),
        history::of("shadows_filter.dv"),
        history::of("shadows_filter.budget"),
    ]
    .map(|n| (n, Read::Texel))
    .to_vec();
    let outputs = vec![
        OutputDesc::storage(NAME, "ring0", RING, Preview::Color),
        OutputDesc::storage(NAME, "ring1", RING, Preview::Color),
        OutputDesc::storage(NAME, "ring2", RING, Preview::Color),
        OutputDesc::storage(NAME, "ring3", RING, Preview::Color),
        OutputDesc::storage(NAME, "sample_count", RING, Preview::Scalar),
        OutputDesc::storage(NAME, "stable", RING, Preview::Scalar),
    ];
    FullscreenPass::new(b, NAME, &b.traced_shader("shadows.comp"), inputs, outputs, push)
}
