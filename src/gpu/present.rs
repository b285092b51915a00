//! What the viewer draws into a swapchain image: the shown image (a frame-graph output, or an
//! RGBA8 picture made on the CPU) fitted to the window, an optional read-back of that
//! (the screenshot, taken before the overlay so it holds the picture only), then the egui
//! overlay's triangles on top.
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

/// egui's output for one frame.
pub struct Overlay<'a> {
    pub primitives: &'a [egui::ClippedPrimitive],
    pub textures: &'a egui::TexturesDelta,
    pub pixels_per_point: f32,
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
    /// egui's textures (the font atlas, mostly), RGBA8 in GENERAL layout.
    textures: HashMap<egui::TextureId, Image>,
    /// Textures egui dropped last frame: freed once that frame has finished.
    to_free: Vec<egui::TextureId>,
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
        p.layout = unsafe { ctx.device.create_pipeline_layout(&info, None) }.context("create pipeline layout")?;
        p.present = p.pipeline(shaders, "view_present", false)?;
        p.overlay = p.pipeline(shaders, "view_overlay", true)?;
        Ok(p)
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// A pipeline drawing into one colour attachment of `self.format`: the present pass (no
    /// vertex input, no blending) or the overlay (egui vertices, premultiplied blending).
    fn pipeline(&self, shaders: &ShaderLibrary, name: &str, overlay: bool) -> Result<vk::Pipeline> {
        let d = &self.ctx.device;
        let vs = shaders.get(&format!("{name}.vert"))?;
        let fs = shaders.get(&format!("{name}.frag"))?;
        let vs = unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&vs), None) }?;
        let fs = match unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&fs), None) } {
            Ok(m) => m,
            Err(e) => {
                unsafe { d.destroy_shader_module(vs, None) };
                return Err(e.into());
            }
        };
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
        ];
        // egui::epaint::Vertex: pos (2 x f32), uv (2 x f32), colour (4 x u8), 20 bytes.
        let bindings =
            [vk::VertexInputBindingDescription { binding: 0, stride: 20, input_rate: vk::VertexInputRate::VERTEX }];
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
        let result = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
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
                .map(|o| [extent.width as f32 / o.pixels_per_point, extent.height as f32 / o.pixels_per_point])
                .unwrap_or([1.0, 1.0]),
        };
        let d = &ctx.device;
        let cmd = rec.cmd;
        self.begin(rec, target, vk::AttachmentLoadOp::DONT_CARE);
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
        unsafe { d.cmd_draw(cmd, 3, 1, 0, 0) };
        ctx.cmd_end_rendering(cmd);

        let shot = if screenshot { Some(self.read_back(rec, target)?) } else { None };

        if let Some(o) = overlay {
            self.begin(rec, target, vk::AttachmentLoadOp::LOAD);
            self.draw_overlay(rec, target, &o)?;
            ctx.cmd_end_rendering(cmd);
            self.to_free.extend(o.textures.free.iter().copied());
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
        if texels.len() != (width * height * 4) as usize {
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

    /// egui's new and changed textures: whole images are made anew, patches copied in place.
    fn upload_textures(&mut self, rec: &Recorder, delta: &egui::TexturesDelta) -> Result<()> {
        for (id, d) in &delta.set {
            let egui::ImageData::Color(img) = &d.image;
            let extent = vk::Extent2D { width: img.width() as u32, height: img.height() as u32 };
            let texels: &[u8] = bytemuck::cast_slice(&img.pixels);
            let offset = match d.pos {
                Some([x, y]) => [x as i32, y as i32],
                None => {
                    let image = self.new_texture(&format!("egui texture {id:?}"), extent)?;
                    init_general(rec, &image);
                    // The replaced texture may still be read by nothing: the last frame finished.
                    self.textures.insert(*id, image);
                    [0, 0]
                }
            };
            let image = self.textures.get(id).ok_or_else(|| anyhow!("egui patched an unknown texture {id:?}"))?;
            let staging =
                Buffer::with_data(&self.ctx, "egui texture (staging)", texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
            copy_region(rec, &staging, image, offset, extent);
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

    fn draw_overlay(&mut self, rec: &Recorder, target: &Target, o: &Overlay) -> Result<()> {
        let meshes: Vec<(&egui::Rect, &egui::epaint::Mesh)> = o
            .primitives
            .iter()
            .filter_map(|p| match &p.primitive {
                egui::epaint::Primitive::Mesh(m) if !m.indices.is_empty() => Some((&p.clip_rect, m)),
                _ => None,
            })
            .collect();
        if meshes.is_empty() {
            return Ok(());
        }
        let vertices: Vec<u8> =
            meshes.iter().flat_map(|(_, m)| bytemuck::cast_slice::<_, u8>(&m.vertices).iter().copied()).collect();
        let indices: Vec<u8> =
            meshes.iter().flat_map(|(_, m)| bytemuck::cast_slice::<_, u8>(&m.indices).iter().copied()).collect();
        let vb = Buffer::with_data(&self.ctx, "egui vertices", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let ib = Buffer::with_data(&self.ctx, "egui indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        let d = &self.ctx.device;
        let cmd = rec.cmd;
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.overlay);
            d.cmd_bind_vertex_buffers(cmd, 0, &[vb.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, ib.raw, 0, vk::IndexType::UINT32);
        }
        let (w, h) = (target.extent.width as f32, target.extent.height as f32);
        let ppp = o.pixels_per_point;
        let (mut first_index, mut vertex_offset) = (0u32, 0i32);
        for (clip, mesh) in meshes {
            let x0 = (clip.min.x * ppp).round().clamp(0.0, w);
            let y0 = (clip.min.y * ppp).round().clamp(0.0, h);
            let x1 = (clip.max.x * ppp).round().clamp(x0, w);
            let y1 = (clip.max.y * ppp).round().clamp(y0, h);
            let count = mesh.indices.len() as u32;
            if let (true, Some(texture)) = (x1 > x0 && y1 > y0, self.textures.get(&mesh.texture_id)) {
                let scissor = vk::Rect2D {
                    offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 },
                    extent: vk::Extent2D { width: (x1 - x0) as u32, height: (y1 - y0) as u32 },
                };
                self.bind_texture(rec, texture.view, self.linear.raw);
                unsafe {
                    d.cmd_set_scissor(cmd, 0, &[scissor]);
                    d.cmd_draw_indexed(cmd, count, 1, first_index, vertex_offset, 0);
                }
            }
            first_index += count;
            vertex_offset += mesh.vertices.len() as i32;
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
}
