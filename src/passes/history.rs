//! history: keeps this frame's images that the next frame needs (the G-buffer's depth,
//! normals and ids for reprojection tests; the denoisers' feedback) as `history.*` twins. It
//! copies nothing: each `x` and its `history.x` are two images that the graph swaps at the
//! start of the next frame (graph::PassKind::History), so a pass that reads `history.x` sees
//! the previous frame's `x`, and `x`'s writer overwrites the image of the frame before. That
//! needs every kept `x` written whole, every frame, before anything reads it (the graph checks
//! the order; each writer here stores every pixel). The copies this replaced cost 5.5-8.3 ms of
//! a 410-474 ms frame at 640x360 on lavapipe, and on a GPU a read and a write of every kept
//! image a frame.

use super::fullscreen::Input;
use super::{gbuffer, gi, radiance_cache};
use crate::gpu::vk;
use crate::graph::{self, Output, OutputDesc, Pass, PassContext, PassDesc, PassKind, Preview, Resource, Usage};
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

/// What tells the temporal passes (SVGF's, TAA) that light their history holds is gone where
/// the frame did not announce it (an occluder; a change of the lights restarts every history
/// anyway): each where the frame has the pass that writes it.
#[derive(Clone, Copy, Default)]
pub struct Restarts {
    /// `radiance_cache::CHANGED`: a radiance cache cell around the pixel restarted.
    pub cache_changed: Option<Resource>,
    /// `gi::LIGHT_LOST`: what the pixel's resampled light brought, now in shadow.
    pub light_lost: Option<Resource>,
}

impl Restarts {
    /// Their inputs, `in_cache_changed` and `in_light_lost`, a zero image for either missing.
    pub fn inputs(&self) -> [Input; 2] {
        let bind = |output: Output, name: &str, resource: Option<Resource>, format: vk::Format| {
            Input::texel(output).bound_as(name).reading(resource.unwrap_or_else(|| graph::zero(format, false)))
        };
        [
            bind(radiance_cache::CHANGED, "in_cache_changed", self.cache_changed, vk::Format::R32_SFLOAT),
            bind(gi::LIGHT_LOST, "in_light_lost", self.light_lost, vk::Format::R32G32_SFLOAT),
        ]
    }
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
