//! light_grid_update: before the frame's rays, teaches the light grid what its cells see
//! (shaders-glsl/light_grid_update.comp). gi counted last frame's shadow rays per cell and
//! group of resampled lights (an emissive triangle's point counts in the group of the region
//! it lies in); this pass folds the counts into each cell's visibility estimate
//! of each group and rebuilds the cells' CDFs over bound x visibility, so a cell stops spending
//! its draws on lights behind a wall (src/world/light_grid.rs says why the grid alone cannot
//! tell).
//!
//! Its output, `visibility`, shows what it learned: row c holds cell c's estimate for each
//! light group (-1 past the grid's cells). The set-0 buffers it reads and writes are not
//! ordered by the graph: it places its own barriers against last frame's counting and this
//! frame's draws.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, SHARED_BUFFER_ACCESS};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, Preview, ShaderInterface};
use crate::world::light_grid::{GROUP_COUNT, RESOLUTION};
use anyhow::Result;

pub const NAME: &str = "light_grid_update";
/// Per cell (row) and light group (column), the learned share of shadow rays that reach the
/// group's lights.
pub const VISIBILITY: Output = Output::new(NAME, "visibility");
/// Invocations per workgroup (`local_size_x`): one per cell.
const GROUP: u32 = 64;

pub struct LightGridUpdatePass {
    pass: FullscreenPass,
}

pub fn new(b: &PassBuilder) -> Result<LightGridUpdatePass> {
    let cells = RESOLUTION.pow(3);
    let outputs =
        vec![OutputDesc::storage(VISIBILITY, vk::Format::R32_SFLOAT, Preview::Scalar).with_extent(GROUP_COUNT, cells)];
    let mut pass = FullscreenPass::new(b, NAME, "light_grid_update.comp", Vec::new(), outputs, &())?;
    // One invocation per cell of the finest grid.
    pass.groups = Some([cells.div_ceil(GROUP), 1, 1]);
    Ok(LightGridUpdatePass { pass })
}

impl Pass for LightGridUpdatePass {
    fn desc(&self) -> PassDesc {
        self.pass.desc()
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        ctx.rec.memory_barrier(SHARED_BUFFER_ACCESS, SHARED_BUFFER_ACCESS);
        self.pass.record(ctx)?;
        ctx.rec.memory_barrier(SHARED_BUFFER_ACCESS, SHARED_BUFFER_ACCESS);
        Ok(())
    }

    fn shader_interface(&self) -> Option<ShaderInterface> {
        self.pass.shader_interface()
    }
}
