//! shadows: shadow rays with adaptive per-pixel counts and the 4-frame visibility ring
//! (shaders-glsl/shadows.comp).

use super::{Params, RING, filter};
use crate::gpu::vk;
use crate::graph::{self, Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::{gbuffer, history};
use anyhow::Result;

pub const NAME: &str = "shadows";
/// Visibility of this frame (one channel per light); ring1..ring3 hold the three frames before.
pub const RING0: Output = Output::new(NAME, "ring0");
pub const RING1: Output = Output::new(NAME, "ring1");
pub const RING2: Output = Output::new(NAME, "ring2");
pub const RING3: Output = Output::new(NAME, "ring3");
/// Shadow rays per pixel and light (0: culled).
pub const SAMPLE_COUNT: Output = Output::new(NAME, "sample_count");
/// Frames the sample count has not changed.
pub const STABLE: Output = Output::new(NAME, "stable");
/// The colour of what reaches each light's visibility through tinted see-through surfaces, one
/// packed RGBA8 per light (0: none; common/shadow_tint.glsl). The visibility stays grey so that
/// the chain filters one channel per light; composite multiplies the colour back in.
pub const TINT: Output = Output::new(NAME, "tint");
/// Four packed colours, one per light.
pub const TINT_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// `soft`: some light has a radius, so the pass reads its history (the ring, counts, the
/// filter's statistics); otherwise every history input is a zero image nobody writes: hard
/// lights use none of it. `tinted`: some thin glass is tinted, so [`TINT`] is written (and a
/// soft light's reused visibility reads last frame's); otherwise it is 1x1 and zero.
pub fn new(b: &PassBuilder, push: &Params, soft: bool, tinted: bool) -> Result<FullscreenPass> {
    let prev = |output: Output, format: vk::Format, small: bool| {
        let input = Input::texel(history::of(output));
        if soft { input } else { input.reading(graph::zero(format, small)) }
    };
    let inputs = vec![
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::NORMAL_GEO),
        Input::texel(gbuffer::IDS),
        Input::texel(gbuffer::MOTION),
        Input::texel(history::of(gbuffer::DEPTH)),
        prev(RING0, RING, false),
        prev(RING1, RING, false),
        prev(RING2, RING, false),
        prev(SAMPLE_COUNT, RING, false),
        prev(STABLE, RING, false),
        prev(filter::DV, RING, false),
        prev(filter::BUDGET, vk::Format::R32_UINT, true),
        // Read only for a soft light's reused visibility, and only when tinted.
        if tinted {
            prev(TINT, TINT_FORMAT, true)
        } else {
            Input::texel(history::of(TINT)).reading(graph::zero(TINT_FORMAT, true))
        },
    ];
    let outputs = [RING0, RING1, RING2, RING3]
        .map(|o| OutputDesc::storage(o, RING, Preview::Color))
        .into_iter()
        .chain([SAMPLE_COUNT, STABLE].map(|o| OutputDesc::storage(o, RING, Preview::Scalar)))
        .chain([tint_desc(tinted)])
        .collect();
    FullscreenPass::new(b, NAME, &b.traced_shader("shadows.comp"), inputs, outputs, push)
}

fn tint_desc(tinted: bool) -> OutputDesc {
    let desc = OutputDesc::storage(TINT, TINT_FORMAT, Preview::Tint);
    if tinted { desc } else { desc.with_extent(1, 1) }
}
