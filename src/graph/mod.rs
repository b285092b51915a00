//! The frame graph. Passes declare the named images they read and the named images they
//! write; the graph creates the images, orders nothing (passes run in the order given, and
//! the graph checks that every input has a producer), places the barriers between passes from
//! those declarations, times each pass with GPU timestamps, and hands any named output to the
//! capture. A new pass gets barriers, timing and dumps by declaring its outputs.

mod sync;

use crate::gpu::{self, Context, Image, Recorder, TimestampPool, vk};
use crate::render::SceneGpu;
use anyhow::{Result, bail};
use std::collections::HashMap;
use std::sync::Arc;
use sync::{Access, SyncState};

/// How a capture previews an output as PNG (the EXR always holds the exact values).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Preview {
    /// HDR or LDR colour: clamped to [0, 1] and sRGB-encoded (LDR images are shown as stored).
    Color,
    /// Already display-encoded (sRGB) colour.
    Display,
    /// Unit vectors: xyz * 0.5 + 0.5.
    Normal,
    /// Positive distances: near bright, far dark, 0 (no surface) black.
    Depth,
    /// Integer ids: a distinct colour per id, no id (0xffffffff) black.
    Ids,
    /// Screen-space motion in pixels: R = x, G = y, centred at 0.5, scaled to the largest motion.
    Motion,
    /// A scalar: min..max mapped to black..white.
    Scalar,
}

/// How a pass writes an output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    /// Written by compute shaders with imageStore.
    Storage,
    /// Written by a copy (the history pass).
    Transfer,
    /// Written as a colour attachment by a raster pass.
    ColorAttachment,
    /// The depth attachment of a raster pass.
    DepthAttachment,
}

#[derive(Clone, Debug)]
pub struct OutputDesc {
    /// `pass.output`, the name used everywhere: shader comments, capture files, UI.
    pub name: String,
    pub format: vk::Format,
    pub usage: Usage,
    pub preview: Preview,
    /// Size when it is not the frame's (small statistics images).
    pub extent: Option<vk::Extent2D>,
}

impl OutputDesc {
    pub fn storage(pass: &str, output: &str, format: vk::Format, preview: Preview) -> Self {
        Self { name: format!("{pass}.{output}"), format, usage: Usage::Storage, preview, extent: None }
    }

    pub fn with_extent(mut self, width: u32, height: u32) -> Self {
        self.extent = Some(vk::Extent2D { width, height });
        self
    }
}

/// Where a pass does its work, which decides the stages its barriers name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    Compute,
    /// Reads its inputs in fragment shaders and writes attachments.
    Raster,
    /// Copies images.
    Transfer,
}

/// What a pass declares about itself.
#[derive(Clone, Debug)]
pub struct PassDesc {
    /// Unique in the frame; several instances of one pass type carry the signal they work on
    /// (`svgf_atrous_diffuse_0`).
    pub name: String,
    pub kind: PassKind,
    /// Named images this pass reads (outputs of passes before it, or of itself last frame).
    pub inputs: Vec<String>,
    pub outputs: Vec<OutputDesc>,
}

/// Everything a pass may touch while it records.
pub struct PassContext<'a> {
    pub rec: &'a Recorder<'a>,
    pub images: &'a Images,
    pub scene: &'a SceneGpu,
    pub extent: vk::Extent2D,
    pub frame_index: u32,
}

pub trait Pass {
    fn desc(&self) -> PassDesc;
    fn record(&mut self, ctx: &PassContext) -> Result<()>;
}

/// The images of a frame, by name.
pub struct Images {
    map: HashMap<String, (Image, OutputDesc)>,
}

impl Images {
    pub fn get(&self, name: &str) -> &Image {
        &self.map[name].0
    }

    pub fn view(&self, name: &str) -> vk::ImageView {
        self.get(name).view
    }

    pub fn desc(&self, name: &str) -> Option<&OutputDesc> {
        self.map.get(name).map(|(_, d)| d)
    }
}

/// Time of one pass in the last frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTime {
    pub pass: String,
    /// From timestamp queries around the pass.
    pub gpu_ms: f64,
    /// Wall clock from the pass's own submission to its fence, when the frame was profiled
    /// (`Renderer::profile_passes`): on lavapipe the only per-pass figure that includes
    /// compute dispatches.
    pub wall_ms: Option<f64>,
}

pub struct Graph {
    passes: Vec<Box<dyn Pass>>,
    descs: Vec<PassDesc>,
    pub images: Images,
    /// Output names in declaration order (the capture writes them in this order).
    pub output_order: Vec<String>,
    sync: HashMap<String, SyncState>,
    timestamps: TimestampPool,
    initialised: bool,
    pub extent: vk::Extent2D,
}

impl Graph {
    pub fn new(ctx: &Arc<Context>, passes: Vec<Box<dyn Pass>>, extent: vk::Extent2D) -> Result<Self> {
        let descs: Vec<PassDesc> = passes.iter().map(|p| p.desc()).collect();
        let mut map = HashMap::new();
        let mut output_order = Vec::new();
        for d in &descs {
            for o in &d.outputs {
                if map.contains_key(&o.name) {
                    bail!("frame graph: output {} is written by two passes", o.name);
                }
                let usage = match o.usage {
                    Usage::Storage | Usage::Transfer => vk::ImageUsageFlags::STORAGE,
                    Usage::ColorAttachment => vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE,
                    Usage::DepthAttachment => vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                } | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST;
                let image = Image::new(ctx, &o.name, o.format, o.extent.unwrap_or(extent), 1, usage)?;
                map.insert(o.name.clone(), (image, o.clone()));
                output_order.push(o.name.clone());
            }
        }
        for d in &descs {
            for i in &d.inputs {
                if map.contains_key(i) {
                    continue;
                }
                let Some(desc) = zero_image(i) else {
                    bail!("frame graph: pass {} reads {i}, which no pass writes", d.name);
                };
                let usage = vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST;
                let image = Image::new(ctx, i, desc.format, desc.extent.unwrap_or(extent), 1, usage)?;
                map.insert(i.clone(), (image, desc));
            }
        }
        let timestamps = TimestampPool::new(ctx, (descs.len() as u32 * 2).max(2))?;
        Ok(Self {
            passes,
            descs,
            images: Images { map },
            output_order,
            sync: HashMap::new(),
            timestamps,
            initialised: false,
            extent,
        })
    }

