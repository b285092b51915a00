//! pathtrace: the progressive reference path tracer (shaders-glsl/pathtrace.comp), run through
//! the trace interface so it works on either ray backend. Each frame adds one sample per pixel:
//! `pathtrace.accum` holds the running sum (alpha = samples), `pathtrace.color` the mean, and
//! `pathtrace.rays` the rays each pixel has traced. Frame 0 starts the sums afresh.

use super::PassBuilder;
use super::fullscreen::FullscreenPass;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, Preview, Resource, ShaderInterface};
use anyhow::Result;

pub const NAME: &str = "pathtrace";
/// The running sum of samples (alpha = samples).
pub const ACCUM: Output = Output::new(NAME, "accum");
/// The mean of the samples so far.
pub const COLOR: Output = Output::new(NAME, "color");
/// Rays each pixel has traced.
pub const RAYS: Output = Output::new(NAME, "rays");

/// pathtrace.comp's push-constant block.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Params {
    pub seed: u32,
    pub max_bounces: u32,
}

pub struct PathtracePass {
    inner: FullscreenPass,
}

pub fn new(b: &PassBuilder, seed: u32, max_bounces: u32) -> Result<PathtracePass> {
    let outputs = vec![
        OutputDesc::storage(ACCUM, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(RAYS, vk::Format::R32_UINT, Preview::Scalar),
    ];
    let push = Params { seed, max_bounces };
    let inner = FullscreenPass::new(b, NAME, &b.traced_shader("pathtrace.comp"), Vec::new(), outputs, &push)?;
    Ok(PathtracePass { inner })
}

impl Pass for PathtracePass {
    fn desc(&self) -> PassDesc {
        // The running sums are read back each frame before they are added to: declaring them as
        // inputs too makes the graph order last frame's writes before this frame's reads.
        let mut desc = self.inner.desc();
        desc.inputs.extend([ACCUM, RAYS].map(Resource::from));
        desc
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        self.inner.record(ctx)
    }

    fn shader_interface(&self) -> Option<ShaderInterface> {
        self.inner.shader_interface()
    }
}
