//! Command recording and submission. The renderer records one command buffer per frame and
//! waits on a fence; uploads use one-shot command buffers the same way.

use super::Context;
use anyhow::{Context as _, Result};
use ash::vk;
use std::cell::Cell;
use std::marker::PhantomData;
use std::sync::Arc;

pub struct CommandPool {
    ctx: Arc<Context>,
    pool: vk::CommandPool,
    fence: vk::Fence,
    /// Not Sync: Vulkan requires the pool and fence to be used from one thread at a time,
    /// and `run` takes `&self`.
    _one_thread: PhantomData<Cell<()>>,
}

impl CommandPool {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT | vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: creation on a live device from infos on this stack frame; the queue family
        // is the context's own.
        let pool = unsafe { ctx.device.create_command_pool(&info, None) }.context("create command pool")?;
        // SAFETY: as above.
        let fence = match unsafe { ctx.device.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(e) => {
                // SAFETY: the pool was made above and has no command buffers yet.
                unsafe { ctx.device.destroy_command_pool(pool, None) };
                return Err(e).context("create fence");
            }
        };
        Ok(Self { ctx: ctx.clone(), pool, fence, _one_thread: PhantomData })
    }

    /// Records commands with `f`, submits them and waits for completion.
    pub fn run<R>(&self, f: impl FnOnce(vk::CommandBuffer) -> Result<R>) -> Result<R> {
        let d = &self.ctx.device;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `self.pool` is live, and used by one thread at a time (CommandPool is not
        // Sync); a nested `run` on the same thread finishes before this one continues.
        let cmd = unsafe { d.allocate_command_buffers(&info) }.context("allocate command buffer")?[0];
        // Set between a submission and the end of its wait: `cmd` may still be executing.
        let mut pending = false;
        let result = (|| {
            // SAFETY: `cmd` was just allocated (initial state).
            unsafe {
                d.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
            }?;
            let r = f(cmd)?;
            // SAFETY: `cmd` is recording (begun above; `f` records into it but never ends it).
            unsafe { d.end_command_buffer(cmd) }.map_err(|e| device_error("vkEndCommandBuffer", e))?;
            let cmds = [cmd];
            let submit = vk::SubmitInfo::default().command_buffers(&cmds);
            // SAFETY: the fence is unsignalled or signalled by a finished submission (each run
            // waits for its own before returning), so it may be reset; `cmd` is executable and
            // submitted once, to the context's queue. The wait keeps `cmd` and everything `f`
            // borrowed alive until the GPU is done.
            unsafe {
                d.reset_fences(&[self.fence]).map_err(|e| device_error("vkResetFences", e))?;
                d.queue_submit(self.ctx.queue, &[submit], self.fence).map_err(|e| device_error("vkQueueSubmit", e))?;
                pending = true;
                d.wait_for_fences(&[self.fence], true, FENCE_TIMEOUT_NS)
                    .map_err(|e| device_error("vkWaitForFences", e))?;
            }
            pending = false;
            Ok(r)
        })();
        if !pending {
            // SAFETY: `cmd` came from this pool and is not pending: never submitted, or its
            // fence was waited for. (After a failed wait it is left to the pool, which Drop
            // destroys after the queue is idle.)
            unsafe { d.free_command_buffers(self.pool, &[cmd]) };
        }
        result
    }
}

/// How long a wait for the GPU may take before it counts as a hang: generous, because lavapipe
/// compiles a pipeline at its first dispatch, inside the wait. The compute backend's first
/// frame took 9.1 minutes on this 2-core machine with an empty shader cache (mostly LLVM on
/// gi.comp, whose workgroup barrier makes it split the shader as a coroutine), and tests that
/// compile at the same time share the two cores: 10 minutes did not always suffice. A GPU hang
/// still ends the program, with a message.
pub(super) const FENCE_TIMEOUT_NS: u64 = 30 * 60 * 1_000_000_000;

/// Turns a failed submission, wait or query read into a message the user can act on. Every
/// call in src/gpu that can report device loss (vkQueueSubmit, vkWaitForFences,
/// vkDeviceWaitIdle, vkGetQueryPoolResults with WAIT) goes through here; the destructors ignore
/// it, as destroying objects of a lost device is allowed.
pub(super) fn device_error(call: &str, e: vk::Result) -> anyhow::Error {
    match e {
        vk::Result::ERROR_DEVICE_LOST => anyhow::anyhow!(
            "the GPU device was lost ({call}: driver reset, crash or GPU hang); nothing more can be rendered in this \
             run: run again, and if it repeats try a smaller --size or --backend compute"
        ),
        vk::Result::TIMEOUT => anyhow::anyhow!("the GPU did not finish within 30 minutes ({call}; hang?)"),
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => {
            anyhow::anyhow!("out of device memory ({call}); try a smaller --size")
        }
        vk::Result::ERROR_OUT_OF_HOST_MEMORY => anyhow::anyhow!("out of host memory ({call})"),
        other => anyhow::anyhow!("{call} failed: {other}"),
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        // SAFETY: after the queue is idle nothing this pool allocated is pending; the fence and
        // pool were made by `new` and are destroyed once, here (their buffers go with the pool).
        unsafe {
            let _ = self.ctx.device.queue_wait_idle(self.ctx.queue);
            self.ctx.device.destroy_fence(self.fence, None);
            self.ctx.device.destroy_command_pool(self.pool, None);
        }
    }
}

/// A global memory barrier between two stage/access scopes (synchronization2).
pub(super) fn memory_barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let dep = vk::DependencyInfo::default().memory_barriers(&b);
    ctx.cmd_pipeline_barrier2(cmd, &dep);
}

/// An image barrier with a layout transition.
#[allow(clippy::too_many_arguments)]
pub(super) fn image_barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::ImageMemoryBarrier2::default()
        .image(image)
        .subresource_range(range)
        .old_layout(old)
        .new_layout(new)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let dep = vk::DependencyInfo::default().image_memory_barriers(&b);
    ctx.cmd_pipeline_barrier2(cmd, &dep);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Device loss cannot be caused on demand (lavapipe never loses its device), so the message
    /// is checked here; the calls that can return it all map through `device_error`.
    #[test]
    fn device_loss_and_hangs_read_clearly() {
        let lost = device_error("vkQueueSubmit", vk::Result::ERROR_DEVICE_LOST).to_string();
        assert!(lost.contains("device was lost") && lost.contains("vkQueueSubmit"), "{lost}");
        let hang = device_error("vkWaitForFences", vk::Result::TIMEOUT).to_string();
        assert!(hang.contains("30 minutes"), "{hang}");
        let oom = device_error("vkQueueSubmit", vk::Result::ERROR_OUT_OF_DEVICE_MEMORY).to_string();
        assert!(oom.contains("out of device memory") && oom.contains("--size"), "{oom}");
    }
}
