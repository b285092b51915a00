//! The frame graph. Passes declare the named images they read and the named images they
//! write; the graph creates the images, orders nothing (passes run in the order given, and
//! the graph checks that every input has a producer), places the barriers between passes from
//! those declarations, times each pass with GPU timestamps, and hands any named output to the
//! capture. A new pass gets barriers, timing and dumps by declaring its outputs.

mod resource;
mod sync;

pub use resource::{Instance, Output, Resource};

use crate::gpu::{self, Context, Image, Recorder, TimestampPool, vk};
use crate::world::SceneGpu;
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
    /// Packed RGBA8 colours, one per channel (`shadows.tint`): the first channel's shown, 0
    /// (no tint) as white.
    Tint,
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
    /// The image's typed name (shown as `pass.output` in capture files and the viewer).
    pub name: Resource,
    pub format: vk::Format,
    pub usage: Usage,
    pub preview: Preview,
    /// Size when it is not the frame's (small statistics images).
    pub extent: Option<vk::Extent2D>,
}

impl OutputDesc {
    pub fn storage(output: Output, format: vk::Format, preview: Preview) -> Self {
        Self { name: output.into(), format, usage: Usage::Storage, preview, extent: None }
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
    /// Keeps images for the next frame (passes::history): for each output `history.x` it reads
    /// `x`, and records nothing. The graph swaps the two images at the start of the next frame
    /// instead of copying, so `history.x` is then this frame's `x`, and `x` the image its
    /// writer overwrites.
    History,
}

/// What a pass declares about itself.
#[derive(Clone, Debug)]
pub struct PassDesc {
    /// Unique in the frame; several instances of one pass type carry the signal they work on
    /// (`svgf_atrous_diffuse_0`).
    pub name: String,
    pub kind: PassKind,
    /// Images this pass reads (outputs of passes before it, or of itself last frame).
    pub inputs: Vec<Resource>,
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
    /// The shader module and the set-1 bindings and push constants this pass declares for it,
    /// for passes that run one shader (checked against the SPIR-V by tests/shader_interface.rs).
    fn shader_interface(&self) -> Option<ShaderInterface> {
        None
    }
}

/// What a pass's Rust code says its shader declares.
#[derive(Clone, Debug)]
pub struct ShaderInterface {
    /// The shader module's key (`taa.comp`, `shadows.comp:compute`).
    pub shader: String,
    /// Set 1, in binding order: the GLSL name each binding must have, and its kind.
    pub bindings: Vec<(String, gpu::BindingKind)>,
    /// Bytes of the push-constant block (`size_of` the pass's `#[repr(C)]` struct).
    pub push_constant_size: usize,
}

/// The images of a frame, by name.
pub struct Images {
    map: HashMap<Resource, (Image, OutputDesc)>,
}

impl Images {
    pub fn get(&self, name: impl Into<Resource>) -> &Image {
        &self.map[&name.into()].0
    }

    pub fn view(&self, name: impl Into<Resource>) -> vk::ImageView {
        self.get(name).view
    }

