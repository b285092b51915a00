//! The shape most passes share: a compute shader run once per pixel, reading named images and
//! writing named images, bound as set 1 in declaration order (inputs first, then outputs), with
//! the pass's `#[repr(C)]` push-constant struct.

use super::PassBuilder;
use crate::gpu::{Binding, BindingKind, Buffer, DescriptorSetLayout, Pipeline, PushResource, Sampler, SamplerDesc, vk};
use crate::graph::{OutputDesc, Pass, PassContext, PassDesc, PassKind, Resource, ShaderInterface};
use anyhow::Result;
use bytemuck::Pod;
use std::sync::Arc;

/// How a shader reads an input image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Read {
    /// imageLoad of exact texels.
    Texel,
    /// texture() with a bilinear, clamped sampler (reprojection); or texelFetch, for an input
    /// whose float format varies (a sampled image's binding names none).
    Filtered,
}

/// One image a pass reads, and the name its shader gives the binding.
#[derive(Clone, Debug)]
pub struct Input {
    resource: Resource,
    read: Read,
    binding: String,
}

impl Input {
    /// Read with imageLoad, bound as the name [`binding_name`] gives it.
    pub fn texel(resource: impl Into<Resource>) -> Self {
        Self::new(resource.into(), Read::Texel)
    }

    /// Read with a bilinear sampler, bound as the name [`binding_name`] gives it.
    pub fn filtered(resource: impl Into<Resource>) -> Self {
        Self::new(resource.into(), Read::Filtered)
    }

    fn new(resource: Resource, read: Read) -> Self {
        Self { resource, read, binding: binding_name(resource) }
    }

    /// Bound under the name of its role (`in_color`), for an input the caller chooses
    /// (tonemap's input is composite's or taa's colour).
    pub fn bound_as(mut self, glsl_name: &str) -> Self {
        self.binding = glsl_name.to_string();
        self
    }

    /// Reads `stand_in` (a zero image) in place of the planned resource, under the same binding.
    pub fn reading(mut self, stand_in: Resource) -> Self {
        self.resource = stand_in;
        self
    }
}

/// The GLSL name of the binding of `resource`: `g_<output>` for the G-buffer's, `prev_<output>`
/// for the previous frame's copy of one, `in_<output>` for any other pass's.
fn binding_name(resource: Resource) -> String {
    match resource {
        Resource::Output(o) if o.pass == super::gbuffer::NAME => format!("g_{}", o.name),
        Resource::Output(o) => format!("in_{}", o.name),
        Resource::History(o) => format!("prev_{}", o.name),
        Resource::Zero { .. } => "zero".into(),
    }
}

pub struct FullscreenPass {
    name: String,
    shader: String,
    pipeline: Pipeline,
    _set_layout: DescriptorSetLayout,
    sampler: Sampler,
    inputs: Vec<Input>,
    outputs: Vec<OutputDesc>,
    /// The bytes of the pass's push-constant struct.
    push_constants: Vec<u8>,
    /// Outputs zeroed before the dispatch (sums the shader accumulates with atomics).
    clears: Vec<Resource>,
    /// Storage buffers bound after the outputs, shared with other passes and kept across
    /// frames (the radiance cache's), with the GLSL names of their blocks.
    buffers: Vec<(&'static str, Arc<Buffer>)>,
    /// Workgroups to dispatch; None: one invocation per `pixels_per_invocation` of the frame.
    pub groups: Option<[u32; 3]>,
    /// Pixels (across, down) one invocation covers when `groups` is None: [1, 1] but for a
    /// shader that shades part of the frame (gi at a reduced rate).
    pub pixels_per_invocation: [u32; 2],
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
        inputs: Vec<Input>,
        outputs: Vec<OutputDesc>,
        push_constants: &impl Pod,
    ) -> Result<Self> {
        Self::with_buffers(b, name, shader_key, inputs, outputs, Vec::new(), push_constants)
    }

