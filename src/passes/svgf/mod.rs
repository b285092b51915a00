//! SVGF (Schied et al. 2017, with Falcor's defaults): spatiotemporal variance-guided filtering
//! of one demodulated signal, as a chain of passes:
//!
//! `svgf_temporal_<signal>` -> `svgf_variance_<signal>` -> `svgf_atrous_<signal>_0` ... `_<n-1>`
//!
//! Each stage is a pass instance with its own named outputs, so `--dump-passes` shows the chain
//! step by step. The first a-trous iteration's colour, and the temporal moments and history
//! length, are kept for the next frame by the `history` pass.

mod atrous;
mod temporal;
mod variance;

use super::PassBuilder;
use super::history::{self, Kept};
use crate::gpu::vk;
use crate::graph::{Pass, Preview};
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

/// The push-constant block of common/svgf.glsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    alpha: f32,
    moments_alpha: f32,
    sigma_z: f32,
    sigma_n: f32,
    sigma_l: f32,
    history_cap: f32,
    clamp_sigma: f32,
    step: i32,
}

impl SvgfSettings {
    fn push_constants(&self, step: i32) -> Vec<u8> {
        bytemuck::bytes_of(&Params {
            alpha: self.alpha,
            moments_alpha: self.moments_alpha,
            sigma_z: self.sigma_z,
            sigma_n: self.sigma_n,
            sigma_l: self.sigma_l,
            history_cap: self.history_cap,
            clamp_sigma: self.clamp_sigma,
            step,
        })
        .to_vec()
    }
}

/// A built chain: its passes in order, the name of the filtered output, and what it keeps.
pub struct Chain {
    pub passes: Vec<Box<dyn Pass>>,
    pub output: String,
    pub kept: Vec<Kept>,
}

/// The names of one chain's outputs.
pub struct Names {
    pub temporal: String,
    pub variance: String,
    signal: String,
}

impl Names {
    pub fn new(signal: &str) -> Self {
        Self {
            temporal: format!("svgf_temporal_{signal}"),
            variance: format!("svgf_variance_{signal}"),
            signal: signal.into(),
        }
    }

    pub fn atrous(&self, i: u32) -> String {
        format!("svgf_atrous_{}_{i}", self.signal)
    }
}

/// The chain filtering `input` (a demodulated RGBA32F signal) under the name `signal`.
pub fn chain(b: &PassBuilder, signal: &str, input: &str, s: &SvgfSettings) -> Result<Chain> {
    let names = Names::new(signal);
    let iterations = s.iterations.max(1);
    let mut passes: Vec<Box<dyn Pass>> =
        vec![Box::new(temporal::new(b, &names, input, s)?), Box::new(variance::new(b, &names, s)?)];
    for i in 0..iterations {
        passes.push(Box::new(atrous::new(b, &names, i, s)?));
    }
    let kept = vec![
        Kept::new(&format!("{}.color", names.atrous(0)), vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        Kept::new(&format!("{}.moments", names.temporal), vk::Format::R32G32_SFLOAT, Preview::Scalar),
        Kept::new(&format!("{}.history_length", names.temporal), vk::Format::R32_SFLOAT, Preview::Scalar),
    ];
    Ok(Chain { passes, output: format!("{}.color", names.atrous(iterations - 1)), kept })
}

/// The previous frame's copy of an output (see `history`).
fn prev(name: &str) -> String {
    history::of(name)
}
