//! A safe view of a command buffer for passes: bind, push, dispatch, draw, copy, time. Passes
//! record through this and never touch ash directly.

use super::{Buffer, Context, DescriptorSet, Image, Pipeline, PushResource, TimestampPool};
use ash::vk;

pub struct Recorder<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
}

impl<'a> Recorder<'a> {
    /// `cmd` must be a command buffer of `ctx`'s device in the recording state, as handed
    /// out by `CommandPool::run` or `Swapchain::draw`, and stay so while this lives (the
    /// safety of every method rests on it; see the module header of gpu).
    pub fn new(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        Self { ctx, cmd }
    }

    pub fn bind_pipeline(&self, p: &Pipeline) {
        // SAFETY: `self.cmd` is recording (see `Recorder::new`); the pipeline is borrowed, so
        // it is live for the call, and the frame's fence wait keeps owners alive until the GPU
        // is done (the renderer drops pipelines only between frames).
        unsafe { self.ctx.device.cmd_bind_pipeline(self.cmd, p.bind_point, p.raw) };
    }

    pub fn bind_scene_set(&self, p: &Pipeline, set: vk::DescriptorSet) {
        // SAFETY: recording; `set` is the scene's DescriptorSet (the only set 0 the renderer
        // makes), alive as long as the scene upload that binds it, and it matches set 0 of
        // every pipeline layout made from the scene set layout.
        unsafe { self.ctx.device.cmd_bind_descriptor_sets(self.cmd, p.bind_point, p.layout, 0, &[set], &[]) };
    }

    /// Binds a pipeline's own set 0, for the pipelines outside the frame graph that do not read
    /// the scene set (skinning).
    pub fn bind_own_set(&self, p: &Pipeline, set: &DescriptorSet) {
        // SAFETY: recording; `set` is borrowed (live), and its owner keeps it alive until the
        // frame's fence wait, as it does the pipeline made with its layout.
        unsafe { self.ctx.device.cmd_bind_descriptor_sets(self.cmd, p.bind_point, p.layout, 0, &[set.raw], &[]) };
    }

