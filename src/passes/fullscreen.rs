//! The shape most passes share: a compute shader run once per pixel, reading named images and
//! writing named images, bound as set 1 in declaration order (inputs first, then outputs).

use super::PassBuilder;
use crate::gpu::{Binding, BindingKind, DescriptorSetLayout, Pipeline, PushResource, Sampler, SamplerDesc, vk};
use crate::graph::{OutputDesc, Pass, PassContext, PassDesc, PassKind};
use anyhow::Result;

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
}

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
        let mut bindings = Vec::new();
        for (i, (_, read)) in inputs.iter().enumerate() {
            let kind = if *read == Read::Filtered { BindingKind::SampledImage } else { BindingKind::StorageImage };
            bindings.push(Binding { binding: i as u32, kind, count: 1 });
        }
        for i in 0..outputs.len() {
            bindings.push(Binding { binding: (inputs.len() + i) as u32, kind: BindingKind::StorageImage, count: 1 });
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
        rec.bind_pipeline(&self.pipeline);
        rec.bind_scene_set(&self.pipeline, ctx.scene.set.raw);
        rec.push_set(&self.pipeline, &resources);
        if !self.push_constants.is_empty() {
            rec.push_constants(&self.pipeline, &self.push_constants);
        }
        rec.dispatch_2d(ctx.extent, GROUP);
        Ok(())
    }
}
