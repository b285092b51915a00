//! A window's Vulkan surface and swapchain (the viewer). One frame is in flight at a time: the
//! renderer already waits for each frame, so a deeper queue would buy nothing and would make
//! every resource shared with the frame graph need per-frame copies.
//!
//! A frame: acquire an image, record into it (it is in COLOR_ATTACHMENT_OPTIMAL while the
//! caller records and must be left so), submit, present, wait. An out-of-date or suboptimal
//! swapchain is rebuilt at the next frame; a zero-sized window (minimised) draws nothing.

use super::{Context, Recorder, image_barrier};
use anyhow::{Context as _, Result, anyhow, bail};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
use std::sync::Arc;

/// The image a frame draws into.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    pub image: vk::Image,
    pub view: vk::ImageView,
    pub extent: vk::Extent2D,
    pub format: vk::Format,
    /// Whether the image can be copied from (screenshots).
    pub readable: bool,
}

pub struct Swapchain {
    ctx: Arc<Context>,
    surface_loader: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    /// Signalled per image by the frame's submission, waited on by the presentation.
    rendered: Vec<vk::Semaphore>,
    acquired: vk::Semaphore,
    fence: vk::Fence,
    pool: vk::CommandPool,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// FIFO presentation (tear-free, paced to the display) rather than the fastest mode.
    pub vsync: bool,
    pub present_mode: vk::PresentModeKHR,
    readable: bool,
    /// Rebuild before the next frame (resize, vsync toggle, out of date).
    stale: bool,
}