    pub fn pass_names(&self) -> Vec<&str> {
        self.descs.iter().map(|d| d.name.as_str()).collect()
    }

    pub fn pass_count(&self) -> usize {
        self.passes.len()
    }

    /// Records every pass with barriers and timestamps into `rec`.
    pub fn record(&mut self, rec: &Recorder, scene: &SceneGpu, frame_index: u32) -> Result<()> {
        self.record_passes(rec, scene, frame_index, 0..self.passes.len())
    }

    /// Records the passes in `range` (in order) with their barriers and timestamps. A frame
    /// may be split over several submissions, in order, each a contiguous range: the first
    /// one (starting at 0) resets the timestamps.
    pub fn record_passes(
        &mut self,
        rec: &Recorder,
        scene: &SceneGpu,
        frame_index: u32,
        range: std::ops::Range<usize>,
    ) -> Result<()> {
        if !self.initialised {
            // Everything starts at zero: history images are read before their first write.
            for (image, desc) in self.images.map.values() {
                rec.init_general(image);
                if desc.usage != Usage::DepthAttachment {
                    rec.clear_image(image);
                }
            }
            rec.memory_barrier(
                (vk::PipelineStageFlags2::CLEAR, vk::AccessFlags2::TRANSFER_WRITE),
                (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE),
            );
            self.initialised = true;
        }
        if range.start == 0 {
            self.timestamps.reset(rec.cmd);
        }
        let ctx = PassContext { rec, images: &self.images, scene, extent: self.extent, frame_index };
        for (i, pass) in self.passes.iter_mut().enumerate().take(range.end).skip(range.start) {
            let desc = &self.descs[i];
            let reads: Vec<(&str, Access)> =
                desc.inputs.iter().map(|n| (n.as_str(), Access::read(desc.kind))).collect();
            let writes: Vec<(&str, Access)> =
                desc.outputs.iter().map(|o| (o.name.as_str(), Access::write(o.usage))).collect();
            sync::barrier(rec, &mut self.sync, &reads, &writes);
            rec.timestamp(&self.timestamps, 2 * i as u32);
            pass.record(&ctx)?;
            rec.timestamp(&self.timestamps, 2 * i as u32 + 1);
        }
        Ok(())
    }

    /// Makes `names` readable by a transfer (for capture and read-back) after the frame.
    pub fn prepare_readback(&mut self, rec: &Recorder, names: &[&str]) {
        let reads: Vec<(&str, Access)> = names.iter().map(|n| (*n, Access::transfer_read())).collect();
        sync::barrier(rec, &mut self.sync, &reads, &[]);
    }

    /// Per-pass GPU times of the last recorded frame (after its fence).
    pub fn pass_times(&self) -> Vec<PassTime> {
        let n = self.descs.len() as u32 * 2;
        match self.timestamps.read_ms(n) {
            Some(ts) => self
                .descs
                .iter()
                .enumerate()
                .map(|(i, d)| PassTime { pass: d.name.clone(), gpu_ms: ts[2 * i + 1] - ts[2 * i], wall_ms: None })
                .collect(),
            None => Vec::new(),
        }
    }

    pub fn image(&self, name: &str) -> Option<&Image> {
        self.images.map.get(name).map(|(i, _)| i)
    }

    /// The producing pass of an output.
    pub fn producer(&self, name: &str) -> Option<&str> {
        self.descs.iter().find(|d| d.outputs.iter().any(|o| o.name == name)).map(|d| d.name.as_str())
    }
}

/// The name of an image that is zero everywhere and written by no pass: a stand-in a pass may read
/// where the frame plan left out the pass that would have made the real input (for example the
/// soft-shadow statistics when every light is punctual). `small` makes it 1x1.
pub fn zero(format: vk::Format, small: bool) -> String {
    format!("zero.{}{}", format.as_raw(), if small { ".1x1" } else { "" })
}

/// The description of a `zero(...)` name, if it is one.
fn zero_image(name: &str) -> Option<OutputDesc> {
    let rest = name.strip_prefix("zero.")?;
    let (raw, small) = match rest.strip_suffix(".1x1") {
        Some(r) => (r, true),
        None => (rest, false),
    };
    let format = vk::Format::from_raw(raw.parse().ok()?);
    let desc =
        OutputDesc { name: name.to_string(), format, usage: Usage::Storage, preview: Preview::Scalar, extent: None };
    Some(if small { desc.with_extent(1, 1) } else { desc })
}

/// Records a full copy of `image` into a host-visible buffer (the image must have been made
/// transfer-readable with [`Graph::prepare_readback`]).
pub fn copy_to_host(ctx: &Arc<Context>, rec: &Recorder, image: &Image) -> Result<gpu::Buffer> {
    let buffer = gpu::upload::readback_buffer(ctx, image)?;
    rec.copy_image_to_buffer(image, &buffer);
    Ok(buffer)
}
