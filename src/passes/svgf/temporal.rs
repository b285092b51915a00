//! svgf_temporal: reprojected temporal accumulation of colour and luminance moments with a
//! history length, and the colour's luminance deviation (from the moments, or a 7x7 spatial
//! estimate while the history is young) in its alpha (shaders-glsl/common/svgf_temporal.glsl).
//! The frame's diffuse and specular signals are accumulated together,
//! `svgf_temporal_diffuse_specular` (svgf_temporal_diffuse_specular.comp), sharing the G-buffer's
//! and the outlier window's loads; when the specular signal is made of reflection rays, a
//! narrow lobe's history is reprojected from the reflected object's virtual position. What glass
//! and blended surfaces let through on its own, `svgf_temporal_let_through`
//! (svgf_temporal_let_through.comp), its history reprojected from where that was seen. Any other
//! signal on its own, `svgf_temporal_<signal>` (svgf_temporal.comp).

use super::{COLOR_FORMAT, PAIR, SHARP_SPECULAR, SvgfSettings, signal};
use crate::gpu::vk;
use crate::graph::{self, Instance, Output, OutputDesc, Preview, Resource};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use crate::passes::history;
use crate::passes::history::Restarts;
use crate::passes::reflections;
use anyhow::Result;

pub const NAME: &str = "svgf_temporal";
/// A lone signal's accumulated colour in rgb, its luminance's standard deviation in alpha
/// (`svgf_pack`): each a-trous tap loads one texel for both (`COLOR.of(svgf::signal(signal))`).
pub const COLOR: Output = Output::new(NAME, "color");
/// A lone signal's first and second moments of the luminance.
pub const MOMENTS: Output = Output::new(NAME, "moments");
/// A lone signal's give-back: what the outlier clamp took out of the pixel's sample, weighed
/// as the history would have weighed it, divided among the neighbours on its surface (each
/// share; the first a-trous iteration adds the shares of its neighbours).
pub const CLAMPED: Output = Output::new(NAME, "clamped");
/// The pair's accumulated diffuse colour, as `COLOR` (`DIFFUSE.of(svgf::signal(PAIR))`).
pub const DIFFUSE: Output = Output::new(NAME, "diffuse");
/// The pair's accumulated specular colour, as `COLOR`.
pub const SPECULAR: Output = Output::new(NAME, "specular");
pub const DIFFUSE_MOMENTS: Output = Output::new(NAME, "diffuse_moments");
pub const SPECULAR_MOMENTS: Output = Output::new(NAME, "specular_moments");
/// The pair's give-back of each signal, as `CLAMPED`.
pub const DIFFUSE_CLAMPED: Output = Output::new(NAME, "diffuse_clamped");
pub const SPECULAR_CLAMPED: Output = Output::new(NAME, "specular_clamped");
/// Non-finite input samples caught since the first frame (texel 0,0), of every signal.
pub const REJECTED: Output = Output::new(NAME, "rejected");
/// What each a-trous iteration reads of the pixel it filters besides its guide texel, in one
/// half-precision texel (`svgf_centre` in common/svgf.glsl): the view depth's fwidth, the
/// specular footprint, and each signal's frames accumulated, the history length (z diffuse, w
/// specular; a lone signal's in z), which the next frame reprojects.
pub const CENTRE: Output = Output::new(NAME, "centre");
/// `CENTRE`'s channel of a lone signal's history length (the pair's diffuse; its specular's is
/// the next).
pub const LENGTH_CHANNEL: usize = 2;

/// The formats of a signal's accumulated colour and moments.
pub const FORMATS: [vk::Format; 2] = [COLOR_FORMAT, vk::Format::R32G32_SFLOAT];
/// How the dumps show them.
pub const PREVIEWS: [Preview; 2] = [Preview::Color, Preview::Scalar];
/// `CENTRE`'s format and preview (its history lengths are kept for the next frame too).
pub const CENTRE_FORMAT: vk::Format = COLOR_FORMAT;
pub const CENTRE_PREVIEW: Preview = Preview::Scalar;

/// One signal's images: what it accumulates this frame and writes.
struct Signal {
    /// This frame's samples.
    input: Input,
    /// The chain's first a-trous output, whose previous frame is the colour history.
    filtered: Output,
    /// Colour, moments.
    outputs: [Output; 2],
    /// The give-back (`CLAMPED`).
    clamped: Output,
}

impl Signal {
    /// What the previous frame left of output `k`: the filtered colour, the moments.
    fn previous(&self, k: usize) -> Output {
        if k == 0 { self.filtered } else { self.outputs[k] }
    }
}

/// The G-buffer inputs every variant reads first (common/svgf_temporal.glsl's
/// bindings 0-7).
fn geometry() -> Vec<Input> {
    vec![
        Input::texel(gbuffer::DEPTH),
        Input::texel(gbuffer::NORMAL_GEO),
        Input::texel(gbuffer::IDS),
        Input::texel(gbuffer::MOTION),
        Input::texel(history::of(gbuffer::DEPTH)),
        Input::texel(history::of(gbuffer::NORMAL_GEO)),
        Input::texel(history::of(gbuffer::IDS)),
        Input::texel(gbuffer::NORMAL),
    ]
}