    /// Pushes the pass's resources into set 1, bindings numbered 0.. in order.
    pub fn push_set(&self, p: &Pipeline, resources: &[PushResource]) {
        let mut image_infos = Vec::with_capacity(resources.len());
        let mut buffer_infos = Vec::with_capacity(resources.len());
        for r in resources {
            match *r {
                PushResource::StorageImage(view) => image_infos.push(vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: view,
                    image_layout: vk::ImageLayout::GENERAL,
                }),
                PushResource::SampledImage(view, sampler) => image_infos.push(vk::DescriptorImageInfo {
                    sampler,
                    image_view: view,
                    image_layout: vk::ImageLayout::GENERAL,
                }),
                PushResource::StorageBuffer(b) | PushResource::UniformBuffer(b) => {
                    buffer_infos.push(vk::DescriptorBufferInfo { buffer: b, offset: 0, range: vk::WHOLE_SIZE })
                }
            }
        }
        let (mut ii, mut bi) = (0, 0);
        let writes: Vec<_> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let w = vk::WriteDescriptorSet::default().dst_binding(i as u32);
                match r {
                    PushResource::StorageImage(_) | PushResource::SampledImage(..) => {
                        let ty = if matches!(r, PushResource::StorageImage(_)) {
                            vk::DescriptorType::STORAGE_IMAGE
                        } else {
                            vk::DescriptorType::COMBINED_IMAGE_SAMPLER
                        };
                        ii += 1;
                        w.descriptor_type(ty).image_info(std::slice::from_ref(&image_infos[ii - 1]))
                    }
                    PushResource::StorageBuffer(_) | PushResource::UniformBuffer(_) => {
                        let ty = if matches!(r, PushResource::StorageBuffer(_)) {
                            vk::DescriptorType::STORAGE_BUFFER
                        } else {
                            vk::DescriptorType::UNIFORM_BUFFER
                        };
                        bi += 1;
                        w.descriptor_type(ty).buffer_info(std::slice::from_ref(&buffer_infos[bi - 1]))
                    }
                }
            })
            .collect();
        // SAFETY: recording; `writes` points into `image_infos`/`buffer_infos`, which outlive the
        // call and are not grown after the pointers are taken (sized up front). Set 1 of every
        // pipeline layout is a push-descriptor layout (DescriptorSetLayout::new with `push`);
        // the views and buffers are of live images and buffers the frame graph owns.
        unsafe { self.ctx.push_descriptor.cmd_push_descriptor_set(self.cmd, p.bind_point, p.layout, 1, &writes) };
    }

    pub fn push_constants(&self, p: &Pipeline, data: &[u8]) {
        debug_assert!(data.len() as u32 <= p.push_constant_size);
        let stages = vk::ShaderStageFlags::COMPUTE | vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        // SAFETY: recording; the stages are exactly those of the layout's one push-constant
        // range (pipeline_layout), and the size is within it (checked in debug builds, and by
        // the validation layer in every test).
        unsafe { self.ctx.device.cmd_push_constants(self.cmd, p.layout, stages, 0, data) };
    }

    /// Dispatches enough groups of `group` threads to cover `extent` threads.
    pub fn dispatch_2d(&self, extent: vk::Extent2D, group: (u32, u32)) {
        // SAFETY: recording, with the pass's compute pipeline and resources bound first (every
        // pass records bind, push, dispatch in that order).
        unsafe {
            self.ctx.device.cmd_dispatch(self.cmd, extent.width.div_ceil(group.0), extent.height.div_ceil(group.1), 1)
        };
    }

    pub fn dispatch(&self, x: u32, y: u32, z: u32) {
        // SAFETY: as dispatch_2d.
        unsafe { self.ctx.device.cmd_dispatch(self.cmd, x, y, z) };
    }

    /// Starts dynamic rendering into colour attachments (each cleared to its value) and a depth
    /// attachment (cleared to 1). All attachments are in GENERAL layout.
    pub fn begin_rendering(&self, extent: vk::Extent2D, colors: &[(&Image, vk::ClearColorValue)], depth: &Image) {
        let color_infos: Vec<_> = colors
            .iter()
            .map(|(img, clear)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::GENERAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: *clear })
            })
            .collect();
        let depth_info = vk::RenderingAttachmentInfo::default()
            .image_view(depth.view)
            .image_layout(vk::ImageLayout::GENERAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&color_infos)
            .depth_attachment(&depth_info);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        self.ctx.cmd_begin_rendering(self.cmd, &info);
        // SAFETY: recording; one viewport and scissor, the count every raster pipeline has
        // (dynamic state, viewport_count 1).
        unsafe {
            self.ctx.device.cmd_set_viewport(self.cmd, 0, &[viewport]);
            self.ctx.device.cmd_set_scissor(self.cmd, 0, &[area]);
        }
    }

    pub fn end_rendering(&self) {
        self.ctx.cmd_end_rendering(self.cmd);
    }

    pub fn bind_index_buffer(&self, buffer: &Buffer) {
        // SAFETY: recording; the buffer is borrowed (live), offset 0 is aligned for u32.
        unsafe { self.ctx.device.cmd_bind_index_buffer(self.cmd, buffer.raw, 0, vk::IndexType::UINT32) };
    }

    pub fn draw_indexed(&self, index_count: u32, first_index: u32, vertex_offset: i32, first_instance: u32) {
        // SAFETY: recording inside begin_rendering with a raster pipeline and index buffer
        // bound (the G-buffer pass's order); its ranges come from the scene's own meshes.
        unsafe {
            self.ctx.device.cmd_draw_indexed(self.cmd, index_count, 1, first_index, vertex_offset, first_instance)
        };
    }

    pub fn copy_image_to_buffer(&self, image: &Image, buffer: &Buffer) {
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: image.aspect,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D { width: image.extent.width, height: image.extent.height, depth: 1 });
        // SAFETY: recording; both objects are borrowed (live). The region is the whole of mip
        // 0 in the image's own aspect, and the image is in GENERAL like every image the
        // renderer makes. Callers size `buffer` for the image (read-back buffers are made from
        // the image's extent and texel size).
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                self.cmd,
                image.raw,
                vk::ImageLayout::GENERAL,
                buffer.raw,
                &[region],
            )
        };
    }

    /// Fills a whole image (GENERAL layout) from tightly packed texels in a buffer.
    pub fn copy_buffer_to_image(&self, buffer: &Buffer, image: &Image) {
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: image.aspect,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D { width: image.extent.width, height: image.extent.height, depth: 1 });
        // SAFETY: as copy_image_to_buffer, the other way; the caller's buffer holds the whole
        // image's texels (uploads build it from the image's extent and format).
        unsafe {
            self.ctx.device.cmd_copy_buffer_to_image(
                self.cmd,
                buffer.raw,
                image.raw,
                vk::ImageLayout::GENERAL,
                &[region],
            )
        };
    }

    pub fn copy_buffer(&self, src: &Buffer, dst: &Buffer, size: u64) {
        let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size };
        // SAFETY: recording; both buffers borrowed (live); callers pass a size within both.
        unsafe { self.ctx.device.cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[region]) };
    }

    /// Copies `(src offset, dst offset, bytes)` regions between two buffers in one command.
    pub fn copy_buffer_regions(&self, src: &Buffer, dst: &Buffer, regions: &[(u64, u64, u64)]) {
        if regions.is_empty() {
            return;
        }
        let regions: Vec<vk::BufferCopy> = regions
            .iter()
            .map(|&(src_offset, dst_offset, size)| vk::BufferCopy { src_offset, dst_offset, size })
            .collect();
        // SAFETY: recording; both buffers borrowed (live); the regions come from the caller's
        // own layout of the two buffers (deform uploads), within their sizes.
        unsafe { self.ctx.device.cmd_copy_buffer(self.cmd, src.raw, dst.raw, &regions) };
    }

    /// Fills a whole buffer with zeros (a transfer: callers put barriers around it).
    pub fn zero_buffer(&self, buffer: &Buffer) {
        // SAFETY: recording; the buffer is borrowed (live) and was made with TRANSFER_DST by
        // callers of this function; WHOLE_SIZE fills it to its end.
        unsafe { self.ctx.device.cmd_fill_buffer(self.cmd, buffer.raw, 0, vk::WHOLE_SIZE, 0) };
    }

    /// Clears a colour image to zero (all bits zero, whatever its format).
    pub fn clear_image(&self, image: &Image) {
        let color = vk::ClearColorValue { uint32: [0; 4] };
        // SAFETY: recording; the image is borrowed (live), in GENERAL, and the range is its
        // own full range.
        unsafe {
            self.ctx.device.cmd_clear_color_image(
                self.cmd,
                image.raw,
                vk::ImageLayout::GENERAL,
                &color,
                &[image.full_range()],
            )
        };
    }

    pub fn timestamp(&self, pool: &TimestampPool, index: u32) {
        pool.write(self.cmd, index);
    }

    pub fn memory_barrier(
        &self,
        src: (vk::PipelineStageFlags2, vk::AccessFlags2),
        dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
    ) {
        super::memory_barrier(self.ctx, self.cmd, src, dst);
    }

    /// Moves an image from UNDEFINED to GENERAL (first use after creation).
    pub fn init_general(&self, image: &Image) {
        super::image_barrier(
            self.ctx,
            self.cmd,
            image.raw,
            image.full_range(),
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::GENERAL,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE),
        );
    }
}
