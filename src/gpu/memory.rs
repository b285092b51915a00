//! Buffers and images with their memory (gpu-allocator). Each owns an `Arc<Context>` and frees
//! itself on drop, so passes never handle raw memory.

use super::Context;
use anyhow::{Context as _, Result, anyhow};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::{AllocationError, MemoryLocation};
use std::sync::Arc;

/// An allocation the device had no memory for. The command line recognises it (anywhere in an
/// error's chain) and suggests a smaller --size.
#[derive(Debug, thiserror::Error)]
#[error("out of memory allocating {what}")]
pub struct OutOfDeviceMemory {
    /// The buffer or image, with its size.
    pub what: String,
    source: AllocationError,
}

/// What gpu-allocator holds at a moment (the soak test and bench watch it for growth).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MemoryUsage {
    /// Bytes of live sub-allocations (buffers and images).
    pub allocated_bytes: u64,
    /// Bytes of device memory blocks, used or not.
    pub capacity_bytes: u64,
    pub allocations: usize,
    pub blocks: usize,
}

impl Context {
    pub fn memory_usage(&self) -> Result<MemoryUsage> {
        let report = self.allocator.lock().map_err(|_| anyhow!("allocator lock poisoned"))?.generate_report();
        Ok(MemoryUsage {
            allocated_bytes: report.total_allocated_bytes,
            capacity_bytes: report.total_capacity_bytes,
            allocations: report.allocations.len(),
            blocks: report.blocks.len(),
        })
    }
}

/// Allocates memory for `what`. Under a memory cap (`Context::memory_limit`) a request that
/// would take the live allocations past it fails with gpu-allocator's own out-of-memory error,
/// so a capped run takes the same path as a full device.
fn allocate(ctx: &Context, what: impl FnOnce() -> String, desc: &AllocationCreateDesc) -> Result<Allocation> {
    let mut allocator = ctx.allocator.lock().map_err(|_| anyhow!("allocator lock poisoned"))?;
    let over_cap = ctx
        .memory_limit
        .is_some_and(|limit| allocator.generate_report().total_allocated_bytes + desc.requirements.size > limit);
    let result = if over_cap { Err(AllocationError::OutOfMemory) } else { allocator.allocate(desc) };
    result.map_err(|source| match source {
        AllocationError::OutOfMemory => OutOfDeviceMemory { what: what(), source }.into(),
        other => anyhow!("cannot allocate memory for {}: {other}", what()),
    })
}

pub struct Buffer {
    ctx: Arc<Context>,
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
    /// Device address when the buffer was made with SHADER_DEVICE_ADDRESS usage.
    pub address: vk::DeviceAddress,
}

impl Buffer {
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        // create_device enables bufferDeviceAddress for the ray-query backend only.
        if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) && !ctx.caps.supports_ray_query() {
            return Err(anyhow!("buffer {name}: device addresses are enabled only where ray query is"));
        }
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: creation on a live device from an info on this stack frame (size >= 4).
        let raw = unsafe { ctx.device.create_buffer(&info, None) }.with_context(|| format!("create buffer {name}"))?;
        // SAFETY: `raw` was just made on this device.
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        let allocation = match allocate(ctx, || format!("buffer {name} ({size} bytes)"), &desc) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: made above, never bound or used.
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: gpu-allocator returned memory and an offset that satisfy `requirements`
        // (size, alignment, memory type) for this buffer, which has no memory bound yet.
        unsafe { ctx.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }?;
        let address = if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
            // SAFETY: the buffer is bound to memory and was made with SHADER_DEVICE_ADDRESS,
            // allowed above only where the context enabled bufferDeviceAddress (and the
            // allocator then allocates with the device-address flag).
            unsafe { ctx.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(raw)) }
        } else {
            0
        };
        ctx.set_name(raw, name);
        Ok(Self { ctx: ctx.clone(), raw, size, allocation: Some(allocation), address })
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data(ctx: &Arc<Context>, name: &str, data: &[u8], usage: vk::BufferUsageFlags) -> Result<Self> {
        let mut b = Self::new(ctx, name, data.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        b.write(0, data)?;
        Ok(b)
    }

    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }

    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| anyhow!("buffer is not host-visible"))?;
        let end = offset + data.len();
        if end > slice.len() {
            return Err(anyhow!("buffer write out of range: {end} > {}", slice.len()));
        }
        slice[offset..end].copy_from_slice(data);
        Ok(())
    }

    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo { buffer: self.raw, offset: 0, range: vk::WHOLE_SIZE }
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take()
            && let Ok(mut alloc) = self.ctx.allocator.lock()
        {
            let _ = alloc.free(a);
        }
        // SAFETY: made by `new`, destroyed once. Buffers are dropped after the frames using
        // them were waited for (one frame in flight; the presenter keeps its staging buffers
        // until the next frame), so no pending command buffer reads it.
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}

