//! primary_rays: a closest-hit ray through every pixel centre (shaders-glsl/primary_rays.comp).
//! Not part of the hybrid frame (the G-buffer replaces primary rays); switched on by
//! `Settings::primary_rays` to check that both ray backends agree with the rasteriser.

use super::PassBuilder;
use super::fullscreen::FullscreenPass;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "primary_rays";
/// x = instance (0xffffffff on a miss), y = primitive, z = f32 bits of t, w = front face.
pub const HIT: Output = Output::new(NAME, "hit");
/// View depth of the hit, as gbuffer.depth.
pub const DEPTH: Output = Output::new(NAME, "depth");
/// Barycentrics (u, v) of vertices 1 and 2.
pub const BARY: Output = Output::new(NAME, "bary");

pub fn new(b: &PassBuilder) -> Result<FullscreenPass> {
    let outputs = vec![
        OutputDesc::storage(HIT, vk::Format::R32G32B32A32_UINT, Preview::Ids),
        OutputDesc::storage(DEPTH, vk::Format::R32_SFLOAT, Preview::Depth),
        OutputDesc::storage(BARY, vk::Format::R32G32_SFLOAT, Preview::Color),
    ];
    FullscreenPass::new(b, NAME, &b.traced_shader("primary_rays.comp"), Vec::new(), outputs, &())
}
