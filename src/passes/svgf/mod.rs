//! SVGF (Schied et al. 2017, with Falcor's defaults): spatiotemporal variance-guided filtering
//! of demodulated signals, as a chain of passes. The frame's diffuse and specular signals:
//!
//! `svgf_temporal_diffuse_specular` (each signal's colour carries the luminance's deviation in
//! alpha) -> `svgf_atrous_diffuse_specular_0` ... `_<n-1>`, each stage filtering both at once,
//!
//! what glass and blended surfaces let through, `svgf_temporal_let_through` ->
//! `svgf_atrous_let_through_<i>`, and a lone signal (the tests' injected one) the same with
//! `svgf_temporal_<signal>` and `svgf_atrous_<signal>_<i>`. Each stage is a pass instance with its own named outputs, so
//! `--dump-passes` shows the chain step by step. The first a-trous iteration's colour, and the
//! temporal moments and history length, are kept for the next frame by the `history` pass.
//! What the edge-stopping weights read of a neighbour (shading normal and view depth) is one
//! texel of the G-buffer, `gbuffer.normal` (common/svgf.glsl, the guide texel).

pub mod atrous;
pub mod temporal;

use super::PassBuilder;
use super::history::{Kept, Restarts};
use crate::gpu::vk;
use crate::graph::{Instance, Output, Pass, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

/// The format of a filtered signal (svgf_temporal's colour and every a-trous iteration's): half
/// precision, the standard deviation of the luminance in alpha (`svgf_pack` in
/// common/svgf.glsl says why).
pub const COLOR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The run name of the pair's stages (`svgf_temporal_diffuse_specular`,
/// `svgf_atrous_diffuse_specular_0`).
pub const PAIR: &str = "diffuse_specular";

/// The run name of the chain of what surfaces let through (`svgf_temporal_let_through`).
pub const LET_THROUGH: &str = "let_through";

/// common/svgf.glsl's SVGF_SHARP_SPECULAR: the pair's specular signal is made of reflection
/// rays (a narrow lobe's history follows the reflected object, its filter keeps it sharp).
const SHARP_SPECULAR: u32 = 1;

/// The default of `SvgfSettings::converged`.
const CONVERGED: f32 = 0.05;

/// The named settings of the filter. Defaults follow Falcor's SVGFPass (iterations 4,
/// phiColor 10, phiNormal 128, alpha 0.05, momentsAlpha 0.2, history capped at 32) and the
/// SVGF paper (sigma_z 1).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct SvgfSettings {
    /// A-trous iterations (step 1, 2, 4, ...).
    pub iterations: u32,
    /// Minimum weight of the new frame in the colour history.
    pub alpha: f32,
    /// Minimum weight of the new frame in the moments history.
    pub moments_alpha: f32,
    /// Depth edge-stopping (scaled by the screen-space depth gradient).
    pub sigma_z: f32,
    /// Normal edge-stopping exponent.
    pub sigma_n: f32,
    /// Luminance edge-stopping (scaled by the standard deviation).
    pub sigma_l: f32,
    /// Longest history in frames.
    pub history_cap: f32,
    /// Outliers: input luminance is clamped to mean + this many standard deviations of its
    /// 7x7 neighbourhood (the centre excluded) before anything accumulates it; where the
    /// history is established, of its 3x3 neighbourhood, the brightest left out, and 3x wider.
    pub clamp_sigma: f32,
    /// Converged: a-trous iterations after the first leave a signal's pixel as it is where the
    /// estimated noise of its accumulated value, sqrt(variance / history length), is below
    /// this fraction of its luminance; 0 filters every pixel in every iteration.
    pub converged: f32,
}

impl Default for SvgfSettings {
    fn default() -> Self {
        Self {
            iterations: 4,
            alpha: 0.05,
            moments_alpha: 0.2,
            sigma_z: 1.0,
            sigma_n: 128.0,
            sigma_l: 10.0,
            history_cap: 32.0,
            clamp_sigma: 4.0,
            converged: CONVERGED,
        }
    }
}

/// The push-constant block of common/svgf.glsl (`SvgfParams`), shared by the three stages.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub alpha: f32,
    pub moments_alpha: f32,
    pub sigma_z: f32,
    pub sigma_n: f32,
    pub sigma_l: f32,
    pub history_cap: f32,
    pub clamp_sigma: f32,
    pub converged: f32,
    pub step: i32,
    pub flags: u32,
}

impl SvgfSettings {
    fn push_constants(&self, step: i32, flags: u32) -> Params {
        Params {
            alpha: self.alpha,
            moments_alpha: self.moments_alpha,
            sigma_z: self.sigma_z,
            sigma_n: self.sigma_n,
            sigma_l: self.sigma_l,
            history_cap: self.history_cap,
            clamp_sigma: self.clamp_sigma,
            converged: self.converged,
            step,
            flags,
        }
    }
}

