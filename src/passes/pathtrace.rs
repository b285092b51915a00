//! pathtrace: the progressive reference path tracer (shaders-glsl/pathtrace.comp), run through
//! the trace interface so it works on either ray backend. Each frame adds one sample per pixel:
//! `pathtrace.accum` holds the running sum (alpha = samples), `pathtrace.color` the mean, and
//! `pathtrace.rays` the rays each pixel has traced. Frame 0 starts the sums afresh.

use super::PassBuilder;
use super::fullscreen::FullscreenPass;
use crate::gpu::vk;
use crate::graph::{OutputDesc, Pass, PassContext, PassDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "pathtrace";
pub const ACCUM: &str = "pathtrace.accum";
pub const COLOR: &str = "pathtrace.color";
pub const RAYS: &str = "pathtrace.rays";

/// The shader's push constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    seed: u32,
    max_bounces: u32,
}

pub struct PathtracePass {
    inner: FullscreenPass,
}

pub fn new(b: &PassBuilder, seed: u32, max_bounces: u32) -> Result<PathtracePass> {
    let outputs = vec![
        OutputDesc::storage(NAME, "accum", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(NAME, "color", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(NAME, "rays", vk::Format::R32_UINT, Preview::Scalar),
    ];
    let push = bytemuck::bytes_of(&Params { seed, max_bounces }).to_vec();
    let inner = FullscreenPass::new(b, NAME, &b.traced_shader("pathtrace.comp"), Vec::new(), outputs, push)?;
    Ok(PathtracePass { inner })
}

impl Pass for PathtracePass {
    fn desc(&self) -> PassDesc {
        // The running sums are read back each frame before they are added to: declaring them as
        // inputs too makes the graph order last frame's writes before this frame's reads.
        let mut desc = self.inner.desc();
        desc.inputs.extend([ACCUM.to_string(), RAYS.to_string()]);
        desc
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        self.inner.record(ctx)
    }
}
