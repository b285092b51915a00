//! Tracing a list of rays through the scene's ray backend (shaders-glsl/trace_rays.comp): the
//! ray benchmark and the backend-agreement tests run exactly the same rays on both backends.

use crate::accel::bvh::rays::Ray;
use crate::gpu::{
    Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSetLayout, MemoryLocation, Pipeline, PushResource,
    Recorder, ShaderLibrary, TimestampPool, vk,
};
use crate::world::SceneGpu;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// The time of one trace of a ray list.
#[derive(Clone, Copy, Debug)]
pub struct TraceTime {
    /// Recording to fence: what a CPU device (lavapipe) spends, and on a GPU the dispatch
    /// plus one submission's overhead.
    pub wall_ms: f64,
    /// Timestamps around the dispatch, where the device has them (lavapipe's can leave
    /// compute dispatches out, so the bench rates rays by `wall_ms`).
    pub gpu_ms: Option<f64>,
}

/// One ray's result, as trace_rays.comp writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitRecord {
    /// Instance id, or [`NO_HIT`].
    pub instance: u32,
    pub primitive: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub front_face: u32,
    pub pad: [u32; 2],
}

pub const NO_HIT: u32 = u32::MAX;

impl HitRecord {
    pub fn is_hit(&self) -> bool {
        self.instance != NO_HIT
    }
}

const GROUP: u32 = 64;

pub struct RayBatch {
    pipeline: Pipeline,
    _set_layout: DescriptorSetLayout,
    timestamps: TimestampPool,
}

impl RayBatch {
    pub fn new(ctx: &Arc<Context>, shaders: &ShaderLibrary, scene: &SceneGpu) -> Result<Self> {
        let b = |binding| Binding { binding, kind: BindingKind::StorageBuffer, count: 1 };
        let set_layout = DescriptorSetLayout::new(ctx, &[b(0), b(1)], true)?;
        let key = format!("trace_rays.comp:{}", scene.accel.backend().variant());
        let pipeline = Pipeline::compute(ctx, "trace_rays", &shaders.get(&key)?, &[&scene.set_layout, &set_layout], 8)?;
        Ok(Self { pipeline, _set_layout: set_layout, timestamps: TimestampPool::new(ctx, 2)? })
    }

    /// Traces `rays` (closest hit, or any hit for shadow rays) `repeats` times after one
    /// untimed warm-up (lavapipe compiles a pipeline's code at its first dispatch); returns
    /// the hits and the time of each repetition.
    pub fn trace(
        &self,
        ctx: &Arc<Context>,
        pool: &CommandPool,
        scene: &mut SceneGpu,
        rays: &[Ray],
        any_hit: bool,
        repeats: u32,
    ) -> Result<(Vec<HitRecord>, Vec<TraceTime>)> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let ray_buffer = crate::gpu::upload::device_buffer(ctx, pool, "rays", bytemuck::cast_slice(rays), storage)?;
        let hits = Buffer::new(
            ctx,
            "hits",
            (rays.len().max(1) * size_of::<HitRecord>()) as u64,
            storage,
            MemoryLocation::GpuToCpu,
        )?;
        let push: [u32; 2] = [rays.len() as u32, any_hit as u32];
        let mut times = Vec::new();
        for run in 0..=repeats.max(1) {
            let start = std::time::Instant::now();
            pool.run(|cmd| {
                let rec = Recorder::new(ctx, cmd);
                scene.record_update(&rec)?;
                self.timestamps.reset(cmd);
                rec.timestamp(&self.timestamps, 0);
                rec.bind_pipeline(&self.pipeline);
                rec.bind_scene_set(&self.pipeline, scene.set.raw);
                rec.push_set(
                    &self.pipeline,
                    &[PushResource::StorageBuffer(ray_buffer.raw), PushResource::StorageBuffer(hits.raw)],
                );
                rec.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
                rec.dispatch((rays.len() as u32).div_ceil(GROUP), 1, 1);
                rec.timestamp(&self.timestamps, 1);
                rec.memory_barrier(
                    (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
                    (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
                );
                Ok(())
            })?;
            let wall_ms = start.elapsed().as_secs_f64() * 1e3;
            if run > 0 {
                let gpu_ms = self.timestamps.read_ms(2).map(|ts| ts[1] - ts[0]);
                times.push(TraceTime { wall_ms, gpu_ms });
            }
        }
        let bytes = hits.mapped().ok_or_else(|| anyhow::anyhow!("hit buffer is not mapped"))?;
        let records: Vec<HitRecord> = bytemuck::pod_collect_to_vec(&bytes[..rays.len() * size_of::<HitRecord>()]);
        Ok((records, times))
    }
}