    /// A pass that also reads and writes `buffers` (GLSL block name, buffer), bound after its
    /// outputs.
    pub fn with_buffers(
        b: &PassBuilder,
        name: &str,
        shader_key: &str,
        inputs: Vec<Input>,
        outputs: Vec<OutputDesc>,
        buffers: Vec<(&'static str, Arc<Buffer>)>,
        push_constants: &impl Pod,
    ) -> Result<Self> {
        let push_constants = bytemuck::bytes_of(push_constants).to_vec();
        let bindings: Vec<Binding> = binding_kinds(&inputs, &outputs, buffers.len())
            .enumerate()
            .map(|(i, kind)| Binding { binding: i as u32, kind, count: 1 })
            .collect();
        let set_layout = DescriptorSetLayout::new(b.ctx, &bindings, true)?;
        let spirv = b.shaders.get(shader_key)?;
        let pipeline =
            Pipeline::compute(b.ctx, name, &spirv, &[&b.scene.set_layout, &set_layout], push_constants.len() as u32)?;
        let sampler = Sampler::new(b.ctx, SamplerDesc::LINEAR_CLAMP)?;
        Ok(Self {
            name: name.to_string(),
            shader: shader_key.to_string(),
            pipeline,
            _set_layout: set_layout,
            sampler,
            inputs,
            outputs,
            push_constants,
            clears: Vec::new(),
            buffers,
            groups: None,
            pixels_per_invocation: [1, 1],
        })
    }
}

impl FullscreenPass {
    /// Replaces the push constants from the next dispatch on (a pass recorded twice a frame in
    /// two modes).
    pub fn set_push_constants(&mut self, push_constants: &impl Pod) {
        self.push_constants = bytemuck::bytes_of(push_constants).to_vec();
    }

    /// Zero `output` (one of this pass's outputs) before every dispatch.
    pub fn clear_before_dispatch(&mut self, output: crate::graph::Output) {
        self.clears.push(output.into());
    }
}

/// The descriptor kind of each binding of set 1, in binding order.
fn binding_kinds<'a>(
    inputs: &'a [Input],
    outputs: &'a [OutputDesc],
    buffers: usize,
) -> impl Iterator<Item = BindingKind> + 'a {
    let read = inputs.iter().map(|i| match i.read {
        Read::Texel => BindingKind::StorageImage,
        Read::Filtered => BindingKind::SampledImage,
    });
    read.chain(outputs.iter().map(|_| BindingKind::StorageImage))
        .chain(std::iter::repeat_n(BindingKind::StorageBuffer, buffers))
}

impl Pass for FullscreenPass {
    fn desc(&self) -> PassDesc {
        PassDesc {
            name: self.name.clone(),
            kind: PassKind::Compute,
            inputs: self.inputs.iter().map(|i| i.resource).collect(),
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
                rec.clear_image(ctx.images.get(*c));
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
            .map(|i| match i.read {
                Read::Texel => PushResource::StorageImage(ctx.images.view(i.resource)),
                Read::Filtered => PushResource::SampledImage(ctx.images.view(i.resource), self.sampler.raw),
            })
            .collect();
        resources.extend(self.outputs.iter().map(|o| PushResource::StorageImage(ctx.images.view(o.name))));
        resources.extend(self.buffers.iter().map(|(_, b)| PushResource::StorageBuffer(b.raw)));
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
            None => {
                let [x, y] = self.pixels_per_invocation;
                rec.dispatch_2d(ctx.extent, (GROUP.0 * x, GROUP.1 * y))
            }
        }
        Ok(())
    }

    fn shader_interface(&self) -> Option<ShaderInterface> {
        let names = self
            .inputs
            .iter()
            .map(|i| i.binding.clone())
            .chain(self.outputs.iter().map(|o| match o.name {
                Resource::Output(out) => format!("out_{}", out.name),
                other => format!("out_{other}"),
            }))
            .chain(self.buffers.iter().map(|(name, _)| name.to_string()));
        Some(ShaderInterface {
            shader: self.shader.clone(),
            bindings: names.zip(binding_kinds(&self.inputs, &self.outputs, self.buffers.len())).collect(),
            push_constant_size: self.push_constants.len(),
        })
    }
}
