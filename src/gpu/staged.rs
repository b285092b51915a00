//! Buffers the shaders read from device-local memory and the host rewrites between frames (the
//! instances' transforms, the lights, the light table, the emitters): written into a
//! host-visible staging twin, and copied in by the next frame's own commands. Read in place from
//! host-visible memory, every hit and light sample would cross the bus on a discrete GPU
//! without resizable BAR.

use super::{Buffer, Context, Recorder, vk};
use anyhow::Result;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct StagedBuffer {
    device: Buffer,
    staging: Buffer,
    /// The byte range written since the last copy.
    pending: Option<(u64, u64)>,
}

impl StagedBuffer {
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64, usage: vk::BufferUsageFlags) -> Result<Self> {
        let device = Buffer::new(ctx, name, size, usage | vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuOnly)?;
        let staging = Buffer::new(
            ctx,
            &format!("{name} (staging)"),
            size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        Ok(Self { device, staging, pending: None })
    }

    /// The device-local buffer, for descriptors.
    pub fn buffer(&self) -> &Buffer {
        &self.device
    }

    /// Writes into the staging buffer; the next [`record_copies`] copies it in.
    /// Nothing is copied for an empty write (a scene without lights): a zero-sized copy is
    /// invalid.
    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<()> {
        if data.is_empty() {
            return Ok(());
        }
        self.staging.write(offset, data)?;
        let (start, end) = (offset as u64, (offset + data.len()) as u64);
        self.pending = Some(self.pending.map_or((start, end), |(s, e)| (s.min(start), e.max(end))));
        Ok(())
    }
}

/// Records the copies of what was written into `buffers` since their last copy, between barriers
/// against every earlier and later use (shaders of any stage read them, the G-buffer's vertex
/// shader the instances; light_grid_update rewrites the grid's entries). Records nothing when
/// nothing was written.
pub fn record_copies(rec: &Recorder, buffers: &mut [&mut StagedBuffer]) {
    if buffers.iter().all(|b| b.pending.is_none()) {
        return;
    }
    let shaders =
        (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE);
    let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
    rec.memory_barrier(shaders, transfer);
    for b in buffers.iter_mut() {
        if let Some((start, end)) = b.pending.take() {
            rec.copy_buffer_regions(&b.staging, &b.device, &[(start, start, end - start)]);
        }
    }
    rec.memory_barrier(transfer, shaders);
}