/// Per signal: the input, then (after all inputs) the previous colour and moments; then the
/// previous history lengths (`CENTRE`), then the outputs; `run` names the pass.
fn pass(
    b: &PassBuilder,
    run: Instance,
    shader: &str,
    signals: &[Signal],
    extra: Vec<Input>,
    s: &SvgfSettings,
    flags: u32,
) -> Result<FullscreenPass> {
    let mut inputs = geometry();
    inputs.extend(signals.iter().map(|x| x.input.clone()));
    for k in 0..2 {
        inputs.extend(signals.iter().map(|x| Input::texel(history::of(x.previous(k)))));
    }
    inputs.push(Input::texel(history::of(CENTRE.of(run))));
    inputs.extend(extra);
    let mut outputs = Vec::new();
    for (k, (format, preview)) in FORMATS.into_iter().zip(PREVIEWS).enumerate() {
        outputs.extend(signals.iter().map(|x| OutputDesc::storage(x.outputs[k], format, preview)));
    }
    outputs.extend(signals.iter().map(|x| OutputDesc::storage(x.clamped, COLOR_FORMAT, Preview::Color)));
    outputs.push(OutputDesc::storage(REJECTED.of(run), vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1));
    outputs.push(OutputDesc::storage(CENTRE.of(run), CENTRE_FORMAT, CENTRE_PREVIEW));
    let push = s.push_constants(0, flags);
    FullscreenPass::new(b, &REJECTED.of(run).pass_name(), shader, inputs, outputs, &push)
}

/// The temporal stage of one signal, `input`, under the name `signal_name`; `filtered`, the
/// chain's first a-trous output.
pub fn single(
    b: &PassBuilder,
    signal_name: &'static str,
    input: Resource,
    filtered: Output,
    s: &SvgfSettings,
) -> Result<FullscreenPass> {
    let run = signal(signal_name);
    pass(b, run, "svgf_temporal.comp", &[lone(run, input, filtered)], Vec::new(), s, 0)
}

/// The temporal stage of what surfaces let through (`reflections::LET_THROUGH`, its
/// distance in alpha), under the name `super::LET_THROUGH`; `filtered`, the chain's first
/// a-trous output.
pub fn let_through(b: &PassBuilder, filtered: Output, s: &SvgfSettings) -> Result<FullscreenPass> {
    let run = signal(super::LET_THROUGH);
    let one = lone(run, reflections::LET_THROUGH.into(), filtered);
    let extra = vec![Input::texel(gbuffer::METAL_ROUGH)];
    pass(b, run, "svgf_temporal_let_through.comp", &[one], extra, s, 0)
}

/// A lone signal's images in the temporal stage `run`.
fn lone(run: Instance, input: Resource, filtered: Output) -> Signal {
    Signal {
        input: Input::texel(input).bound_as("in_signal"),
        filtered,
        outputs: [COLOR.of(run), MOMENTS.of(run)],
        clamped: CLAMPED.of(run),
    }
}

/// The temporal stage of the frame's `diffuse` and `specular` signals; `filtered`, the
/// chain's first a-trous outputs of each. `hit_distance`, where the specular signal is made of
/// reflection rays (`reflections::HIT_DISTANCE`): their mean hit distance, which moves a narrow
/// lobe's history with the reflected object rather than the surface. `restarts`: where a
/// radiance cache cell let go of light that is gone, the diffuse history restarts; where a
/// pixel's resampled light went into shadow, each signal's history to which it brought a share.
pub fn pair(
    b: &PassBuilder,
    (diffuse, specular): (Resource, Resource),
    filtered: [Output; 2],
    hit_distance: Option<Resource>,
    restarts: Restarts,
    s: &SvgfSettings,
) -> Result<FullscreenPass> {
    let run = signal(PAIR);
    let signals = [
        Signal {
            input: Input::texel(diffuse).bound_as("in_diffuse"),
            filtered: filtered[0],
            outputs: [DIFFUSE.of(run), DIFFUSE_MOMENTS.of(run)],
            clamped: DIFFUSE_CLAMPED.of(run),
        },
        Signal {
            input: Input::texel(specular).bound_as("in_specular"),
            filtered: filtered[1],
            outputs: [SPECULAR.of(run), SPECULAR_MOMENTS.of(run)],
            clamped: SPECULAR_CLAMPED.of(run),
        },
    ];
    let hit = Input::texel(reflections::HIT_DISTANCE).bound_as("in_hit_distance");
    let mut extra = vec![
        match hit_distance {
            Some(h) => hit.reading(h),
            None => hit.reading(graph::zero(vk::Format::R32_SFLOAT, false)),
        },
        Input::texel(gbuffer::METAL_ROUGH),
    ];
    extra.extend(restarts.inputs());
    let flags = if hit_distance.is_some() { SHARP_SPECULAR } else { 0 };
    pass(b, run, "svgf_temporal_diffuse_specular.comp", &signals, extra, s, flags)
}
