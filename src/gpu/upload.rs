//! Moving data to and from the GPU: device-local buffers filled through a staging buffer,
//! textures with all their mip levels, and read-back of images for capture and tests.

use super::{Buffer, CommandPool, Context, Image, Recorder, image_barrier};
use anyhow::{Result, bail};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A device-local buffer holding `data` (uploaded through a staging buffer).
pub fn device_buffer(
    ctx: &Arc<Context>,
    pool: &CommandPool,
    name: &str,
    data: &[u8],
    usage: vk::BufferUsageFlags,
) -> Result<Buffer> {
    let dst =
        Buffer::new(ctx, name, data.len() as u64, usage | vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuOnly)?;
    if data.is_empty() {
        return Ok(dst);
    }
    let staging = Buffer::with_data(ctx, &format!("{name} (staging)"), data, vk::BufferUsageFlags::TRANSFER_SRC)?;
    pool.run(|cmd| {
        Recorder::new(ctx, cmd).copy_buffer(&staging, &dst, data.len() as u64);
        Ok(())
    })?;
    Ok(dst)
}

/// An RGBA8 texture from its mip chain (level 0 first), left in SHADER_READ_ONLY_OPTIMAL.
pub fn texture(ctx: &Arc<Context>, pool: &CommandPool, name: &str, levels: &[(u32, u32, Vec<u8>)]) -> Result<Image> {
    let Some(&(w, h, _)) = levels.first() else { bail!("texture {name}: no mip levels") };
    // Each level is the previous halved and holds exactly its texels: the copies below read
    // the staging buffer and write the image by these sizes.
    for (i, (lw, lh, d)) in levels.iter().enumerate() {
        let (ew, eh) = ((w >> i).max(1), (h >> i).max(1));
        if (*lw, *lh) != (ew, eh) || d.len() as u64 != *lw as u64 * *lh as u64 * 4 {
            bail!("texture {name}: mip {i} is {lw}x{lh} with {} bytes, expected {ew}x{eh} RGBA8", d.len());
        }
    }
    let image = Image::new(
        ctx,
        name,
        vk::Format::R8G8B8A8_UNORM,
        vk::Extent2D { width: w, height: h },
        levels.len() as u32,
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
    )?;
    let bytes: Vec<u8> = levels.iter().flat_map(|(_, _, d)| d.iter().copied()).collect();
    let staging = Buffer::with_data(ctx, &format!("{name} (staging)"), &bytes, vk::BufferUsageFlags::TRANSFER_SRC)?;
    let mut offset = 0u64;
    let regions: Vec<_> = levels
        .iter()
        .enumerate()
        .map(|(i, (w, h, d))| {
            let r = vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: i as u32,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D { width: *w, height: *h, depth: 1 });
            offset += d.len() as u64;
            r
        })
        .collect();
    pool.run(|cmd| {
        image_barrier(
            ctx,
            cmd,
            image.raw,
            image.full_range(),
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
        );
        // SAFETY: `cmd` is recording (CommandPool::run); the staging buffer and image are
        // live until `run` has waited for the copy. The regions were checked above to match
        // the image's mip chain and lie inside the staging buffer (laid out level after
        // level), and the image was just moved to TRANSFER_DST_OPTIMAL.
        unsafe {
            ctx.device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
        image_barrier(
            ctx,
            cmd,
            image.raw,
            image.full_range(),
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::SHADER_SAMPLED_READ),
        );
        Ok(())
    })?;
    Ok(image)
}

/// A host-visible buffer big enough to read `image` back.
pub fn readback_buffer(ctx: &Arc<Context>, image: &Image) -> Result<Buffer> {
    let size = image.extent.width as u64 * image.extent.height as u64 * super::texel_size(image.format) as u64;
    Buffer::new(ctx, "readback", size, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)
}
