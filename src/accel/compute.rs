//! The compute backend: the project's BVH (src/accel/bvh) in storage buffers.
//!
//! Both levels' nodes share one device buffer so the shader fetches every node the same way:
//! the top level's nodes first (a region reserved for the instance count), then the pooled
//! bottom levels, whose roots the instance records point at. The top level is rebuilt on the
//! CPU when instances move; its nodes go through a host-visible staging buffer and a copy
//! recorded before the next trace, and its instance records are rewritten in place.

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
    /// Top-level nodes (the first `tlas_capacity`), then the bottom levels' nodes.
    nodes: Buffer,
    tlas_staging: Buffer,
    tlas_instances: Buffer,
    triangles: Buffer,
    tlas_capacity: usize,
    /// The staging buffer holds top-level nodes not yet copied into `nodes`.
    dirty: bool,
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
        let tlas_capacity = tlas_node_capacity(scene.instances.len());
        let mut all_nodes = vec![BvhNode::default(); tlas_capacity];
        all_nodes.extend_from_slice(&bvh.blas.nodes);
        let nodes = gpu::upload::device_buffer(ctx, pool, "bvh.nodes", bytemuck::cast_slice(&all_nodes), storage)?;
        drop(all_nodes);
        let triangles =
            gpu::upload::device_buffer(ctx, pool, "bvh.triangles", bytemuck::cast_slice(&bvh.blas.triangles), storage)?;
        let node_bytes = (tlas_capacity * size_of::<BvhNode>()) as u64;
        let instance_bytes = (scene.instances.len().max(1) * size_of::<BvhInstance>()) as u64;
        let tlas_staging = Buffer::new(
            ctx,
            "bvh.tlas_nodes (staging)",
            node_bytes,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let tlas_instances = Buffer::new(ctx, "bvh.tlas_instances", instance_bytes, storage, MemoryLocation::CpuToGpu)?;
        let blas_bytes = nodes.size - node_bytes + triangles.size;
        let stats = AccelStats {
            blas_build_ms: build_ms,
            blas_bytes,
            blas_bytes_uncompacted: blas_bytes,
            tlas_bytes: node_bytes + instance_bytes,
            upload_bytes_per_update: node_bytes + instance_bytes,
            top_level_rebuilds: 0,
        };
        let mut accel = Self {
            bvh,
            nodes,
            tlas_staging,
            tlas_instances,
            triangles,
            tlas_capacity,
            dirty: false,
            last_pose: pose.clone(),
            stats,
        };
        accel.write_top_level()?;
        Ok(accel)
    }

    /// Writes the top level's nodes to the staging buffer and its instances, with roots
    /// shifted past the top-level region, to their buffer.
    fn write_top_level(&mut self) -> Result<()> {
        let tlas = &self.bvh.tlas;
        if tlas.nodes.len() > self.tlas_capacity {
            bail!("top-level BVH has {} nodes, more than reserved", tlas.nodes.len());
        }
        let offset = self.tlas_capacity as u32;
        let instances: Vec<BvhInstance> =
            tlas.instances.iter().map(|i| BvhInstance { root_node: i.root_node + offset, ..*i }).collect();
        self.tlas_staging.write(0, bytemuck::cast_slice(&tlas.nodes))?;
        self.tlas_instances.write(0, bytemuck::cast_slice(&instances))?;
        self.dirty = true;
        Ok(())
    }
}

impl RayAccel for ComputeAccel {
    fn backend(&self) -> Backend {
        Backend::Compute
    }

    fn bindings(&self) -> Vec<Binding> {
        (0..3).map(|i| Binding { binding: FIRST_BINDING + i, kind: BindingKind::StorageBuffer, count: 1 }).collect()
    }

    fn write_set(&self, set: &DescriptorSet) {
        for (i, b) in [&self.nodes, &self.tlas_instances, &self.triangles].iter().enumerate() {
            set.write_buffer(FIRST_BINDING + i as u32, BindingKind::StorageBuffer, b);
        }
    }

    fn update_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        if same_instances(scene, &self.last_pose, pose) {
            return Ok(());
        }
        self.bvh.update_instances(scene, pose);
        self.write_top_level()?;
        self.last_pose = pose.clone();
        self.stats.top_level_rebuilds += 1;
        Ok(())
    }

    fn record_update(&mut self, rec: &Recorder) -> Result<()> {
        if !self.dirty {
            return Ok(());
        }
        // The copy overwrites nodes that earlier traces in flight may still read; later traces
        // (compute or fragment shaders) must see it. Host writes to the staging and instance
        // buffers are made visible by the queue submission.
        let readers = vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        rec.memory_barrier((readers, vk::AccessFlags2::SHADER_STORAGE_READ), transfer);
        rec.copy_buffer(&self.tlas_staging, &self.nodes, self.tlas_staging.size);
        rec.memory_barrier(transfer, (readers, vk::AccessFlags2::SHADER_STORAGE_READ));
        self.dirty = false;
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
