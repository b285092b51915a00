//! The shape most passes share: a compute shader run once per pixel, reading named images and
//! writing named images, bound as set 1 in declaration order (inputs first, then outputs).

use super::PassBuilder;
use crate::gpu::{Binding, BindingKind, Buffer, DescriptorSetLayout, Pipeline, PushResource, Sampler, SamplerDesc, vk};
use crate::graph::{OutputDesc, Pass, PassContext, PassDesc, PassKind};
use anyhow::Result;
use std::sync::Arc;

/// How a shader reads an input image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Read {
    /// imageLoad of exact texels.
    Texel,
    /// texture() with a bilinear, clamped sampler (reprojection).
    Filtered,
}

pub struct FullscreenPass {
    name: String,
    pipeline: Pipeline,
    _set_layout: DescriptorSetLayout,
    sampler: Sampler,
    inputs: Vec<(String, Read)>,
    outputs: Vec<OutputDesc>,
    /// Push constants, rewritten by the owner before a frame when they change.
    pub push_constants: Vec<u8>,
    /// Outputs zeroed before the dispatch (sums the shader accumulates with atomics).
    clears: Vec<String>,
    /// Storage buffers bound after the outputs, shared with other passes and kept across
    /// frames (the radiance cache's).
    buffers: Vec<Arc<Buffer>>,
    /// Workgroups to dispatch; None: one invocation per pixel of the frame.
    pub groups: Option<[u32; 3]>,
}

/// Compute-shader storage access, on both sides of the barrier before a pass that shares
/// buffers with others.
pub const SHARED_BUFFER_ACCESS: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::COMPUTE_SHADER,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw() | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
    ),
);

/// Workgroup size of every full-screen compute shader (`local_size_x/y`).
pub const GROUP: (u32, u32) = (8, 8);

impl FullscreenPass {
    pub fn new(
        b: &PassBuilder,
        name: &str,
        shader_key: &str,
        inputs: Vec<(String, Read)>,
        outputs: Vec<OutputDesc>,
        push_constants: Vec<u8>,
    ) -> Result<Self> {
        Self::with_buffers(b, name, shader_key, inputs, outputs, Vec::new(), push_constants)
    }

    /// A pass that also reads and writes `buffers`, bound after its outputs.
    pub fn with_buffers(
        b: &PassBuilder,
        name: &str,
        shader_key: &str,
        inputs: Vec<(String, Read)>,
        outputs: Vec<OutputDesc>,
        buffers: Vec<Arc<Buffer>>,
        push_constants: Vec<u8>,
    ) -> Result<Self> {
        let mut bindings = Vec::new();
        for (i, (_, read)) in inputs.iter().enumerate() {
            let kind = if *read == Read::Filtered { BindingKind::SampledImage } else { BindingKind::StorageImage };
            bindings.push(Binding { binding: i as u32, kind, count: 1 });
        }
        for i in 0..outputs.len() {
            bindings.push(Binding { binding: (inputs.len() + i) as u32, kind: BindingKind::StorageImage, count: 1 });
        }
        for i in 0..buffers.len() {
            let binding = (inputs.len() + outputs.len() + i) as u32;
            bindings.push(Binding { binding, kind: BindingKind::StorageBuffer, count: 1 });
        }
        let set_layout = DescriptorSetLayout::new(b.ctx, &bindings, true)?;
        let spirv = b.shaders.get(shader_key)?;
        let pipeline =
            Pipeline::compute(b.ctx, name, &spirv, &[&b.scene.set_layout, &set_layout], push_constants.len() as u32)?;
        let sampler = Sampler::new(b.ctx, SamplerDesc::LINEAR_CLAMP)?;
        Ok(Self {
            name: name.to_string(),
            pipeline,
            _set_layout: set_layout,
            sampler,
            inputs,
            outputs,
            push_constants,
            clears: Vec::new(),
            buffers,
            groups: None,
        })
    }
}

impl FullscreenPass {
    /// Zero `output` (one of this pass's outputs) before every dispatch.
    pub fn clear_before_dispatch(&mut self, output: &str) {
        self.clears.push(output.to_string());
    }
}

impl Pass for FullscreenPass {
    fn desc(&self) -> PassDesc {
        PassDesc {
            name: self.name.clone(),
            kind: PassKind::Compute,
            inputs: self.inputs.iter().map(|(n, _)| n.clone()).collect(),
            outputs: self.outputs.clone(),
        }
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        let rec = ctx.rec;
        if !self.clears.is_empty() {
            // The graph's barrier covered compute access; the clear is a transfer, so it gets
            // barriers of its own on both sides.
            rec.memory_barrier(
                (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE),
                (vk::PipelineStageFlags2::CLEAR, vk::AccessFlags2::TRANSFER_WRITE),
            );
            for c in &self.clears {
                rec.clear_image(ctx.images.get(c));
            }
            rec.memory_barrier(
                (vk::PipelineStageFlags2::CLEAR, vk::AccessFlags2::TRANSFER_WRITE),
                (
                    vk::PipelineStageFlags2::COMPUTE_SHADER,
                    vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
                ),
            );
        }
        let mut resources: Vec<PushResource> = self
            .inputs
            .iter()
            .map(|(n, read)| match read {
                Read::Texel => PushResource::StorageImage(ctx.images.view(n)),
                Read::Filtered => PushResource::SampledImage(ctx.images.view(n), self.sampler.raw),
            })
            .collect();
        resources.extend(self.outputs.iter().map(|o| PushResource::StorageImage(ctx.images.view(&o.name))));
        resources.extend(self.buffers.iter().map(|b| PushResource::StorageBuffer(b.raw)));
        if !self.buffers.is_empty() {
            // The graph orders images only: the shared buffers get a barrier of their own
            // against whatever pass (this frame or the last) wrote or read them before.
            rec.memory_barrier(SHARED_BUFFER_ACCESS, SHARED_BUFFER_ACCESS);
        }
        rec.bind_pipeline(&self.pipeline);
        rec.bind_scene_set(&self.pipeline, ctx.scene.set.raw);
        rec.push_set(&self.pipeline, &resources);
        if !self.push_constants.is_empty() {
            rec.push_constants(&self.pipeline, &self.push_constants);
        }
        match self.groups {
            Some([x, y, z]) => rec.dispatch(x, y, z),
            None => rec.dispatch_2d(ctx.extent, GROUP),
        }
        Ok(())
    }
}
