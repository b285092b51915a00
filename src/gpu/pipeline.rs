//! Compute and graphics pipelines. Every pipeline uses the same two-set shape: set 0 the scene
//! set, set 1 the pass's push-descriptor set, plus an optional push-constant block.

use super::{Context, DescriptorSetLayout};
use anyhow::{Context as _, Result, anyhow};
use ash::vk;
use std::sync::Arc;

pub struct Pipeline {
    ctx: Arc<Context>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub bind_point: vk::PipelineBindPoint,
    pub push_constant_size: u32,
    pub name: String,
}

fn shader_module(ctx: &Context, spirv: &[u32], name: &str) -> Result<vk::ShaderModule> {
    let info = vk::ShaderModuleCreateInfo::default().code(spirv);
    // SAFETY: `spirv` is a whole SPIR-V module as u32 words (the size ash passes is in bytes,
    // a multiple of 4 by construction), compiled by shaderc (committed in shaders-spv/, which
    // tests/committed_spirv.rs checks byte for byte against shaderc's output, or at build time
    // or start-up with the shader-compiler feature), which emits valid SPIR-V; the device is live.
    unsafe { ctx.device.create_shader_module(&info, None) }.with_context(|| format!("create shader module {name}"))
}

fn pipeline_layout(
    ctx: &Context,
    sets: &[&DescriptorSetLayout],
    push_constant_size: u32,
) -> Result<vk::PipelineLayout> {
    let raw_sets: Vec<_> = sets.iter().map(|s| s.raw).collect();
    let ranges = [vk::PushConstantRange {
        stage_flags: vk::ShaderStageFlags::COMPUTE | vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
        offset: 0,
        size: push_constant_size,
    }];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&raw_sets);
    if push_constant_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    // SAFETY: the set layouts are borrowed (live); `raw_sets` and `ranges` outlive the call.
    unsafe { ctx.device.create_pipeline_layout(&info, None) }.context("create pipeline layout")
}

impl Pipeline {
    pub fn compute(
        ctx: &Arc<Context>,
        name: &str,
        spirv: &[u32],
        sets: &[&DescriptorSetLayout],
        push_constant_size: u32,
    ) -> Result<Self> {
        let layout = pipeline_layout(ctx, sets, push_constant_size)?;
        let module = match shader_module(ctx, spirv, name) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: made above, used by nothing yet.
                unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
                return Err(e);
            }
        };
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
        // SAFETY: the module and layout were made above on this device; `info` (and the stage's
        // entry-point name, a 'static C string) live across the call.
        let result = unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
        // SAFETY: a module may be destroyed once pipelines are made from it; nothing else uses it.
        unsafe { ctx.device.destroy_shader_module(module, None) };
        match result {
            Ok(p) => {
                ctx.set_name(p[0], name);
                Ok(Self {
                    ctx: ctx.clone(),
                    raw: p[0],
                    layout,
                    bind_point: vk::PipelineBindPoint::COMPUTE,
                    push_constant_size,
                    name: name.to_string(),
                })
            }
            Err((_, e)) => {
                // SAFETY: made above; no pipeline was made with it.
                unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
                Err(anyhow!("create compute pipeline {name}: {e}"))
            }
        }
    }

    /// A raster pipeline for a full-screen-sized G-buffer style pass: triangle lists, no vertex
    /// input (vertices are pulled from storage buffers), depth test and write, no culling (the
    /// fragment shader discards back faces of single-sided materials), no blending.
    pub fn raster(ctx: &Arc<Context>, desc: &RasterDesc) -> Result<Self> {
        let layout = pipeline_layout(ctx, desc.sets, desc.push_constant_size)?;
        let vs = shader_module(ctx, desc.vertex, desc.name);
        let fs = shader_module(ctx, desc.fragment, desc.name);
        let (vs, fs) = match (vs, fs) {
            (Ok(v), Ok(f)) => (v, f),
            (v, f) => {
                // SAFETY: whichever of the two modules was made, and the layout, were made just
                // above and are used by nothing.
                unsafe {
                    if let Ok(v) = v {
                        ctx.device.destroy_shader_module(v, None);
                    }
                    if let Ok(f) = f {
                        ctx.device.destroy_shader_module(f, None);
                    }
                    ctx.device.destroy_pipeline_layout(layout, None);
                }
                return Err(anyhow!("create shader modules for {}", desc.name));
            }
        };
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let attachments: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format);
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
            .layout(layout)
            .push_next(&mut rendering);
        // SAFETY: modules and layout made above on this device; every state struct, the
        // colour formats and the rendering info (chained) live across the call. Dynamic
        // rendering is enabled (required by the context), so no render pass is needed.
        let result = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
        // SAFETY: as for compute: modules may go once the pipeline is made (or failed).
        unsafe {
            ctx.device.destroy_shader_module(vs, None);
            ctx.device.destroy_shader_module(fs, None);
        }
        match result {
            Ok(p) => {
                ctx.set_name(p[0], desc.name);
                Ok(Self {
                    ctx: ctx.clone(),
                    raw: p[0],
                    layout,
                    bind_point: vk::PipelineBindPoint::GRAPHICS,
                    push_constant_size: desc.push_constant_size,
                    name: desc.name.to_string(),
                })
            }
            Err((_, e)) => {
                // SAFETY: made above; no pipeline was made with it.
                unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
                Err(anyhow!("create graphics pipeline {}: {e}", desc.name))
            }
        }
    }
}

pub struct RasterDesc<'a> {
    pub name: &'a str,
    pub vertex: &'a [u32],
    pub fragment: &'a [u32],
    pub sets: &'a [&'a DescriptorSetLayout],
    pub push_constant_size: u32,
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: made by `compute`/`raster`, destroyed once. Pipelines are dropped between
        // frames (hot reload swaps them after the frame's fence wait), so no pending command
        // buffer uses them.
        unsafe {
            self.ctx.device.destroy_pipeline(self.raw, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}
