//! The compute backend: the project's BVH (src/accel/bvh) in storage buffers. Bottom levels
//! are built once and uploaded to device memory; the top level is rebuilt on the CPU when
//! instances move and rewritten into host-visible buffers.

use super::bvh::{BvhInstance, BvhNode, SceneBvh};
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
    blas_nodes: Buffer,
    blas_triangles: Buffer,
    tlas_nodes: Buffer,
    tlas_instances: Buffer,
    last_pose: Pose,
    stats: AccelStats,
}

/// Top-level nodes reserved per instance: a binary tree over n leaves has fewer than n inner
/// nodes, plus the root of a single-leaf tree.
fn tlas_node_capacity(instances: usize) -> usize {
    instances.max(1) + 1
}

impl ComputeAccel {
    pub fn new(ctx: &Arc<Context>, pool: &CommandPool, scene: &Scene, pose: &Pose) -> Result<Self> {
        let start = Instant::now();
        let bvh = SceneBvh::build(scene, pose);
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let blas_nodes =
            gpu::upload::device_buffer(ctx, pool, "bvh.blas_nodes", bytemuck::cast_slice(&bvh.blas.nodes), storage)?;
        let blas_triangles = gpu::upload::device_buffer(
            ctx,
            pool,
            "bvh.blas_triangles",
            bytemuck::cast_slice(&bvh.blas.triangles),
            storage,
        )?;
        let n = scene.instances.len();
        let node_bytes = (tlas_node_capacity(n) * size_of::<BvhNode>()) as u64;
        let instance_bytes = (n.max(1) * size_of::<BvhInstance>()) as u64;
        let tlas_nodes = Buffer::new(ctx, "bvh.tlas_nodes", node_bytes, storage, MemoryLocation::CpuToGpu)?;
        let tlas_instances = Buffer::new(ctx, "bvh.tlas_instances", instance_bytes, storage, MemoryLocation::CpuToGpu)?;
        let stats = AccelStats {
            blas_build_ms: build_ms,
            blas_bytes: blas_nodes.size + blas_triangles.size,
            blas_bytes_uncompacted: blas_nodes.size + blas_triangles.size,
            tlas_bytes: node_bytes + instance_bytes,
            upload_bytes_per_update: node_bytes + instance_bytes,
            top_level_rebuilds: 0,
        };
        let mut accel =
            Self { bvh, blas_nodes, blas_triangles, tlas_nodes, tlas_instances, last_pose: pose.clone(), stats };
        accel.upload_top_level()?;
        Ok(accel)
    }

    fn upload_top_level(&mut self) -> Result<()> {
        let tlas = &self.bvh.tlas;
        if tlas.nodes.len() > tlas_node_capacity(tlas.instances.len()) {
            bail!("top-level BVH has {} nodes, more than reserved", tlas.nodes.len());
        }
        self.tlas_nodes.write(0, bytemuck::cast_slice(&tlas.nodes))?;
        self.tlas_instances.write(0, bytemuck::cast_slice(&tlas.instances))?;
        Ok(())
    }
}

impl RayAccel for ComputeAccel {
    fn backend(&self) -> Backend {
        Backend::Compute
    }

    fn bindings(&self) -> Vec<Binding> {
        (0..4).map(|i| Binding { binding: FIRST_BINDING + i, kind: BindingKind::StorageBuffer, count: 1 }).collect()
    }

    fn write_set(&self, set: &DescriptorSet) {
        let buffers = [&self.tlas_nodes, &self.tlas_instances, &self.blas_nodes, &self.blas_triangles];
        for (i, b) in buffers.iter().enumerate() {
            set.write_buffer(FIRST_BINDING + i as u32, BindingKind::StorageBuffer, b);
        }
    }

    fn update_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        if same_instances(scene, &self.last_pose, pose) {
            return Ok(());
        }
        self.bvh.update_instances(scene, pose);
        self.upload_top_level()?;
        self.last_pose = pose.clone();
        self.stats.top_level_rebuilds += 1;
        Ok(())
    }

    fn record_update(&mut self, _rec: &Recorder) -> Result<()> {
        // Host writes to the top-level buffers are made visible by the queue submission.
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
