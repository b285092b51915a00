//! The compute backend: the project's BVH (src/accel/bvh) in one storage buffer of rows.
//!
//! The top level comes first (a region reserved for the instance count), the pooled bottom
//! levels after it; row 0 tells the shader where they start. The bottom levels are built
//! once; the top level is rebuilt on the CPU when instances move and goes through a
//! host-visible staging buffer and a copy recorded before the next trace.

use super::bvh::{Row, SceneBvh, Tlas};
use super::{AccelStats, FIRST_BINDING, RayAccel, same_instances};
use crate::backend::Backend;
use crate::gpu::{
    self, Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSet, MemoryLocation, Recorder, vk,
};
use crate::scene::{Pose, Scene};
use anyhow::{Result, bail};
use std::sync::Arc;
use std::time::Instant;

pub struct ComputeAccel {
    bvh: SceneBvh,
    /// The top level's rows (the first `tlas_rows`), then the bottom levels'.
    rows: Buffer,
    tlas_staging: Buffer,
    tlas_rows: usize,
    /// The staging buffer holds a top level not yet copied into `rows`.
    dirty: bool,
    last_pose: Pose,
    stats: AccelStats,
}

impl ComputeAccel {
    pub fn new(ctx: &Arc<Context>, pool: &CommandPool, scene: &Scene, pose: &Pose) -> Result<Self> {
        let start = Instant::now();
        let bvh = SceneBvh::build(scene, pose);
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let tlas_rows = Tlas::rows_for(scene.instances.len());
        let mut all = top_level_rows(&bvh.tlas, tlas_rows)?;
        all.extend_from_slice(&bvh.blas.rows);
        let rows = gpu::upload::device_buffer(
            ctx,
            pool,
            "bvh.rows",
            bytemuck::cast_slice(&all),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        drop(all);
        let tlas_bytes = (tlas_rows * size_of::<Row>()) as u64;
        let tlas_staging = Buffer::new(
            ctx,
            "bvh.tlas (staging)",
            tlas_bytes,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let blas_bytes = rows.size - tlas_bytes;
        let stats = AccelStats {
            blas_build_ms: build_ms,
            blas_bytes,
            blas_bytes_uncompacted: blas_bytes,
            tlas_bytes,
            upload_bytes_per_update: tlas_bytes,
            top_level_rebuilds: 0,
        };
        Ok(Self { bvh, rows, tlas_staging, tlas_rows, dirty: false, last_pose: pose.clone(), stats })
    }
}

/// The top level as the GPU buffer starts: its rows, with row 0 naming where the bottom
/// levels start, padded to `capacity` rows.
fn top_level_rows(tlas: &Tlas, capacity: usize) -> Result<Vec<Row>> {
    if tlas.rows.len() > capacity {
        bail!("top-level BVH has {} rows, more than the {capacity} reserved", tlas.rows.len());
    }
    let mut rows = tlas.rows.clone();
    rows[0][1] = capacity as u32;
    rows.resize(capacity, [0; 4]);
    Ok(rows)
}

impl RayAccel for ComputeAccel {
    fn backend(&self) -> Backend {
        Backend::Compute
    }

    fn bindings(&self) -> Vec<Binding> {
        vec![Binding { binding: FIRST_BINDING, kind: BindingKind::StorageBuffer, count: 1 }]
    }

    fn write_set(&self, set: &DescriptorSet) {
        set.write_buffer(FIRST_BINDING, BindingKind::StorageBuffer, &self.rows);
    }

    fn update_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        if same_instances(scene, &self.last_pose, pose) {
            return Ok(());
        }
        self.bvh.update_instances(scene, pose);
        let rows = top_level_rows(&self.bvh.tlas, self.tlas_rows)?;
        self.tlas_staging.write(0, bytemuck::cast_slice(&rows))?;
        self.dirty = true;
        self.last_pose = pose.clone();
        self.stats.top_level_rebuilds += 1;
        Ok(())
    }

    fn record_update(&mut self, rec: &Recorder) -> Result<()> {
        if !self.dirty {
            return Ok(());
        }
        // The copy overwrites rows that earlier traces (compute or fragment shaders) may still
        // read, and later traces must see it. Host writes to the staging buffer are made
        // visible by the queue submission.
        let readers = vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        rec.memory_barrier((readers, vk::AccessFlags2::SHADER_STORAGE_READ), transfer);
        rec.copy_buffer(&self.tlas_staging, &self.rows, self.tlas_staging.size);
        rec.memory_barrier(transfer, (readers, vk::AccessFlags2::SHADER_STORAGE_READ));
        self.dirty = false;
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
