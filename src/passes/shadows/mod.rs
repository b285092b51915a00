//! Ray-traced shadows of the first four punctual lights, after Ray Tracing Gems ch. 13
//! (adaptive sampling): a chain of passes, one file and one shader each.
//!
//! `shadows` (trace, 4-frame visibility ring, sample counts) -> `shadows_penumbra` (dv, 5x5 max)
//! -> `shadows_tent_h` -> `shadows_tent_v` (13x13 tent) -> `shadows_filter` (temporal mean and
//! dv-scaled bilateral filter; dv_bar, kernel width, budget sum).
//!
//! Lights with a radius (sphere lights for points, disk lights for spots) are soft: adaptive
//! sample counts 1..s_max, filtering, history. Lights without one are hard: one ray, no filter.
//! Channels the punctual lights leave free go to mesh lights (small emissive meshes,
//! world::lights::chain_lights), which are soft like sphere lights.
//! The final visibility is `shadows_filter.visibility`, one channel per light, grey; the colour
//! of tinted glass on the way goes beside it, unfiltered, in `shadows.tint`.

pub mod filter;
pub mod penumbra;
pub mod tent;
pub mod trace;

use super::PassBuilder;
use super::history::Kept;
use crate::gpu::vk;
use crate::graph::{Output, Pass, Preview};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

/// The visibility the lighting reads when some light is soft: one channel per light (the first
/// four). With punctual lights only, the chain is the trace pass alone and its `ring0` is read.
pub const VISIBILITY: Output = filter::VISIBILITY;
/// The visibility of a chain without soft lights (see [`Chain::visibility`]).
pub const HARD_VISIBILITY: Output = trace::RING0;
/// The colour beside the visibility (see [`trace::TINT`]).
pub const TINT: Output = trace::TINT;
/// The first this many lights (those `world::lights::chain_lights` ranks first, leading
/// `shading_order`) get the chain's visibility; the rest are resampled in gi.
pub const MAX_SHADOWED_LIGHTS: usize = crate::world::lights::SHADOWED_LIGHTS;

/// The named settings of the adaptive shadows.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ShadowSettings {
    /// Most rays per pixel and area light. The chapter's tiers are 5 (standard) and 8 (high);
    /// the default is 3: the 4-frame ring, the filter and SVGF leave the same error after 64
    /// frames at 5 and at 3 (HDR-FLIP 0.1084 on the default scene, `bench sweep
    /// --configs d4-s5-b1-r1,d4-s3-b1-r1`), and 3 took 6-10% off its frame in two runs.
    pub s_max: u32,
    /// Penumbra threshold on dv_bar: above it the count grows, below it (after 4 stable frames)
    /// it shrinks.
    pub delta: f32,
    /// dv_bar at which the spatial filter reaches its widest, 9x9 (the chapter's 0.4).
    pub eta: f32,
    /// Budget: when dv_bar summed over the image exceeds this fraction of the pixel count, s_max
    /// is lowered in proportion for the next frame.
    pub budget_fraction: f32,
    /// Force 8x8 blocks rotating over 4 frames to be sampled (so every pixel is refreshed at
    /// least every 4th frame even outside penumbrae).
    pub forced_blocks: bool,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { s_max: 3, delta: 0.02, eta: 0.4, budget_fraction: 0.25, forced_blocks: true }
    }
}

/// The push-constant block of common/shadows_common.glsl (`ShadowParams`), shared by the
/// chain's passes.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub s_max: u32,
    pub delta: f32,
    pub eta: f32,
    pub budget: f32,
    pub forced_blocks: u32,
    pub tent_axis: u32,
    /// 1: some thin glass is tinted and the trace pass writes `shadows.tint` (the frame plan).
    pub tinted: u32,
    pub _pad: u32,
    pub mesh_lights: MeshLights,
}

/// Per channel of the chain, the mesh light on it: its first emitter and its triangles (0: the
/// channel is a punctual light's, or free). common/shadows_common.glsl's `MeshLights`.
#[repr(C)]
#[derive(Clone, Copy, Default, Pod, Zeroable)]
pub struct MeshLights {
    pub first_emitter: [u32; MAX_SHADOWED_LIGHTS],
    pub triangles: [u32; MAX_SHADOWED_LIGHTS],
}

impl MeshLights {
    /// The channels after the `punctual` lights' go to `chain` ((instance, first emitter,
    /// triangles): world::lights::chain_lights), in order.
    pub fn new(punctual: usize, chain: &[(u32, u32, u32)]) -> Self {
        let mut m = Self::default();
        for (k, &(_, first, triangles)) in chain.iter().enumerate() {
            let channel = punctual + k;
            m.first_emitter[channel] = first;
            m.triangles[channel] = triangles;
        }
        m
    }
}

impl ShadowSettings {
    fn push_constants(&self, pixels: u32, tent_axis: u32, tinted: bool, mesh_lights: MeshLights) -> Params {
        Params {
            s_max: self.s_max.max(1),
            delta: self.delta,
            eta: self.eta,
            budget: self.budget_fraction * pixels as f32,
            forced_blocks: self.forced_blocks as u32,
            tent_axis,
            tinted: tinted as u32,
            _pad: 0,
            mesh_lights,
        }
    }
}

const RING: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// A built chain.
pub struct Chain {
    pub passes: Vec<Box<dyn Pass>>,
    /// What the next frame needs from this one.
    pub kept: Vec<Kept>,
    /// The visibility the lighting reads.
    pub visibility: Output,
}

/// The chain's passes. With `soft` false (every light punctual, the frame plan's call) only the
/// trace pass runs: one hard-shadow ray per light, nothing kept, nothing filtered. With `tinted`
/// false (no tinted thin glass, the plan's call) `shadows.tint` is 1x1 and holds no tint.
/// `mesh_lights`: the channels of the mesh lights.
pub fn chain(
    b: &PassBuilder,
    s: &ShadowSettings,
    extent: vk::Extent2D,
    soft: bool,
    tinted: bool,
    mesh_lights: MeshLights,
) -> Result<Chain> {
    let pixels = extent.width * extent.height;
    let push = |axis| s.push_constants(pixels, axis, tinted, mesh_lights);
    if !soft {
        let trace = trace::new(b, &push(0), false, tinted)?;
        return Ok(Chain { passes: vec![Box::new(trace)], kept: Vec::new(), visibility: HARD_VISIBILITY });
    }
    let passes: Vec<Box<dyn Pass>> = vec![
        Box::new(trace::new(b, &push(0), true, tinted)?),
        Box::new(penumbra::new(b)?),
        Box::new(tent::new(b, 0, &push(0))?),
        Box::new(tent::new(b, 1, &push(1))?),
        Box::new(filter::new(b, &push(0))?),
    ];
    let mut kept = vec![
        Kept::new(trace::RING0, RING, Preview::Color),
        Kept::new(trace::RING1, RING, Preview::Color),
        Kept::new(trace::RING2, RING, Preview::Color),
        Kept::new(trace::SAMPLE_COUNT, RING, Preview::Scalar),
        Kept::new(trace::STABLE, RING, Preview::Scalar),
        Kept::new(filter::DV, RING, Preview::Scalar),
        Kept::new(filter::BUDGET, vk::Format::R32_UINT, Preview::Scalar).with_extent(1, 1),
    ];
    if tinted {
        kept.push(Kept::new(trace::TINT, trace::TINT_FORMAT, Preview::Tint));
    }
    Ok(Chain { passes, kept, visibility: VISIBILITY })
}
