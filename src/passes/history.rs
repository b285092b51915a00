//! history: copies this frame's images that the next frame needs (the G-buffer's depth,
//! normals and ids for reprojection tests; the denoisers' feedback) into `history.*` twins.
//! It runs last, so a pass that reads `history.x` sees the previous frame's `x`.

use crate::gpu::vk;
use crate::graph::{OutputDesc, Pass, PassContext, PassDesc, PassKind, Preview, Usage};
use anyhow::Result;

pub const NAME: &str = "history";

/// One image kept for the next frame.
#[derive(Clone, Debug)]
pub struct Kept {
    pub source: String,
    pub format: vk::Format,
    pub preview: Preview,
    /// Size when the source is not frame-sized.
    pub extent: Option<vk::Extent2D>,
}

impl Kept {
    pub fn new(source: &str, format: vk::Format, preview: Preview) -> Self {
        Self { source: source.to_string(), format, preview, extent: None }
    }

    pub fn with_extent(mut self, width: u32, height: u32) -> Self {
        self.extent = Some(vk::Extent2D { width, height });
        self
    }
}

/// The name under which the previous frame's `source` can be read.
pub fn of(source: &str) -> String {
    format!("{NAME}.{}", source.replace('.', "_"))
}

/// The G-buffer channels every reprojection needs.
pub fn gbuffer() -> Vec<Kept> {
    vec![
        Kept::new("gbuffer.depth", vk::Format::R32G32_SFLOAT, Preview::Depth),
        Kept::new("gbuffer.normal_geo", vk::Format::R16G16B16A16_SFLOAT, Preview::Normal),
        Kept::new("gbuffer.ids", vk::Format::R32G32_UINT, Preview::Ids),
    ]
}

pub struct HistoryPass {
    kept: Vec<Kept>,
}

pub fn new(kept: Vec<Kept>) -> HistoryPass {
    HistoryPass { kept }
}

impl Pass for HistoryPass {
    fn desc(&self) -> PassDesc {
        PassDesc {
            name: NAME.into(),
            kind: PassKind::Transfer,
            inputs: self.kept.iter().map(|k| k.source.clone()).collect(),
            outputs: self
                .kept
                .iter()
                .map(|k| OutputDesc {
                    name: of(&k.source),
                    format: k.format,
                    usage: Usage::Transfer,
                    preview: k.preview,
                    extent: k.extent,
                })
                .collect(),
        }
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        for k in &self.kept {
            ctx.rec.copy_image(ctx.images.get(&k.source), ctx.images.get(&of(&k.source)));
        }
        Ok(())
    }
}
