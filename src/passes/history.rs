//! history: keeps this frame's images that the next frame needs (the G-buffer's depth,
//! normals and ids for reprojection tests; the denoisers' feedback) as `history.*` twins. It
//! copies nothing: each `x` and its `history.x` are two images that the graph swaps at the
//! start of the next frame (graph::PassKind::History), so a pass that reads `history.x` sees
//! the previous frame's `x`, and `x`'s writer overwrites the image of the frame before. That
//! needs every kept `x` written whole, every frame, before anything reads it (the graph checks
//! the order; each writer here stores every pixel). The copies this replaced cost 5.5-8.3 ms of
//! a 410-474 ms frame at 640x360 on lavapipe, and on a GPU a read and a write of every kept
//! image a frame.

use super::gbuffer;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, PassKind, Preview, Resource, Usage};
use anyhow::Result;

pub const NAME: &str = "history";

/// One image kept for the next frame.
#[derive(Clone, Debug)]
pub struct Kept {
    pub source: Output,
    pub format: vk::Format,
    pub preview: Preview,
    /// Size when the source is not frame-sized.
    pub extent: Option<vk::Extent2D>,
}

impl Kept {
    pub fn new(source: Output, format: vk::Format, preview: Preview) -> Self {
        Self { source, format, preview, extent: None }
    }

    pub fn with_extent(mut self, width: u32, height: u32) -> Self {
        self.extent = Some(vk::Extent2D { width, height });
        self
    }
}

/// The previous frame's `source` (shown as `history.<pass>_<output>`).
pub fn of(source: Output) -> Resource {
    Resource::History(source)
}

/// The G-buffer channels every reprojection needs.
pub fn gbuffer() -> Vec<Kept> {
    vec![
        Kept::new(gbuffer::DEPTH, vk::Format::R32G32_SFLOAT, Preview::Depth),
        Kept::new(gbuffer::NORMAL_GEO, vk::Format::R16G16B16A16_SFLOAT, Preview::Normal),
        Kept::new(gbuffer::IDS, vk::Format::R32G32_UINT, Preview::Ids),
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
            kind: PassKind::History,
            inputs: self.kept.iter().map(|k| k.source.into()).collect(),
            outputs: self
                .kept
                .iter()
                .map(|k| OutputDesc {
                    name: of(k.source),
                    format: k.format,
                    usage: Usage::Transfer,
                    preview: k.preview,
                    extent: k.extent,
                })
                .collect(),
        }
    }

    fn record(&mut self, _: &PassContext) -> Result<()> {
        Ok(())
    }
}