/// A 2D image with one view. Storage images live in GENERAL layout for their whole life (the
/// frame graph only adds memory dependencies), which keeps barriers simple and correct.
pub struct Image {
    ctx: Arc<Context>,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub mip_levels: u32,
    pub aspect: vk::ImageAspectFlags,
    allocation: Option<Allocation>,
}

impl Image {
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        mip_levels: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(mip_levels)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: creation on a live device from an info on this stack frame.
        let raw = unsafe { ctx.device.create_image(&info, None) }.with_context(|| format!("create image {name}"))?;
        // SAFETY: `raw` was just made on this device.
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        let what = || {
            let mib = requirements.size as f64 / (1 << 20) as f64;
            format!("image {name} ({}x{} {format:?}, {mib:.1} MiB)", extent.width, extent.height)
        };
        let allocation = match allocate(ctx, what, &desc) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: made above, never bound or used.
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: as for buffers: memory satisfying this image's requirements, none bound yet.
        unsafe { ctx.device.bind_image_memory(raw, allocation.memory(), allocation.offset()) }?;
        let aspect = aspect_of(format);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: aspect,
                base_mip_level: 0,
                level_count: mip_levels,
                base_array_layer: 0,
                layer_count: 1,
            });
        // SAFETY: a view of the whole image (its mip levels, one layer, its format and aspect),
        // which is bound to memory.
        let view = unsafe { ctx.device.create_image_view(&view_info, None) };
        let view = match view {
            Ok(v) => v,
            Err(e) => {
                if let Ok(mut alloc) = ctx.allocator.lock() {
                    let _ = alloc.free(allocation);
                }
                // SAFETY: made above, never used by any command.
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(anyhow!("create image view {name}: {e}"));
            }
        };
        ctx.set_name(raw, name);
        ctx.set_name(view, name);
        Ok(Self { ctx: ctx.clone(), raw, view, format, extent, mip_levels, aspect, allocation: Some(allocation) })
    }

    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: 0,
            level_count: self.mip_levels,
            base_array_layer: 0,
            layer_count: 1,
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: made by `new`, destroyed once, view before image; as for buffers, images are
        // dropped only after the frames using them were waited for.
        unsafe { self.ctx.device.destroy_image_view(self.view, None) };
        if let Some(a) = self.allocation.take()
            && let Ok(mut alloc) = self.ctx.allocator.lock()
        {
            let _ = alloc.free(a);
        }
        // SAFETY: as above; its memory was freed just before, which Vulkan allows while the
        // image exists as long as the image is not used again.
        unsafe { self.ctx.device.destroy_image(self.raw, None) };
    }
}

pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// Bytes per texel of the formats the renderer uses.
pub fn texel_size(format: vk::Format) -> u32 {
    match format {
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::R32_SFLOAT | vk::Format::R32_UINT => 4,
        vk::Format::R16G16_SFLOAT | vk::Format::D32_SFLOAT => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT | vk::Format::R32G32_UINT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        vk::Format::R8_UNORM => 1,
        vk::Format::R16_SFLOAT | vk::Format::R8G8_UNORM => 2,
        _ => 16,
    }
}
