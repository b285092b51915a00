//! What the viewer draws into a swapchain image: the shown image (a frame-graph output, or an
//! RGBA8 picture made on the CPU) fitted to the window, an optional read-back of that
//! (the screenshot, taken before the overlay so it holds the picture only), then an overlay of
//! textured, alpha-blended triangles on top. The overlay comes in plain types ([`Overlay`]:
//! vertices, indices, draws, texture updates), checked before anything is recorded; the
//! viewer turns its UI toolkit's output into them (src/app/overlay_painter.rs).
//!
//! Everything here lives in GENERAL layout except the swapchain image, like the rest of the
//! renderer; the barriers are global ones because this runs once per frame on small data.

use super::swapchain::Target;
use super::{
    Binding, BindingKind, Buffer, Context, DescriptorSetLayout, Image, MemoryLocation, Recorder, Sampler, SamplerDesc,
    ShaderLibrary, image_barrier,
};
use anyhow::{Context as _, Result, anyhow, bail};
use ash::vk;
use std::collections::HashMap;
use std::sync::Arc;

/// The picture to show.
pub enum Shown<'a> {
    /// A frame-graph image holding display-encoded RGBA8 (the tonemap output), read in place.
    Graph(&'a Image),
    /// Display-encoded RGBA8 texels made on the CPU (the capture's preview of an output).
    Rgba { width: u32, height: u32, texels: &'a [u8] },
}

/// One overlay vertex: position in overlay units (top-left origin; see
/// [`Overlay::pixels_per_unit`]), texture coordinates, premultiplied RGBA8 colour. The layout
/// view_overlay.vert reads (20 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OverlayVertex {
    pub pos: [f32; 2],
    pub uv: [f32; 2],
    pub color: [u8; 4],
}

/// An overlay texture, named by the caller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct OverlayTextureId(pub u64);

/// New texels for an overlay texture, applied before the frame's triangles are drawn.
#[derive(Clone, Copy, Debug)]
pub struct OverlayTextureUpdate<'a> {
    pub id: OverlayTextureId,
    /// `None`: the texture is made anew with this size (replacing one of the same id);
    /// `Some([x, y])`: a patch written at x, y into the existing texture.
    pub at: Option<[u32; 2]>,
    pub width: u32,
    pub height: u32,
    /// Tightly packed RGBA8 rows (premultiplied), top to bottom: `width * height * 4` bytes.
    pub texels: &'a [u8],
}

/// A run of indexed triangles drawn with one texture, clipped to a rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverlayDraw {
    /// Clip rectangle in overlay units: min x, min y, max x, max y.
    pub clip: [f32; 4],
    pub texture: OverlayTextureId,
    /// `Overlay::indices[first_index..first_index + index_count]`, each plus `vertex_offset`.
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: u32,
}

/// Textured triangles drawn over the shown image, blended "one, one minus source alpha"
/// (premultiplied colours).
#[derive(Clone, Copy, Debug)]
pub struct Overlay<'a> {
    pub vertices: &'a [OverlayVertex],
    pub indices: &'a [u32],
    pub draws: &'a [OverlayDraw],
    pub textures: &'a [OverlayTextureUpdate<'a>],
    /// Textures no longer used: freed once this frame has finished.
    pub freed: &'a [OverlayTextureId],
    /// Window pixels per overlay unit (the UI's scale).
    pub pixels_per_unit: f32,
}

impl Overlay<'_> {
    /// Every draw reads indices that exist and vertices that exist, and every texture update
    /// holds the texels its size says: what the GPU would otherwise read out of bounds.
    pub fn check(&self) -> Result<()> {
        if !(self.pixels_per_unit.is_finite() && self.pixels_per_unit > 0.0) {
            bail!("overlay: {} pixels per unit", self.pixels_per_unit);
        }
        if self.vertices.len() > i32::MAX as usize {
            bail!("overlay: {} vertices (at most {})", self.vertices.len(), i32::MAX);
        }
        for (k, d) in self.draws.iter().enumerate() {
            let range = d.first_index as usize..d.first_index as usize + d.index_count as usize;
            let indices = self
                .indices
                .get(range.clone())
                .ok_or_else(|| anyhow!("overlay draw {k}: indices {range:?} of {} given", self.indices.len()))?;
            if let Some(i) = indices.iter().find(|&&i| i as u64 + d.vertex_offset as u64 >= self.vertices.len() as u64)
            {
                bail!("overlay draw {k}: index {i} + {} past {} vertices", d.vertex_offset, self.vertices.len());
            }
        }
        for t in self.textures {
            if t.width == 0 || t.height == 0 || t.texels.len() as u64 != t.width as u64 * t.height as u64 * 4 {
                bail!("overlay texture {:?}: {} bytes for {}x{} RGBA8", t.id, t.texels.len(), t.width, t.height);
            }
        }
        Ok(())
    }
}

