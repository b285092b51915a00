//! The compute backend: the project's BVH (src/accel/bvh) in one storage buffer of rows.
//!
//! The top level comes first (a region reserved for the instance count), the pooled bottom
//! levels after it; row 0 tells the shader where they start. The bottom levels are built
//! once; the top level is rebuilt on the CPU when instances move and goes through a
//! host-visible staging buffer and a copy recorded before the next trace.
//!
//! A deforming mesh's tree lives in rows reserved for its largest possible tree; each
//! deformation refits it on the CPU (or rebuilds it, every [`super::REBUILD_EVERY`] refits)
//! and uploads that mesh's rows and the top level, nothing else.

use super::bvh::{BuildOptions, MeshBvh, Row, SceneBvh, Tlas, reserved_rows};
use super::{AccelStats, FIRST_BINDING, RayAccel, RefitTimes, rebuild_due, same_instances};
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
    deforming: Vec<Deforming>,
    /// The deforming meshes' rows as last refit, one region per mesh; `None` without any.
    blas_staging: Option<Buffer>,
    /// Copies from `blas_staging` into `rows` not yet recorded: (src, dst, bytes).
    blas_copies: Vec<(u64, u64, u64)>,
    times: RefitTimes,
}

struct Deforming {
    mesh: u32,
    /// Byte offset of the mesh's region in the staging buffer.
    staging_offset: u64,
    /// Refits since the tree was last built.
    refits: u32,
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
            ..Default::default()
        };
        let mut deforming = Vec::new();
        let mut staging_bytes = 0u64;
        for mesh in (0..scene.meshes.len() as u32).filter(|&m| scene.deforms(m)) {
            deforming.push(Deforming { mesh, staging_offset: staging_bytes, refits: 0 });
            staging_bytes += (bvh.blas.meshes[mesh as usize].rows as usize * size_of::<Row>()) as u64;
        }
        let blas_staging = if deforming.is_empty() {
            None
        } else {
            Some(Buffer::new(
                ctx,
                "bvh.blas (staging)",
                staging_bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?)
        };
        Ok(Self {
            bvh,
            rows,
            tlas_staging,
            tlas_rows,
            dirty: false,
            last_pose: pose.clone(),
            stats,
            deforming,
            blas_staging,
            blas_copies: Vec::new(),
            times: RefitTimes::default(),
        })
    }

    /// Rebuilds the top level for `pose` and stages it for the next `record_update`.
    fn stage_top_level(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        self.bvh.update_instances(scene, pose);
        let rows = top_level_rows(&self.bvh.tlas, self.tlas_rows)?;
        self.tlas_staging.write(0, bytemuck::cast_slice(&rows))?;
        self.dirty = true;
        self.last_pose = pose.clone();
        self.stats.top_level_rebuilds += 1;
        Ok(())
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
        self.stage_top_level(scene, pose)
    }

    fn update_geometry(&mut self, scene: &Scene, pose: &Pose, meshes: &[(u32, &[glam::Vec3])]) -> Result<()> {
        if meshes.is_empty() {
            return Ok(());
        }
        let staging = self.blas_staging.as_mut().ok_or_else(|| anyhow::anyhow!("no deforming meshes"))?;
        let start = Instant::now();
        let mut rebuilt = false;
        for &(mesh, positions) in meshes {
            let Some(d) = self.deforming.iter_mut().find(|d| d.mesh == mesh) else {
                bail!("mesh {mesh} deformed, but its BVH has no reserved rows");
            };
            let indices = &scene.meshes[mesh as usize].indices;
            let changed = if rebuild_due(&mut d.refits) {
                let tree = MeshBvh::build(positions, indices, &BuildOptions::MESH);
                debug_assert!(tree.rows.len() <= reserved_rows(tree.triangle_count));
                self.stats.blas_rebuilds += 1;
                rebuilt = true;
                self.bvh.blas.replace_mesh(mesh, tree)
            } else {
                self.stats.blas_refits += 1;
                self.bvh.blas.refit_mesh(mesh, positions, indices)
            };
            // Only the rows the tree now spans change; the rest of its reserve is never read.
            let range = &self.bvh.blas.meshes[mesh as usize];
            let rows = &self.bvh.blas.rows[range.base as usize..range.base as usize + changed.rows];
            staging.write(d.staging_offset as usize, bytemuck::cast_slice(rows))?;
            let bytes = (changed.rows * size_of::<Row>()) as u64;
            let dst = ((self.tlas_rows + range.base as usize) * size_of::<Row>()) as u64;
            // A mesh deformed twice before a recording is copied once, from its latest rows.
            self.blas_copies.retain(|c| c.0 != d.staging_offset);
            self.blas_copies.push((d.staging_offset, dst, bytes));
        }
        // Timed with the staging writes: that upload is part of what a refit costs here.
        self.times.add(rebuilt, start.elapsed().as_secs_f64() * 1e3);
        // The instances' boxes (and a lone instance's copy of its mesh root) changed.
        self.stage_top_level(scene, pose)
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
        if let Some(staging) = &self.blas_staging {
            rec.copy_buffer_regions(staging, &self.rows, &self.blas_copies);
        }
        self.blas_copies.clear();
        rec.memory_barrier(transfer, (readers, vk::AccessFlags2::SHADER_STORAGE_READ));
        self.dirty = false;
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        let mut stats = self.stats.clone();
        self.times.fill(&mut stats);
        stats
    }
}
