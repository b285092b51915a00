//! shadows: shadow rays with adaptive per-pixel counts and the 4-frame visibility ring
//! (shaders-glsl/shadows.comp).

use super::RING;
use crate::gpu::vk;
use crate::graph::{self, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Read};
use crate::passes::history;
use anyhow::Result;

pub const NAME: &str = "shadows";

/// `soft`: some light has a radius, so the pass reads its history (the ring, counts, the
/// filter's statistics); otherwise every history input is a zero image nobody writes: hard
/// lights use none of it.
pub fn new(b: &PassBuilder, push: Vec<u8>, soft: bool) -> Result<FullscreenPass> {
    let prev = |name: &str| if soft { history::of(name) } else { graph::zero(RING, false) };
    let budget = if soft { history::of("shadows_filter.budget") } else { graph::zero(vk::Format::R32_UINT, true) };
    let inputs = [
        "gbuffer.depth".to_string(),
        "gbuffer.normal_geo".into(),
        "gbuffer.ids".into(),
        "gbuffer.motion".into(),
        history::of("gbuffer.depth"),
        prev("shadows.ring0"),
        prev("shadows.ring1"),
        prev("shadows.ring2"),
        prev("shadows.sample_count"),
        prev("shadows.stable"),
        prev("shadows_filter.dv"),
        budget,
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