/// The window's pixels under the overlay, read back.
pub struct Screenshot {
    buffer: Buffer,
    pub width: u32,
    pub height: u32,
    bgra: bool,
}

impl Screenshot {
    /// Tightly packed RGBA8 rows, top to bottom.
    pub fn rgba(&self) -> Result<Vec<u8>> {
        let bytes = self.buffer.mapped().ok_or_else(|| anyhow!("screenshot buffer is not mapped"))?;
        let mut out = bytes[..(self.width * self.height * 4) as usize].to_vec();
        if self.bgra {
            out.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        Ok(out)
    }
}

/// Push constants shared by both pipelines (see view_present.frag and view_overlay.vert).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    rect: [i32; 4],
    src_size: [i32; 2],
    screen: [f32; 2],
}

pub struct Presenter {
    ctx: Arc<Context>,
    set_layout: DescriptorSetLayout,
    layout: vk::PipelineLayout,
    present: vk::Pipeline,
    overlay: vk::Pipeline,
    format: vk::Format,
    nearest: Sampler,
    linear: Sampler,
    /// The overlay's textures (the UI's font atlas, mostly), RGBA8 in GENERAL layout.
    textures: HashMap<OverlayTextureId, Image>,
    /// Textures the overlay dropped last frame: freed once that frame has finished.
    to_free: Vec<OverlayTextureId>,
    /// The CPU-made picture's GPU copy, remade when its size changes.
    shown: Option<Image>,
    /// Staging and geometry of the last frame, kept until it has finished (the next call).
    in_flight: Vec<Buffer>,
}

