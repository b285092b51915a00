//! Descriptor set layouts and sets. Two kinds are used: the scene set (set 0, allocated once per
//! scene upload: geometry, materials, textures, the ray-tracing structures) and a per-pass push
//! descriptor set (set 1: the images and buffers a pass reads and writes, pushed at record time).

use super::{Buffer, Context};
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    UniformBuffer,
    StorageBuffer,
    StorageImage,
    SampledImage,
    AccelerationStructure,
}

impl BindingKind {
    pub fn vk(self) -> vk::DescriptorType {
        match self {
            BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
            BindingKind::SampledImage => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            BindingKind::AccelerationStructure => vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub binding: u32,
    pub kind: BindingKind,
    pub count: u32,
}

pub struct DescriptorSetLayout {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorSetLayout,
    pub bindings: Vec<Binding>,
}

impl DescriptorSetLayout {
    pub fn new(ctx: &Arc<Context>, bindings: &[Binding], push: bool) -> Result<Self> {
        let stages = vk::ShaderStageFlags::COMPUTE | vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let vk_bindings: Vec<_> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.kind.vk())
                    .descriptor_count(b.count)
                    .stage_flags(stages)
            })
            .collect();
        let flags = if push { vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR } else { Default::default() };
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&vk_bindings).flags(flags);
        // SAFETY: creation on a live device; `info` points into `vk_bindings`, alive across the
        // call. Push-descriptor layouts need VK_KHR_push_descriptor, which the context requires.
        let raw = unsafe { ctx.device.create_descriptor_set_layout(&info, None) }.context("create set layout")?;
        Ok(Self { ctx: ctx.clone(), raw, bindings: bindings.to_vec() })
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        // SAFETY: made by `new`, destroyed once. Pipeline layouts made from it keep working
        // (the spec allows destroying a set layout once layouts and sets are made from it).
        unsafe { self.ctx.device.destroy_descriptor_set_layout(self.raw, None) };
    }
}

/// One descriptor set with its own pool (the scene set is allocated once; a private pool keeps
/// its lifetime obvious).
pub struct DescriptorSet {
    ctx: Arc<Context>,
    pool: vk::DescriptorPool,
    pub raw: vk::DescriptorSet,
}

impl DescriptorSet {
    pub fn new(ctx: &Arc<Context>, layout: &DescriptorSetLayout) -> Result<Self> {
        let sizes: Vec<_> = layout
            .bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize { ty: b.kind.vk(), descriptor_count: b.count.max(1) })
            .collect();
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes);
        // SAFETY: creation on a live device from infos on this stack frame.
        let pool = unsafe { ctx.device.create_descriptor_pool(&info, None) }.context("create descriptor pool")?;
        let layouts = [layout.raw];
        let alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        // SAFETY: one set from a pool made for exactly this layout's bindings (max_sets 1);
        // the layout is borrowed, so live. The pool is used by this object only.
        match unsafe { ctx.device.allocate_descriptor_sets(&alloc) } {
            Ok(sets) => Ok(Self { ctx: ctx.clone(), pool, raw: sets[0] }),
            Err(e) => {
                // SAFETY: made above, nothing allocated from it.
                unsafe { ctx.device.destroy_descriptor_pool(pool, None) };
                Err(e).context("allocate descriptor set")
            }
        }
    }

    pub fn write_buffer(&self, binding: u32, kind: BindingKind, buffer: &Buffer) {
        let infos = [buffer.descriptor()];
        let w = [vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(kind.vk())
            .buffer_info(&infos)];
        // SAFETY: the set is live (owned) and the buffer borrowed. Sets are written while the
        // scene is uploaded, before any command buffer uses them, so none is pending.
        unsafe { self.ctx.device.update_descriptor_sets(&w, &[]) };
    }

    pub fn write_sampled_images(&self, binding: u32, images: &[(vk::ImageView, vk::Sampler)]) {
        if images.is_empty() {
            return;
        }
        let infos: Vec<_> = images
            .iter()
            .map(|(view, sampler)| vk::DescriptorImageInfo {
                sampler: *sampler,
                image_view: *view,
                image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            })
            .collect();
        let w = [vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&infos)];
        // SAFETY: as write_buffer; the views and samplers are the scene's textures, which live
        // as long as the scene upload that owns this set, and are in SHADER_READ_ONLY_OPTIMAL
        // (upload::texture leaves them so).
        unsafe { self.ctx.device.update_descriptor_sets(&w, &[]) };
    }

    pub fn write_acceleration_structure(&self, binding: u32, accel: vk::AccelerationStructureKHR) {
        let handles = [accel];
        let mut as_info = vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&handles);
        // The count is not implied by any info array ash knows about: it must be set by hand.
        let mut w = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut as_info);
        w.descriptor_count = 1;
        // SAFETY: as write_buffer; `as_info` (chained) and `handles` live across the call, the
        // count matches the one handle, and the handle is the scene's TLAS, owned alongside.
        unsafe { self.ctx.device.update_descriptor_sets(&[w], &[]) };
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // SAFETY: made by `new`, destroyed once (its set with it); the scene is dropped only
        // after its last frame has been waited for, so no command buffer still uses the set.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}

/// A resource pushed into a pass's set 1 at record time.
#[derive(Clone, Copy, Debug)]
pub enum PushResource {
    StorageImage(vk::ImageView),
    SampledImage(vk::ImageView, vk::Sampler),
    StorageBuffer(vk::Buffer),
    UniformBuffer(vk::Buffer),
}
