//! svgf_atrous: iteration i of the edge-avoiding a-trous filter, step 2^i
//! (shaders-glsl/common/svgf_atrous.glsl). The frame's diffuse and specular signals are filtered
//! together, `svgf_atrous_diffuse_specular_<i>` (svgf_atrous_diffuse_specular.comp), sharing
//! each tap's guide texel and depth and normal weights; any other signal on its own,
//! `svgf_atrous_<signal>_<i>` (svgf_atrous.comp).

use super::{COLOR_FORMAT, PAIR, SvgfSettings, iteration, temporal};
use crate::graph::{self, Output, OutputDesc, Preview};
use crate::passes::PassBuilder;
use crate::passes::fullscreen::{FullscreenPass, Input};
use crate::passes::gbuffer;
use anyhow::Result;

pub const NAME: &str = "svgf_atrous";
/// A lone signal's filtered colour, its luminance's standard deviation in alpha
/// (`COLOR.of(svgf::iteration(signal, i))`).
pub const COLOR: Output = Output::new(NAME, "color");
/// The pair's filtered diffuse signal, its luminance's standard deviation in alpha
/// (`DIFFUSE.of(svgf::iteration(PAIR, i))`).
pub const DIFFUSE: Output = Output::new(NAME, "diffuse");
/// The pair's filtered specular signal, its luminance's standard deviation in alpha.
pub const SPECULAR: Output = Output::new(NAME, "specular");

/// Iteration `i` of one signal.
pub fn single(b: &PassBuilder, signal: &'static str, i: u32, s: &SvgfSettings) -> Result<FullscreenPass> {
    let color = if i == 0 { temporal::COLOR.of(super::signal(signal)) } else { COLOR.of(iteration(signal, i - 1)) };
    let run = iteration(signal, i);
    let inputs = vec![
        Input::texel(color),
        Input::texel(temporal::CENTRE.of(super::signal(signal))),
        Input::texel(gbuffer::NORMAL),
        give_back(temporal::CLAMPED.of(super::signal(signal)), i),
    ];
    let outputs = vec![OutputDesc::storage(COLOR.of(run), COLOR_FORMAT, Preview::Color)];
    let push = s.push_constants(1 << i, 0);
    FullscreenPass::new(b, &COLOR.of(run).pass_name(), "svgf_atrous.comp", inputs, outputs, &push)
}

/// Iteration `i` of the frame's diffuse and specular signals (a narrow reflection lobe's
/// footprint, which keeps it sharp, comes with `temporal::CENTRE`).
pub fn pair(b: &PassBuilder, i: u32, s: &SvgfSettings) -> Result<FullscreenPass> {
    let pair = super::signal(PAIR);
    let (diffuse, specular) = if i == 0 {
        (temporal::DIFFUSE.of(pair), temporal::SPECULAR.of(pair))
    } else {
        (DIFFUSE.of(iteration(PAIR, i - 1)), SPECULAR.of(iteration(PAIR, i - 1)))
    };
    let inputs = vec![
        Input::texel(diffuse).bound_as("in_diffuse"),
        Input::texel(specular).bound_as("in_specular"),
        Input::texel(temporal::CENTRE.of(pair)),
        Input::texel(gbuffer::NORMAL),
        give_back(temporal::DIFFUSE_CLAMPED.of(pair), i),
        give_back(temporal::SPECULAR_CLAMPED.of(pair), i),
    ];
    let run = iteration(PAIR, i);
    let outputs = vec![
        OutputDesc::storage(DIFFUSE.of(run), COLOR_FORMAT, Preview::Color),
        OutputDesc::storage(SPECULAR.of(run), COLOR_FORMAT, Preview::Color),
    ];
    let push = s.push_constants(1 << i, 0);
    let shader = "svgf_atrous_diffuse_specular.comp";
    FullscreenPass::new(b, &DIFFUSE.of(run).pass_name(), shader, inputs, outputs, &push)
}

/// svgf_temporal's give-back of a signal, which iteration 0 (step 1, whose taps are the 8
/// neighbours it was handed to) adds; the later iterations read nothing there (a 1x1 zero
/// image).
fn give_back(clamped: Output, i: u32) -> Input {
    let input = Input::texel(clamped);
    if i == 0 { input } else { input.reading(graph::zero(COLOR_FORMAT, true)) }
}