impl Presenter {
    /// Pipelines for drawing into images of `format` (the swapchain's).
    pub fn new(ctx: &Arc<Context>, shaders: &ShaderLibrary, format: vk::Format) -> Result<Self> {
        let set_layout =
            DescriptorSetLayout::new(ctx, &[Binding { binding: 0, kind: BindingKind::SampledImage, count: 1 }], true)?;
        let point = SamplerDesc { mag_linear: false, min_linear: false, ..SamplerDesc::LINEAR_CLAMP };
        let mut p = Self {
            ctx: ctx.clone(),
            set_layout,
            layout: vk::PipelineLayout::null(),
            present: vk::Pipeline::null(),
            overlay: vk::Pipeline::null(),
            format,
            nearest: Sampler::new(ctx, point)?,
            linear: Sampler::new(ctx, SamplerDesc::LINEAR_CLAMP)?,
            textures: HashMap::new(),
            to_free: Vec::new(),
            shown: None,
            in_flight: Vec::new(),
        };
        // From here on Drop frees whatever was made if a step fails.
        let sets = [p.set_layout.raw];
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            offset: 0,
            size: size_of::<Params>() as u32,
        }];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets).push_constant_ranges(&ranges);
        // SAFETY: the set layout is owned by `p` (live); `sets` and `ranges` outlive the call.
        p.layout = unsafe { ctx.device.create_pipeline_layout(&info, None) }.context("create pipeline layout")?;
        p.present = p.pipeline(shaders, "view_present", false)?;
        p.overlay = p.pipeline(shaders, "view_overlay", true)?;
        Ok(p)
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// A pipeline drawing into one colour attachment of `self.format`: the present pass (no
    /// vertex input, no blending) or the overlay ([`OverlayVertex`], premultiplied blending).
    fn pipeline(&self, shaders: &ShaderLibrary, name: &str, overlay: bool) -> Result<vk::Pipeline> {
        let d = &self.ctx.device;
        let vs = shaders.get(&format!("{name}.vert"))?;
        let fs = shaders.get(&format!("{name}.frag"))?;
        // SAFETY: whole SPIR-V modules from the shader library (shaderc output, as u32 words).
        let vs = unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&vs), None) }?;
        // SAFETY: as above.
        let fs = match unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&fs), None) } {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: made above, used by nothing.
                unsafe { d.destroy_shader_module(vs, None) };
                return Err(e.into());
            }
        };
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
        ];
        // OverlayVertex: pos (2 x f32), uv (2 x f32), colour (4 x u8), 20 bytes.
        let bindings = [vk::VertexInputBindingDescription {
            binding: 0,
            stride: size_of::<OverlayVertex>() as u32,
            input_rate: vk::VertexInputRate::VERTEX,
        }];
        let attributes = [
            vk::VertexInputAttributeDescription {
                location: 0,
                binding: 0,
                format: vk::Format::R32G32_SFLOAT,
                offset: 0,
            },
            vk::VertexInputAttributeDescription {
                location: 1,
                binding: 0,
                format: vk::Format::R32G32_SFLOAT,
                offset: 8,
            },
            vk::VertexInputAttributeDescription {
                location: 2,
                binding: 0,
                format: vk::Format::R8G8B8A8_UNORM,
                offset: 16,
            },
        ];
        let vertex_input = if overlay {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes)
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
        };
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let attachment = vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA)
            .blend_enable(overlay)
            .src_color_blend_factor(vk::BlendFactor::ONE)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_DST_ALPHA)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE)
            .alpha_blend_op(vk::BlendOp::ADD);
        let attachments = [attachment];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let formats = [self.format];
        let mut rendering = vk::PipelineRenderingCreateInfo::default().color_attachment_formats(&formats);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default();
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(self.layout)
            .push_next(&mut rendering);
        // SAFETY: modules and layout are live; every state struct, the attachment format and
        // the chained rendering info live across the call (dynamic rendering: no render pass).
        // The vertex input describes OverlayVertex (repr(C), offsets 0, 8, 16).
        let result = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
        // SAFETY: modules may be destroyed once the pipeline is made (or failed); nothing else
        // uses them.
        unsafe {
            d.destroy_shader_module(vs, None);
            d.destroy_shader_module(fs, None);
        }
        let pipeline = result.map_err(|(_, e)| anyhow!("create graphics pipeline {name}: {e}"))?[0];
        self.ctx.set_name(pipeline, name);
        Ok(pipeline)
    }

    /// Records one frame into `target`: `shown` fitted to the window, a read-back of that
    /// when `screenshot`, then `overlay`. The returned screenshot is valid once the frame has
    /// finished (after `Swapchain::draw` returns).
    pub fn record(
        &mut self,
        rec: &Recorder,
        target: &Target,
        shown: Shown,
        overlay: Option<Overlay>,
        screenshot: bool,
    ) -> Result<Option<Screenshot>> {
        if target.format != self.format {
            bail!("the presenter draws {:?}, the window is {:?}", self.format, target.format);
        }
        if let Some(o) = &overlay {
            o.check()?;
        }
        // The previous frame has finished (one frame in flight): its resources may go.
        self.in_flight.clear();
        for id in self.to_free.drain(..) {
            self.textures.remove(&id);
        }
        let ctx = self.ctx.clone();
        // Frame-graph images were last written by earlier submissions; make those writes
        // visible to this frame's reads (and order this frame after them).
        rec.memory_barrier(
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
            (
                vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::SHADER_SAMPLED_READ | vk::AccessFlags2::TRANSFER_WRITE,
            ),
        );
        let (view, src_size) = match shown {
            Shown::Graph(image) => (image.view, image.extent),
            Shown::Rgba { width, height, texels } => {
                let image = self.upload_shown(rec, width, height, texels)?;
                (image.view, image.extent)
            }
        };
        if let Some(o) = &overlay {
            self.upload_textures(rec, o.textures)?;
        }
        rec.memory_barrier(
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
            (vk::PipelineStageFlags2::FRAGMENT_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
        );

        let extent = target.extent;
        let params = Params {
            rect: fit(src_size, extent),
            src_size: [src_size.width as i32, src_size.height as i32],
            screen: overlay
                .as_ref()
                .map(|o| [extent.width as f32 / o.pixels_per_unit, extent.height as f32 / o.pixels_per_unit])
                .unwrap_or([1.0, 1.0]),
        };
        let d = &ctx.device;
        let cmd = rec.cmd;
        self.begin(rec, target, vk::AttachmentLoadOp::DONT_CARE);
        // SAFETY: `cmd` is recording inside the rendering just begun (Swapchain::draw hands
        // this a recording command buffer and its target); the pipeline and layout are owned
        // by `self`; the push covers exactly the layout's one range (Params, both stages).
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.present);
            d.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(&params),
            );
        }
        self.bind_texture(rec, view, self.nearest.raw);
        // SAFETY: pipeline, texture, push constants, viewport and scissor are all set above;
        // the present pipeline has no vertex input (a full-screen triangle from the index).
        unsafe { d.cmd_draw(cmd, 3, 1, 0, 0) };
        ctx.cmd_end_rendering(cmd);

        let shot = if screenshot { Some(self.read_back(rec, target)?) } else { None };

        if let Some(o) = overlay {
            self.begin(rec, target, vk::AttachmentLoadOp::LOAD);
            self.draw_overlay(rec, target, &o)?;
            ctx.cmd_end_rendering(cmd);
            self.to_free.extend_from_slice(o.freed);
        }
        // Later submissions (the next frame's passes) overwrite what was read here.
        rec.memory_barrier(
            (vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COPY, vk::AccessFlags2::NONE),
            (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::NONE),
        );
        Ok(shot)
    }

    fn begin(&self, rec: &Recorder, target: &Target, load: vk::AttachmentLoadOp) {
        let attachments = [vk::RenderingAttachmentInfo::default()
            .image_view(target.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: target.extent };
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&attachments);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: target.extent.width as f32,
            height: target.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        self.ctx.cmd_begin_rendering(rec.cmd, &info);
        // SAFETY: recording; one viewport and scissor, the counts both pipelines declare.
        unsafe {
            self.ctx.device.cmd_set_viewport(rec.cmd, 0, &[viewport]);
            self.ctx.device.cmd_set_scissor(rec.cmd, 0, &[area]);
        }
    }

    fn bind_texture(&self, rec: &Recorder, view: vk::ImageView, sampler: vk::Sampler) {
        let info = [vk::DescriptorImageInfo { sampler, image_view: view, image_layout: vk::ImageLayout::GENERAL }];
        let write = [vk::WriteDescriptorSet::default()
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&info)];
        // SAFETY: recording; set 0 of `self.layout` is a push-descriptor layout with one
        // combined image sampler at binding 0, which this writes. The view is the shown image
        // (a frame-graph image, or `self.shown`) or an overlay texture, all in GENERAL and
        // kept alive until the frame has finished; the sampler is owned by `self`.
        unsafe {
            self.ctx.push_descriptor.cmd_push_descriptor_set(
                rec.cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &write,
            )
        };
    }

    /// Copies CPU texels into the shown image through a staging buffer.
    fn upload_shown(&mut self, rec: &Recorder, width: u32, height: u32, texels: &[u8]) -> Result<&Image> {
        if width == 0 || height == 0 || texels.len() as u64 != width as u64 * height as u64 * 4 {
            bail!("shown image: {} bytes for {width}x{height} RGBA8", texels.len());
        }
        let extent = vk::Extent2D { width, height };
        if self.shown.as_ref().is_none_or(|i| i.extent != extent) {
            let image = self.new_texture("viewer shown image", extent)?;
            init_general(rec, &image);
            self.shown = Some(image);
        }
        let image = self.shown.as_ref().expect("made above");
        let staging =
            Buffer::with_data(&self.ctx, "viewer shown (staging)", texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
        copy_region(rec, &staging, image, [0, 0], extent);
        self.in_flight.push(staging);
        Ok(self.shown.as_ref().expect("made above"))
    }

    fn new_texture(&self, name: &str, extent: vk::Extent2D) -> Result<Image> {
        Image::new(
            &self.ctx,
            name,
            vk::Format::R8G8B8A8_UNORM,
            extent,
            1,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        )
    }

    /// The overlay's new and changed textures (sizes checked by `Overlay::check`): whole
    /// images are made anew, patches copied in place after a bounds check.
    fn upload_textures(&mut self, rec: &Recorder, updates: &[OverlayTextureUpdate]) -> Result<()> {
        for u in updates {
            let extent = vk::Extent2D { width: u.width, height: u.height };
            let offset = match u.at {
                Some([x, y]) => [x, y],
                None => {
                    let image = self.new_texture(&format!("overlay texture {}", u.id.0), extent)?;
                    init_general(rec, &image);
                    // The replaced texture may still be read by nothing: the last frame finished.
                    self.textures.insert(u.id, image);
                    [0, 0]
                }
            };
            let image =
                self.textures.get(&u.id).ok_or_else(|| anyhow!("overlay patched an unknown texture {:?}", u.id))?;
            let fits = |at: u32, len: u32, size: u32| at.checked_add(len).is_some_and(|end| end <= size);
            if !fits(offset[0], u.width, image.extent.width) || !fits(offset[1], u.height, image.extent.height) {
                bail!(
                    "overlay texture {:?}: a {}x{} patch at {offset:?} leaves its {}x{} texels",
                    u.id,
                    u.width,
                    u.height,
                    image.extent.width,
                    image.extent.height
                );
            }
            let staging = Buffer::with_data(
                &self.ctx,
                "overlay texture (staging)",
                u.texels,
                vk::BufferUsageFlags::TRANSFER_SRC,
            )?;
            copy_region(rec, &staging, image, [offset[0] as i32, offset[1] as i32], extent);
            self.in_flight.push(staging);
        }
        Ok(())
    }

    fn read_back(&mut self, rec: &Recorder, target: &Target) -> Result<Screenshot> {
        if !target.readable {
            bail!("this window's images cannot be read back (no TRANSFER_SRC usage)");
        }
        let (w, h) = (target.extent.width, target.extent.height);
        let buffer = Buffer::new(
            &self.ctx,
            "screenshot",
            w as u64 * h as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let colour = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        let copy = (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ);
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        image_barrier(
            &self.ctx,
            rec.cmd,
            target.image,
            range,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            colour,
            copy,
        );
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D { width: w, height: h, depth: 1 });
        // SAFETY: recording, outside rendering; the target was made with TRANSFER_SRC
        // (`readable`) and moved to TRANSFER_SRC_OPTIMAL just above; the buffer holds w x h
        // four-byte texels, the whole image.
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                rec.cmd,
                target.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
        image_barrier(
            &self.ctx,
            rec.cmd,
            target.image,
            range,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            copy,
            (
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_READ | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            ),
        );
        // The copy must land before the host maps the buffer (after the frame's fence).
        rec.memory_barrier(copy_write(), (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ));
        Ok(Screenshot { buffer, width: w, height: h, bgra: target.format == vk::Format::B8G8R8A8_UNORM })
    }

    /// Records the overlay's draws (checked by `Overlay::check`), each clipped by a scissor.
    fn draw_overlay(&mut self, rec: &Recorder, target: &Target, o: &Overlay) -> Result<()> {
        if o.draws.iter().all(|d| d.index_count == 0) {
            return Ok(());
        }
        let vertices: &[u8] = bytemuck::cast_slice(o.vertices);
        let indices: &[u8] = bytemuck::cast_slice(o.indices);
        let vb = Buffer::with_data(&self.ctx, "overlay vertices", vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let ib = Buffer::with_data(&self.ctx, "overlay indices", indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        let d = &self.ctx.device;
        let cmd = rec.cmd;
        // SAFETY: recording inside the overlay's rendering (begun by `record`); the pipeline
        // is owned by `self`; both buffers hold the overlay's data and stay in `in_flight`
        // until the frame has finished; indices are u32 at offset 0.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.overlay);
            d.cmd_bind_vertex_buffers(cmd, 0, &[vb.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, ib.raw, 0, vk::IndexType::UINT32);
        }
        let (w, h) = (target.extent.width as f32, target.extent.height as f32);
        let ppu = o.pixels_per_unit;
        for draw in o.draws {
            let [min_x, min_y, max_x, max_y] = draw.clip;
            let x0 = (min_x * ppu).round().clamp(0.0, w);
            let y0 = (min_y * ppu).round().clamp(0.0, h);
            let x1 = (max_x * ppu).round().clamp(x0, w);
            let y1 = (max_y * ppu).round().clamp(y0, h);
            let visible = draw.index_count > 0 && x1 > x0 && y1 > y0;
            // A draw naming a texture never uploaded is skipped, like one clipped away.
            if let (true, Some(texture)) = (visible, self.textures.get(&draw.texture)) {
                let scissor = vk::Rect2D {
                    offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 },
                    extent: vk::Extent2D { width: (x1 - x0) as u32, height: (y1 - y0) as u32 },
                };
                self.bind_texture(rec, texture.view, self.linear.raw);
                // SAFETY: the scissor lies inside the target (clamped above); `Overlay::check`
                // (run by `record`) proved every index of this draw, plus its vertex offset
                // (<= i32::MAX), addresses a vertex in the bound buffer.
                unsafe {
                    d.cmd_set_scissor(cmd, 0, &[scissor]);
                    d.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, draw.vertex_offset as i32, 0);
                }
            }
        }
        self.in_flight.push(vb);
        self.in_flight.push(ib);
        Ok(())
    }
}

