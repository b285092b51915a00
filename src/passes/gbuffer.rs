//! gbuffer: the raster pass every other pass builds on (shaders-glsl/gbuffer.vert, .frag).
//! Draws every instance once; masked texels are discarded; single-sided back faces too.

use super::PassBuilder;
use crate::gpu::{Pipeline, RasterDesc, vk};
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, PassKind, Preview, Usage};
use anyhow::Result;

pub const NAME: &str = "gbuffer";
/// View depth and its screen-space derivative (fwidth), for the denoisers' depth tests.
pub const DEPTH: Output = Output::new(NAME, "depth");
/// The face normal (reprojection asks whether a sample is the same surface).
pub const NORMAL_GEO: Output = Output::new(NAME, "normal_geo");
/// The shading normal (normal-mapped), and the view depth in alpha (0: no surface): the SVGF
/// passes weigh each tap by both, loaded as one texel (common/svgf.glsl, the guide texel).
pub const NORMAL: Output = Output::new(NAME, "normal");
pub const BASE_COLOR: Output = Output::new(NAME, "base_color");
/// Metallic, roughness, occlusion and transmission (KHR_materials_transmission).
pub const METAL_ROUGH: Output = Output::new(NAME, "metal_rough");
pub const EMISSIVE: Output = Output::new(NAME, "emissive");
/// Camera and object motion, pixels.
pub const MOTION: Output = Output::new(NAME, "motion");
/// Instance and material id ([`NO_ID`] where no surface).
pub const IDS: Output = Output::new(NAME, "ids");
/// The depth attachment.
pub const ZBUFFER: Output = Output::new(NAME, "zbuffer");

/// The colour outputs in attachment order (matching `layout(location = N)` in gbuffer.frag),
/// with their formats and previews.
const OUTPUTS: [(Output, vk::Format, Preview); 8] = [
    (DEPTH, vk::Format::R32G32_SFLOAT, Preview::Depth),
    (NORMAL_GEO, vk::Format::R16G16B16A16_SFLOAT, Preview::Normal),
    (NORMAL, vk::Format::R32G32B32A32_SFLOAT, Preview::Normal),
    (BASE_COLOR, vk::Format::R16G16B16A16_SFLOAT, Preview::Color),
    (METAL_ROUGH, vk::Format::R8G8B8A8_UNORM, Preview::Color),
    (EMISSIVE, vk::Format::R16G16B16A16_SFLOAT, Preview::Color),
    (MOTION, vk::Format::R32G32_SFLOAT, Preview::Motion),
    (IDS, vk::Format::R32G32_UINT, Preview::Ids),
];

/// Instance and material id written where no surface was hit.
pub const NO_ID: u32 = u32::MAX;

struct Draw {
    index_count: u32,
    first_index: u32,
    base_vertex: i32,
    instance: u32,
}

pub struct GbufferPass {
    pipeline: Pipeline,
    draws: Vec<Draw>,
}

pub fn new(b: &PassBuilder) -> Result<GbufferPass> {
    let vs = b.shaders.get("gbuffer.vert")?;
    let fs = b.shaders.get("gbuffer.frag")?;
    let formats: Vec<vk::Format> = OUTPUTS.iter().map(|o| o.1).collect();
    let pipeline = Pipeline::raster(
        b.ctx,
        &RasterDesc {
            name: NAME,
            vertex: &vs,
            fragment: &fs,
            sets: &[&b.scene.set_layout],
            push_constant_size: 0,
            color_formats: &formats,
            depth_format: vk::Format::D32_SFLOAT,
        },
    )?;
    let draws = b
        .scene
        .instance_meshes
        .iter()
        .enumerate()
        .map(|(i, &m)| {
            let mesh = b.scene.mesh_table[m as usize];
            Draw {
                index_count: mesh.index_count,
                first_index: mesh.first_index,
                base_vertex: mesh.base_vertex,
                instance: i as u32,
            }
        })
        .collect();
    Ok(GbufferPass { pipeline, draws })
}

impl Pass for GbufferPass {
    fn desc(&self) -> PassDesc {
        let mut outputs: Vec<OutputDesc> = OUTPUTS
            .iter()
            .map(|(n, f, p)| OutputDesc {
                name: (*n).into(),
                format: *f,
                usage: Usage::ColorAttachment,
                preview: *p,
                extent: None,
            })
            .collect();
        outputs.push(OutputDesc {
            name: ZBUFFER.into(),
            format: vk::Format::D32_SFLOAT,
            usage: Usage::DepthAttachment,
            preview: Preview::Scalar,
            extent: None,
        });
        PassDesc { name: NAME.into(), kind: PassKind::Raster, inputs: Vec::new(), outputs }
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        let rec = ctx.rec;
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        let no_id = vk::ClearColorValue { uint32: [NO_ID; 4] };
        let colors: Vec<_> =
            OUTPUTS.iter().map(|(n, _, _)| (ctx.images.get(*n), if *n == IDS { no_id } else { zero })).collect();
        rec.begin_rendering(ctx.extent, &colors, ctx.images.get(ZBUFFER));
        rec.bind_pipeline(&self.pipeline);
        rec.bind_scene_set(&self.pipeline, ctx.scene.set.raw);
        rec.bind_index_buffer(&ctx.scene.indices);
        for d in &self.draws {
            rec.draw_indexed(d.index_count, d.first_index, d.base_vertex, d.instance);
        }
        rec.end_rendering();
        Ok(())
    }
}
