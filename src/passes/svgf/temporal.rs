//! svgf_temporal_<signal>: reprojected temporal accumulation of colour and luminance moments
//! with a history length, and the colour's luminance deviation (from the moments, or a 7x7
//! spatial estimate while the history is young) in its alpha (shaders-glsl/svgf_temporal.comp).
//! The specular chain behind the reflections pass reprojects a narrow lobe's history from the
//! reflected object's virtual position instead (svgf_temporal_specular.comp,
//! common/svgf_temporal.glsl).

use super::{COLOR_FORMAT, SvgfSettings, guide, signal};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview, Resource};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use crate::passes::history;
use anyhow::Result;

pub const NAME: &str = "svgf_temporal";
/// The accumulated colour in rgb, its luminance's standard deviation in alpha (`svgf_pack`): each
/// a-trous tap loads one texel for both (of one chain: `COLOR.of(svgf::signal(signal))`).
pub const COLOR: Output = Output::new(NAME, "color");
/// First and second moments of the luminance.
pub const MOMENTS: Output = Output::new(NAME, "moments");
/// Frames accumulated.
pub const HISTORY_LENGTH: Output = Output::new(NAME, "history_length");
/// Non-finite input samples caught since the first frame (texel 0,0).
pub const REJECTED: Output = Output::new(NAME, "rejected");

/// `input` is the signal to filter (bound as `in_signal`); `filtered`, the chain's first
/// a-trous output for this signal, whose previous frame is the colour history. `hit_distance`,
/// where the signal is made of reflection rays (`reflections::HIT_DISTANCE`): their mean hit
/// distance, which moves a narrow lobe's history with the reflected object rather than the
/// surface.
pub fn new(
    b: &PassBuilder,
    signal_name: &'static str,
    input: Resource,
    filtered: Output,
    hit_distance: Option<Resource>,
    s: &SvgfSettings,
) -> Result<FullscreenPass> {
    let run = signal(signal_name);
    let mut inputs = vec![
        Input::texel(input).bound_as("in_signal"),
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::NORMAL_GEO),
        Input::texel(gbuffer::IDS),
        Input::texel(gbuffer::MOTION),
        Input::texel(history::of(gbuffer::DEPTH)),
        Input::texel(history::of(gbuffer::NORMAL_GEO)),
        Input::texel(history::of(gbuffer::IDS)),
        Input::texel(history::of(filtered)).bound_as("prev_color"),
        Input::texel(history::of(MOMENTS.of(run))),
        Input::texel(history::of(HISTORY_LENGTH.of(run))),
        Input::texel(guide::GUIDE),
    ];
    let mut shader = "svgf_temporal.comp".to_string();
    if let Some(hit_distance) = hit_distance {
        shader = format!("{}.comp", COLOR.of(run).pass_name());
        inputs.extend([Input::texel(hit_distance).bound_as("in_hit_distance"), Input::texel(gbuffer::METAL_ROUGH)]);
    }
    let outputs = vec![
        OutputDesc::storage(COLOR.of(run), COLOR_FORMAT, Preview::Color),
        OutputDesc::storage(MOMENTS.of(run), vk::Format::R32G32_SFLOAT, Preview::Scalar),
        OutputDesc::storage(HISTORY_LENGTH.of(run), vk::Format::R32_SFLOAT, Preview::Scalar),
        OutputDesc::storage(REJECTED.of(run), vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1),
    ];
    let push = s.push_constants(0, 0);
    FullscreenPass::new(b, &COLOR.of(run).pass_name(), &shader, inputs, outputs, &push)
}