impl Swapchain {
    /// A surface for the window and a swapchain of `size` pixels (the surface's own size wins
    /// where the platform fixes it). The window must outlive the swapchain. The context must
    /// have been made for this display (`ContextOptions::window`).
    pub fn new(
        ctx: &Arc<Context>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        size: (u32, u32),
        vsync: bool,
    ) -> Result<Self> {
        let surface_loader = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        // SAFETY: the handles come from a live window, which the caller keeps alive for longer
        // than the swapchain (documented above).
        let surface = unsafe { ash_window::create_surface(&ctx.entry, &ctx.instance, display, window, None) }
            .context("create a Vulkan surface for the window")?;
        let mut s = Self {
            ctx: ctx.clone(),
            surface_loader,
            surface,
            loader: ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device),
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            views: Vec::new(),
            rendered: Vec::new(),
            acquired: vk::Semaphore::null(),
            fence: vk::Fence::null(),
            pool: vk::CommandPool::null(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D { width: size.0, height: size.1 },
            vsync,
            present_mode: vk::PresentModeKHR::FIFO,
            readable: false,
            stale: true,
        };
        // From here on `s` owns everything made, and its Drop frees it on any error.
        // SAFETY: the surface was just made on this instance; the queue family is the
        // context's own (an index the device has).
        let supported = unsafe {
            s.surface_loader.get_physical_device_surface_support(ctx.physical_device, ctx.queue_family, s.surface)
        }?;
        if !supported {
            bail!("the Vulkan device's graphics queue cannot present to this window");
        }
        // SAFETY: creations on a live device from infos on this stack frame; each handle is
        // stored in `s` at once, so Drop destroys whatever was made if a later one fails.
        unsafe {
            s.acquired = ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            s.fence = ctx.device.create_fence(&vk::FenceCreateInfo::default(), None)?;
            let info = vk::CommandPoolCreateInfo::default()
                .queue_family_index(ctx.queue_family)
                .flags(vk::CommandPoolCreateFlags::TRANSIENT | vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
            s.pool = ctx.device.create_command_pool(&info, None)?;
        }
        s.rebuild()?;
        Ok(s)
    }

    /// The window's drawable size changed: the swapchain follows at the next frame.
    pub fn resize(&mut self, width: u32, height: u32) {
        if (width, height) != (self.extent.width, self.extent.height) {
            self.extent = vk::Extent2D { width, height };
            self.stale = true;
        }
    }

    pub fn set_vsync(&mut self, vsync: bool) {
        if vsync != self.vsync {
            self.vsync = vsync;
            self.stale = true;
        }
    }

    fn rebuild(&mut self) -> Result<()> {
        let ctx = self.ctx.clone();
        let pd = ctx.physical_device;
        // SAFETY: the surface is owned by `self` and live, `pd` is the context's physical
        // device, and `new` checked the queue can present to the surface (so for all three).
        let caps = unsafe { self.surface_loader.get_physical_device_surface_capabilities(pd, self.surface) }?;
        // SAFETY: as above.
        let formats = unsafe { self.surface_loader.get_physical_device_surface_formats(pd, self.surface) }?;
        // SAFETY: as above.
        let modes = unsafe { self.surface_loader.get_physical_device_surface_present_modes(pd, self.surface) }?;
        // UNORM, not SRGB: everything drawn (tonemap output, previews, the overlay) is display-encoded
        // already, so bytes go to the screen unchanged and screenshots equal the PNG captures.
        let format = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .into_iter()
            .find_map(|f| formats.iter().find(|s| s.format == f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR))
            .ok_or_else(|| anyhow!("the window offers no 8-bit UNORM surface format ({formats:?})"))?;
        self.present_mode = if self.vsync {
            vk::PresentModeKHR::FIFO
        } else {
            [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
                .into_iter()
                .find(|m| modes.contains(m))
                .unwrap_or(vk::PresentModeKHR::FIFO)
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: self.extent.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: self.extent.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            // Minimised: keep the old swapchain until the window has pixels again.
            self.extent = extent;
            return Ok(());
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        self.readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | if self.readable { vk::ImageUsageFlags::TRANSFER_SRC } else { vk::ImageUsageFlags::empty() };
        let old = self.raw;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(self.present_mode)
            .clipped(true)
            .old_swapchain(old);
        ctx.wait_idle()?;
        // SAFETY: every value in `info` comes from the surface's own capabilities (format and
        // colour space offered, extent clamped to its limits, count within min..max, usage
        // within supported_usage_flags, present mode offered or FIFO, which is always there);
        // `old` is this surface's current swapchain or null, and the device is idle.
        let raw = unsafe { self.loader.create_swapchain(&info, None) }.context("vkCreateSwapchainKHR")?;
        self.destroy_images();
        // SAFETY: the device is idle (waited above), so no acquired image of `old` is in use;
        // its views and semaphores went just before; null is ignored.
        unsafe { self.loader.destroy_swapchain(old, None) };
        self.raw = raw;
        self.format = format.format;
        self.extent = extent;
        // SAFETY: `raw` was just made; its images belong to it (never destroyed by us).
        self.images = unsafe { self.loader.get_swapchain_images(raw) }?;
        for (i, &image) in self.images.iter().enumerate() {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.format)
                .subresource_range(color_range());
            // SAFETY: a colour view of a swapchain image in the swapchain's format.
            let view = unsafe { ctx.device.create_image_view(&view_info, None) }?;
            ctx.set_name(image, &format!("swapchain image {i}"));
            self.views.push(view);
            // SAFETY: creation on a live device.
            let sem = unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }?;
            self.rendered.push(sem);
        }
        self.stale = false;
        Ok(())
    }

    fn destroy_images(&mut self) {
        let d = &self.ctx.device;
        // SAFETY: callers make the device idle first (rebuild and Drop wait), so no frame uses
        // these views or semaphores; each was made by rebuild and is drained, so freed once.
        unsafe {
            for v in self.views.drain(..) {
                d.destroy_image_view(v, None);
            }
            for s in self.rendered.drain(..) {
                d.destroy_semaphore(s, None);
            }
        }
        self.images.clear();
    }

    /// Whether the window currently has pixels to draw into.
    pub fn visible(&self) -> bool {
        self.extent.width > 0 && self.extent.height > 0
    }

    /// Draws one frame: `record` fills the acquired image (in COLOR_ATTACHMENT_OPTIMAL, to be
    /// left so), then the frame is submitted, presented and waited for. `None` when nothing
    /// was drawn (minimised, or the swapchain went out of date: it is rebuilt next time).
    pub fn draw<R>(&mut self, record: impl FnOnce(&Recorder, &Target) -> Result<R>) -> Result<Option<R>> {
        if self.stale {
            self.rebuild()?;
        }
        if !self.visible() || self.raw == vk::SwapchainKHR::null() {
            return Ok(None);
        }
        // SAFETY: the swapchain is live and not null (checked above); `acquired` is unsignalled
        // with no pending wait, because the previous frame's submission waited on it and that
        // frame was waited for (one frame in flight), and a failed acquire signals nothing.
        let acquired = unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, self.acquired, vk::Fence::null()) };
        let index = match acquired {
            Ok((i, suboptimal)) => {
                self.stale |= suboptimal;
                i as usize
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(None);
            }
            Err(e) => return Err(anyhow!("vkAcquireNextImageKHR: {e}")),
        };
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is owned by `self` and used only here, under `&mut self`.
        let cmd = unsafe { d.allocate_command_buffers(&alloc) }.context("allocate command buffer")?[0];
        let target = Target {
            image: self.images[index],
            view: self.views[index],
            extent: self.extent,
            format: self.format,
            readable: self.readable,
        };
        // Set between the submission and the end of its wait: `cmd` may still be executing.
        let mut pending = false;
        let result = (|| {
            // SAFETY: `cmd` was just allocated (initial state).
            unsafe {
                d.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
            }?;
            // The acquire semaphore is waited on at the colour-output stage; the transition
            // chains to that wait through the same stage.
            let out = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
            image_barrier(
                &ctx,
                cmd,
                target.image,
                color_range(),
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::NONE),
                out,
            );
            let r = record(&Recorder::new(&ctx, cmd), &target)?;
            image_barrier(
                &ctx,
                cmd,
                target.image,
                color_range(),
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageLayout::PRESENT_SRC_KHR,
                out,
                (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            );
            // SAFETY: `cmd` is recording; `record` records into it but never ends it.
            unsafe { d.end_command_buffer(cmd) }?;
            let cmds = [cmd];
            let waits = [self.acquired];
            let stages = [vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT];
            let signals = [self.rendered[index]];
            let submit = vk::SubmitInfo::default()
                .command_buffers(&cmds)
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages)
                .signal_semaphores(&signals);
            // SAFETY: the fence is not in use (the last frame's wait returned, or it was never
            // submitted); `cmd` is executable; the acquire semaphore has a signal pending from
            // the acquire above, and `rendered[index]` is unsignalled: its last signal was
            // consumed by this image's previous present, which finished before the image could
            // be acquired again. Arrays live on this stack frame.
            unsafe {
                d.reset_fences(&[self.fence])?;
                d.queue_submit(ctx.queue, &[submit], self.fence).context("vkQueueSubmit")?;
            }
            pending = true;
            let swapchains = [self.raw];
            let indices = [index as u32];
            let present =
                vk::PresentInfoKHR::default().wait_semaphores(&signals).swapchains(&swapchains).image_indices(&indices);
            // SAFETY: `index` was acquired from this swapchain and is presented once, waiting
            // on the semaphore the submission signals; the queue can present (checked in new).
            let presented = unsafe { self.loader.queue_present(ctx.queue, &present) };
            // Wait even when presenting failed: the submission itself went ahead.
            // SAFETY: the fence belongs to this device and was submitted above.
            unsafe { d.wait_for_fences(&[self.fence], true, super::commands::FENCE_TIMEOUT_NS) }
                .context("wait for the frame")?;
            pending = false;
            match presented {
                Ok(suboptimal) => self.stale |= suboptimal,
                Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
                Err(e) => return Err(anyhow!("vkQueuePresentKHR: {e}")),
            }
            Ok(r)
        })();
        if !pending {
            // SAFETY: `cmd` came from this pool and is not pending: never submitted, or its
            // fence was waited for. (After a failed wait it is left to the pool, which Drop
            // destroys after the device is idle.)
            unsafe { d.free_command_buffers(self.pool, &[cmd]) };
        }
        result.map(Some)
    }
}

fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        self.destroy_images();
        let d = &self.ctx.device;
        // SAFETY: the device is idle (waited above), so nothing is pending; each handle was
        // made by new/rebuild and is destroyed once, the swapchain before its surface. The
        // window outlives the surface (the contract of `new`).
        unsafe {
            // Null handles (a swapchain never made, a failed start) are ignored by Vulkan.
            self.loader.destroy_swapchain(self.raw, None);
            d.destroy_semaphore(self.acquired, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            self.surface_loader.destroy_surface(self.surface, None);
        }
    }
}