fn copy_write() -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
    (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE)
}

/// A new image's first use: UNDEFINED to GENERAL, before the copies into it.
fn init_general(rec: &Recorder, image: &Image) {
    image_barrier(
        rec.ctx,
        rec.cmd,
        image.raw,
        image.full_range(),
        vk::ImageLayout::UNDEFINED,
        vk::ImageLayout::GENERAL,
        (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
        copy_write(),
    );
}

/// Copies tightly packed RGBA8 texels into `image` at `offset` (GENERAL layout).
fn copy_region(rec: &Recorder, staging: &Buffer, image: &Image, offset: [i32; 2], extent: vk::Extent2D) {
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_offset(vk::Offset3D { x: offset[0], y: offset[1], z: 0 })
        .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
    // SAFETY: recording, outside rendering; the image is in GENERAL and the region lies inside
    // it (whole image, or a patch checked by upload_textures); the staging buffer holds
    // exactly extent's texels (checked by upload_shown / Overlay::check). Both stay alive
    // until the frame has finished (`in_flight`, `textures`).
    unsafe {
        rec.ctx.device.cmd_copy_buffer_to_image(rec.cmd, staging.raw, image.raw, vk::ImageLayout::GENERAL, &[region])
    };
}

/// Where an image of `src` pixels goes in a window of `dst` pixels: as large as fits with its
/// aspect kept, centred; exactly 1:1 when the sizes match.
fn fit(src: vk::Extent2D, dst: vk::Extent2D) -> [i32; 4] {
    let (sw, sh, dw, dh) = (src.width as u64, src.height as u64, dst.width as u64, dst.height as u64);
    // Width-limited when src is relatively wider than dst (sw/sh >= dw/dh).
    let (w, h) = if sw * dh >= dw * sh { (dw, (dw * sh / sw).max(1)) } else { ((dh * sw / sh).max(1), dh) };
    [((dw - w) / 2) as i32, ((dh - h) / 2) as i32, w as i32, h as i32]
}

impl Drop for Presenter {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        // SAFETY: after the wait nothing uses the pipelines or layout; each was made by `new`
        // (or is still null) and is destroyed once.
        unsafe {
            let _ = d.device_wait_idle();
            // Null handles (a failed start) are ignored by Vulkan.
            d.destroy_pipeline(self.present, None);
            d.destroy_pipeline(self.overlay, None);
            d.destroy_pipeline_layout(self.layout, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(width: u32, height: u32) -> vk::Extent2D {
        vk::Extent2D { width, height }
    }

    #[test]
    fn fit_keeps_aspect_and_centres() {
        assert_eq!(fit(e(320, 240), e(320, 240)), [0, 0, 320, 240]);
        assert_eq!(fit(e(320, 240), e(640, 240)), [160, 0, 320, 240]);
        assert_eq!(fit(e(320, 240), e(320, 480)), [0, 120, 320, 240]);
        assert_eq!(fit(e(100, 100), e(50, 80)), [0, 15, 50, 50]);
    }

    #[test]
    fn overlay_check_rejects_what_would_read_out_of_bounds() {
        let vertices = [OverlayVertex::default(); 4];
        let indices = [0, 1, 2, 1, 2, 3];
        let draw = OverlayDraw {
            clip: [0.0, 0.0, 10.0, 10.0],
            texture: OverlayTextureId(0),
            first_index: 0,
            index_count: 6,
            vertex_offset: 0,
        };
        let texels = [0u8; 2 * 2 * 4];
        let texture = OverlayTextureUpdate { id: OverlayTextureId(0), at: None, width: 2, height: 2, texels: &texels };
        let draws = [draw];
        let textures = [texture];
        let good = Overlay {
            vertices: &vertices,
            indices: &indices,
            draws: &draws,
            textures: &textures,
            freed: &[],
            pixels_per_unit: 1.0,
        };
        good.check().expect("in bounds");
        let past_vertices = [OverlayDraw { vertex_offset: 1, ..draw }];
        let err = Overlay { draws: &past_vertices, ..good }.check().unwrap_err().to_string();
        assert!(err.contains("past 4 vertices"), "{err}");
        let past_indices = [OverlayDraw { first_index: 3, ..draw }];
        let err = Overlay { draws: &past_indices, ..good }.check().unwrap_err().to_string();
        assert!(err.contains("indices 3..9 of 6"), "{err}");
        let short = [OverlayTextureUpdate { width: 3, ..texture }];
        let err = Overlay { textures: &short, ..good }.check().unwrap_err().to_string();
        assert!(err.contains("16 bytes for 3x2"), "{err}");
        assert!(Overlay { pixels_per_unit: 0.0, ..good }.check().is_err());
    }
}
