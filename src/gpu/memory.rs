//! Buffers and images with their memory (gpu-allocator). Each owns an `Arc<Context>` and frees
//! itself on drop, so passes never handle raw memory.

use super::Context;
use anyhow::{Context as _, Result, anyhow};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use std::sync::Arc;

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
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { ctx.device.create_buffer(&info, None) }.with_context(|| format!("create buffer {name}"))?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation =
            ctx.allocator.lock().map_err(|_| anyhow!("allocator lock poisoned"))?.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(anyhow!("out of memory allocating buffer {name} ({size} bytes): {e}"));
            }
        };
        unsafe { ctx.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }?;
        let address = if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
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
        let raw = unsafe { ctx.device.create_image(&info, None) }.with_context(|| format!("create image {name}"))?;
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation =
            ctx.allocator.lock().map_err(|_| anyhow!("allocator lock poisoned"))?.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(anyhow!("out of memory allocating image {name} ({}x{}): {e}", extent.width, extent.height));
            }
        };
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
        let view = unsafe { ctx.device.create_image_view(&view_info, None) };
        let view = match view {
            Ok(v) => v,
            Err(e) => {
                if let Ok(mut alloc) = ctx.allocator.lock() {
                    let _ = alloc.free(allocation);
                }
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
        unsafe { self.ctx.device.destroy_image_view(self.view, None) };
        if let Some(a) = self.allocation.take()
            && let Ok(mut alloc) = self.ctx.allocator.lock()
        {
            let _ = alloc.free(a);
        }
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