    pub fn desc(&self, name: impl Into<Resource>) -> Option<&OutputDesc> {
        self.map.get(&name.into()).map(|(_, d)| d)
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
    /// Outputs in declaration order (the capture writes them in this order).
    pub output_order: Vec<Resource>,
    sync: HashMap<Resource, SyncState>,
    /// The images kept for the next frame, (x, history.x), swapped at the start of each frame
    /// after the first.
    swaps: Vec<(Resource, Resource)>,
    timestamps: TimestampPool,
    initialised: bool,
    pub extent: vk::Extent2D,
}

impl Graph {
    pub fn new(ctx: &Arc<Context>, passes: Vec<Box<dyn Pass>>, extent: vk::Extent2D) -> Result<Self> {
        let descs: Vec<PassDesc> = passes.iter().map(|p| p.desc()).collect();
        let mut map: HashMap<Resource, (Image, OutputDesc)> = HashMap::new();
        let mut output_order = Vec::new();
        for d in &descs {
            for o in &d.outputs {
                if map.contains_key(&o.name) {
                    bail!("frame graph: output {} is written by two passes", o.name);
                }
                // A kept image takes the place of its source every other frame (swap_histories):
                // it is made like it.
                let like = match o.name {
                    Resource::History(source) if d.kind == PassKind::History => match map.get(&source.into()) {
                        Some((_, s)) if (s.format, s.extent) == (o.format, o.extent) => s.usage,
                        _ => bail!(
                            "frame graph: {source} is kept as {}, which no earlier pass writes in its format and size",
                            o.name
                        ),
                    },
                    _ => o.usage,
                };
                let usage = match like {
                    Usage::Storage | Usage::Transfer => vk::ImageUsageFlags::STORAGE,
                    Usage::ColorAttachment => vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE,
                    Usage::DepthAttachment => vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                } | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST;
                let image = Image::new(ctx, &o.name.to_string(), o.format, o.extent.unwrap_or(extent), 1, usage)?;
                map.insert(o.name, (image, o.clone()));
                output_order.push(o.name);
            }
        }
        for d in &descs {
            for i in &d.inputs {
                if map.contains_key(i) {
                    continue;
                }
                let Some(desc) = zero_image(*i) else {
                    bail!("frame graph: pass {} reads {i}, which no pass writes", d.name);
                };
                let usage = vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST;
                let image = Image::new(ctx, &i.to_string(), desc.format, desc.extent.unwrap_or(extent), 1, usage)?;
                map.insert(*i, (image, desc));
            }
        }
        let swaps = history_swaps(&descs)?;
        let timestamps = TimestampPool::new(ctx, (descs.len() as u32 * 2).max(2))?;
        Ok(Self {
            passes,
            descs,
            images: Images { map },
            output_order,
            sync: HashMap::new(),
            swaps,
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
        if range.start == 0 && self.initialised {
            self.swap_histories();
        }
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
            // A history pass touches nothing on the GPU (the swap is bookkeeping).
            if desc.kind != PassKind::History {
                let reads: Vec<(Resource, Access)> =
                    desc.inputs.iter().map(|n| (*n, Access::read(desc.kind))).collect();
                let writes: Vec<(Resource, Access)> =
                    desc.outputs.iter().map(|o| (o.name, Access::write(o.usage))).collect();
                sync::barrier(rec, &mut self.sync, &reads, &writes);
            }
            rec.timestamp(&self.timestamps, 2 * i as u32);
            pass.record(&ctx)?;
            rec.timestamp(&self.timestamps, 2 * i as u32 + 1);
        }
        Ok(())
    }

    /// Last frame's images become the history, and the history's images the ones this frame
    /// writes; each image's barrier state goes with it.
    fn swap_histories(&mut self) {
        for (x, history) in &self.swaps {
            let [a, b] = self.images.map.get_disjoint_mut([x, history]);
            let (Some(a), Some(b)) = (a, b) else { continue };
            std::mem::swap(&mut a.0, &mut b.0);
            let (sx, sh) = (self.sync.remove(x).unwrap_or_default(), self.sync.remove(history).unwrap_or_default());
            self.sync.insert(*x, sh);
            self.sync.insert(*history, sx);
        }
    }

    /// Makes `names` readable by a transfer (for capture and read-back) after the frame.
    pub fn prepare_readback(&mut self, rec: &Recorder, names: &[Resource]) {
        let reads: Vec<(Resource, Access)> = names.iter().map(|n| (*n, Access::transfer_read())).collect();
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

    pub fn image(&self, name: impl Into<Resource>) -> Option<&Image> {
        self.images.map.get(&name.into()).map(|(i, _)| i)
    }

    /// The producing pass of an output.
    pub fn producer(&self, name: Resource) -> Option<&str> {
        self.descs.iter().find(|d| d.outputs.iter().any(|o| o.name == name)).map(|d| d.name.as_str())
    }

    /// The output a person named (`--view taa.color`, a viewer script), or an error listing
    /// every output of this frame.
    pub fn resource_named(&self, name: &str) -> Result<Resource> {
        if let Some(r) = self.output_order.iter().find(|r| r.to_string() == name) {
            return Ok(*r);
        }
        let all: Vec<String> = self.output_order.iter().map(Resource::to_string).collect();
        bail!("no pass output named {name}; the frame has: {}", all.join(", "))
    }

    /// The shader interface of every pass that declares one (see `tests/shader_interface.rs`).
    pub fn shader_interfaces(&self) -> Vec<(String, ShaderInterface)> {
        self.passes.iter().zip(&self.descs).filter_map(|(p, d)| Some((d.name.clone(), p.shader_interface()?))).collect()
    }
}

/// The (x, history.x) pairs that history passes keep. Swapping images is a copy only where
/// every pass that reads `x` runs after the one that writes it (one that read it before would
/// see the frame before last), so the graph checks that.
fn history_swaps(descs: &[PassDesc]) -> Result<Vec<(Resource, Resource)>> {
    let mut swaps = Vec::new();
    for d in descs.iter().filter(|d| d.kind == PassKind::History) {
        for o in &d.outputs {
            let Resource::History(source) = o.name else {
                bail!("frame graph: history pass {} writes {}, not a history image", d.name, o.name);
            };
            let x: Resource = source.into();
            if !d.inputs.contains(&x) {
                bail!("frame graph: history pass {} keeps {x} without reading it", d.name);
            }
            let writer = descs.iter().position(|w| w.outputs.iter().any(|wo| wo.name == x));
            let first_reader = descs.iter().position(|r| r.kind != PassKind::History && r.inputs.contains(&x));
            if let (Some(w), Some(r)) = (writer, first_reader)
                && r < w
            {
                bail!(
                    "frame graph: {} reads {x} before {} writes it, so it cannot be kept by a swap",
                    descs[r].name,
                    descs[w].name
                );
            }
            swaps.push((x, o.name));
        }
    }
    Ok(swaps)
}

/// An image that is zero everywhere and written by no pass (see [`Resource::Zero`]).
pub fn zero(format: vk::Format, small: bool) -> Resource {
    Resource::Zero { format, small }
}

/// The description of a zero image, if `name` is one.
fn zero_image(name: Resource) -> Option<OutputDesc> {
    let Resource::Zero { format, small } = name else { return None };
    let desc = OutputDesc { name, format, usage: Usage::Storage, preview: Preview::Scalar, extent: None };
    Some(if small { desc.with_extent(1, 1) } else { desc })
}

/// Records a full copy of `image` into a host-visible buffer (the image must have been made
/// transfer-readable with [`Graph::prepare_readback`]).
pub fn copy_to_host(ctx: &Arc<Context>, rec: &Recorder, image: &Image) -> Result<gpu::Buffer> {
    let buffer = gpu::upload::readback_buffer(ctx, image)?;
    rec.copy_image_to_buffer(image, &buffer);
    Ok(buffer)
}

#[cfg(test)]
mod tests {
    use super::*;

    const X: Output = Output::new("a", "x");

    fn pass(name: &str, kind: PassKind, inputs: Vec<Resource>, outputs: Vec<OutputDesc>) -> PassDesc {
        PassDesc { name: name.into(), kind, inputs, outputs }
    }

    fn keep_x() -> PassDesc {
        let mut kept = OutputDesc::storage(X, vk::Format::R32_SFLOAT, Preview::Scalar);
        kept.name = Resource::History(X);
        kept.usage = Usage::Transfer;
        pass("history", PassKind::History, vec![X.into()], vec![kept])
    }

    #[test]
    fn a_kept_image_is_swapped_only_when_read_after_its_writer() {
        let write_x = pass(
            "a",
            PassKind::Compute,
            Vec::new(),
            vec![OutputDesc::storage(X, vk::Format::R32_SFLOAT, Preview::Scalar)],
        );
        let read_both = pass("b", PassKind::Compute, vec![X.into(), Resource::History(X)], Vec::new());
        let swaps = history_swaps(&[write_x.clone(), read_both.clone(), keep_x()]).unwrap();
        assert_eq!(swaps, vec![(X.into(), Resource::History(X))]);
        // Read before it is written, `x` would hold the frame before last after a swap.
        let err = history_swaps(&[read_both, write_x, keep_x()]).unwrap_err();
        assert!(err.to_string().contains("b reads a.x before a writes it"), "{err}");
    }
}