/// A built chain: its passes in order, the filtered outputs (one per signal, in the order
/// given), and what it keeps.
pub struct Chain {
    pub passes: Vec<Box<dyn Pass>>,
    pub outputs: Vec<Output>,
    pub kept: Vec<Kept>,
}

/// The temporal stage of the chain of `signal` (`svgf_temporal_signal`, or of the pair,
/// `svgf_temporal_diffuse_specular`): `temporal::COLOR.of(svgf::signal("signal"))`.
pub const fn signal(signal: &'static str) -> Instance {
    Instance { signal: Some(signal), iteration: None }
}

/// A-trous iteration `i` of the chain of `signal`, or of the pair (`svgf_atrous_signal_0`,
/// `svgf_atrous_diffuse_specular_0`).
pub const fn iteration(signal: &'static str, i: u32) -> Instance {
    Instance { signal: Some(signal), iteration: Some(i) }
}

/// The frame's chains: the demodulated RGBA32F `diffuse` and `specular` signals, filtered
/// together by the a-trous iterations. `hit_distance` when the specular signal is made of
/// reflection rays (see [`temporal::pair`]); their narrow lobes then also keep their sharpness.
pub fn pair(
    b: &PassBuilder,
    diffuse: Resource,
    specular: Resource,
    hit_distance: Option<Resource>,
    restarts: Restarts,
    s: &SvgfSettings,
) -> Result<Chain> {
    let iterations = s.iterations.max(1);
    let first = iteration(PAIR, 0);
    let filtered = [atrous::DIFFUSE.of(first), atrous::SPECULAR.of(first)];
    let mut passes: Vec<Box<dyn Pass>> =
        vec![Box::new(temporal::pair(b, (diffuse, specular), filtered, hit_distance, restarts, s)?)];
    for i in 0..iterations {
        passes.push(Box::new(atrous::pair(b, i, s)?));
    }
    let run = signal(PAIR);
    let kept = [[filtered[0], temporal::DIFFUSE_MOMENTS.of(run)], [filtered[1], temporal::SPECULAR_MOMENTS.of(run)]];
    let last = iteration(PAIR, iterations - 1);
    Ok(Chain {
        passes,
        outputs: vec![atrous::DIFFUSE.of(last), atrous::SPECULAR.of(last)],
        kept: kept.into_iter().flat_map(keep).chain([keep_lengths(run)]).collect(),
    })
}

/// The chain of one demodulated RGBA32F signal, `input`, under the name `signal`.
pub fn single(b: &PassBuilder, signal: &'static str, input: Resource, s: &SvgfSettings) -> Result<Chain> {
    let filtered = atrous::COLOR.of(iteration(signal, 0));
    lone(b, signal, temporal::single(b, signal, input, filtered, s)?, s)
}

/// The chain of what glass and blended surfaces let through (`reflections::LET_THROUGH`): its
/// history follows what shows through them, its filter is as sharp as their lobe.
pub fn let_through(b: &PassBuilder, s: &SvgfSettings) -> Result<Chain> {
    let filtered = atrous::COLOR.of(iteration(LET_THROUGH, 0));
    lone(b, LET_THROUGH, temporal::let_through(b, filtered, s)?, s)
}

/// A lone signal's chain under the name `signal`, from its temporal stage.
fn lone(b: &PassBuilder, signal: &'static str, stage: impl Pass + 'static, s: &SvgfSettings) -> Result<Chain> {
    let iterations = s.iterations.max(1);
    let filtered = atrous::COLOR.of(iteration(signal, 0));
    let mut passes: Vec<Box<dyn Pass>> = vec![Box::new(stage)];
    for i in 0..iterations {
        passes.push(Box::new(atrous::single(b, signal, i, s)?));
    }
    let outputs = vec![atrous::COLOR.of(iteration(signal, iterations - 1))];
    let run = self::signal(signal);
    let kept = keep([filtered, temporal::MOMENTS.of(run)]).into_iter().chain([keep_lengths(run)]).collect();
    Ok(Chain { passes, outputs, kept })
}

/// What the next frame's temporal stage of a signal reprojects: its first a-trous colour and
/// its moments (and, for all its signals, `keep_lengths`).
fn keep(images: [Output; 2]) -> [Kept; 2] {
    std::array::from_fn(|k| Kept::new(images[k], temporal::FORMATS[k], temporal::PREVIEWS[k]))
}

/// The history lengths of the temporal stage `run`'s signals, which the next frame reprojects
/// (`temporal::CENTRE`).
fn keep_lengths(run: Instance) -> Kept {
    Kept::new(temporal::CENTRE.of(run), temporal::CENTRE_FORMAT, temporal::CENTRE_PREVIEW)
}
