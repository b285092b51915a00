//! One module per pass, mirrored by one shader file each (`gbuffer` -> gbuffer.vert/.frag,
//! `composite` -> composite.comp, ...). Each pass declares its inputs and outputs; the frame
//! graph does the rest.

pub mod composite;
pub mod fullscreen;
pub mod gbuffer;
pub mod gi;
pub mod gi_fill;
pub mod history;
pub mod inject;
pub mod light_grid_update;
pub mod pathtrace;
pub mod primary_rays;
pub mod radiance_cache;
pub mod reflections;
pub mod shadows;
pub mod svgf;
pub mod taa;
pub mod tonemap;

use crate::gpu::{Context, ShaderLibrary};
use crate::world::SceneGpu;
use std::sync::Arc;

/// What every pass constructor needs.
pub struct PassBuilder<'a> {
    pub ctx: &'a Arc<Context>,
    pub shaders: &'a ShaderLibrary,
    pub scene: &'a SceneGpu,
}

impl PassBuilder<'_> {
    /// Module key of a ray-traced shader for the scene's ray backend (`shadows.comp:compute`).
    pub fn traced_shader(&self, file: &str) -> String {
        format!("{file}:{}", self.scene.accel.backend().variant())
    }
}
