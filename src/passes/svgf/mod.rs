//! SVGF (Schied et al. 2017, with Falcor's defaults): spatiotemporal variance-guided filtering
//! of one demodulated signal, as a chain of passes:
//!
//! `svgf_temporal_<signal>` -> `svgf_variance_<signal>` -> `svgf_atrous_<signal>_0` ... `_<n-1>`
//!
//! Each stage is a pass instance with its own named outputs, so `--dump-passes` shows the chain
//! step by step. The first a-trous iteration's colour, and the temporal moments and history
//! length, are kept for the next frame by the `history` pass.

pub mod atrous;
pub mod temporal;
pub mod variance;

use super::PassBuilder;
use super::history::Kept;
use crate::gpu::vk;
use crate::graph::{Instance, Output, Pass, Preview, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

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
    /// 7x7 neighbourhood (the centre excluded) before anything accumulates it.
    pub clamp_sigma: f32,
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
    pub step: i32,
}

impl SvgfSettings {
    fn push_constants(&self, step: i32) -> Params {
        Params {
            alpha: self.alpha,
            moments_alpha: self.moments_alpha,
            sigma_z: self.sigma_z,
            sigma_n: self.sigma_n,
            sigma_l: self.sigma_l,
            history_cap: self.history_cap,
            clamp_sigma: self.clamp_sigma,
            step,
        }
    }
}

/// A built chain: its passes in order, the filtered output, and what it keeps.
pub struct Chain {
    pub passes: Vec<Box<dyn Pass>>,
    pub output: Output,
    pub kept: Vec<Kept>,
}

/// The temporal and variance stages of the chain of `signal` (`svgf_temporal_diffuse`):
/// `temporal::COLOR.of(svgf::signal("diffuse"))`.
pub const fn signal(signal: &'static str) -> Instance {
    Instance { signal: Some(signal), iteration: None }
}

/// A-trous iteration `i` of the chain of `signal` (`svgf_atrous_diffuse_0`).
pub const fn iteration(signal: &'static str, i: u32) -> Instance {
    Instance { signal: Some(signal), iteration: Some(i) }
}

/// The chain filtering `input` (a demodulated RGBA32F signal) under the name `signal`;
/// `hit_distance` for a signal of reflection rays (see [`temporal::new`]).
pub fn chain(
    b: &PassBuilder,
    signal: &'static str,
    input: Resource,
    hit_distance: Option<Resource>,
    s: &SvgfSettings,
) -> Result<Chain> {
    let iterations = s.iterations.max(1);
    let mut passes: Vec<Box<dyn Pass>> =
        vec![Box::new(temporal::new(b, signal, input, hit_distance, s)?), Box::new(variance::new(b, signal, s)?)];
    for i in 0..iterations {
        passes.push(Box::new(atrous::new(b, signal, i, s)?));
    }
    let run = self::signal(signal);
    let kept = vec![
        Kept::new(atrous::COLOR.of(iteration(signal, 0)), vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        Kept::new(temporal::MOMENTS.of(run), vk::Format::R32G32_SFLOAT, Preview::Scalar),
        Kept::new(temporal::HISTORY_LENGTH.of(run), vk::Format::R32_SFLOAT, Preview::Scalar),
    ];
    Ok(Chain { passes, output: atrous::COLOR.of(iteration(signal, iterations - 1)), kept })
}
