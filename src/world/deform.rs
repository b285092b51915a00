//! Deforming meshes on the GPU: each frame whose morph weights differ from the last frame's,
//! the deformed vertices (evaluated on the CPU, [`crate::scene::Morph::deform`]) are written
//! to a host-visible staging buffer and copied over the mesh's range of the scene's vertex
//! buffer, before the ray backend refits its structures from them. Raster passes, shading
//! passes and both ray backends read the one vertex buffer, so they all see the same geometry.

use crate::gpu::{Buffer, Context, MemoryLocation, Recorder, vk};
use crate::scene::{Pose, Scene, Vertex};
use anyhow::Result;
use glam::Vec3;
use std::sync::Arc;

pub struct Deformer {
    /// One region per morph of the scene, as large as its mesh's vertices.
    staging: Buffer,
    /// Per morph: byte offset in `staging`, byte offset of the mesh's vertices in the vertex
    /// buffer, bytes.
    regions: Vec<(u64, u64, u64)>,
    /// Per morph: the weights its mesh's vertices were last deformed with.
    applied: Vec<Option<Vec<f32>>>,
    /// Regions written since the last recording (indices into `regions`).
    pending: Vec<usize>,
    /// Acceleration-structure builds read the vertex buffer too.
    ray_query: bool,
}

impl Deformer {
    /// `None` when no mesh of the scene deforms. `base_vertex[m]` is mesh m's first vertex in
    /// the vertex buffer.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, base_vertex: &[i32], ray_query: bool) -> Result<Option<Self>> {
        if scene.morphs.is_empty() {
            return Ok(None);
        }
        let stride = size_of::<Vertex>() as u64;
        let mut regions = Vec::with_capacity(scene.morphs.len());
        let mut total = 0;
        for morph in &scene.morphs {
            let bytes = scene.meshes[morph.mesh as usize].vertices.len() as u64 * stride;
            regions.push((total, base_vertex[morph.mesh as usize] as u64 * stride, bytes));
            total += bytes;
        }
        let staging = Buffer::new(
            ctx,
            "morph vertices (staging)",
            total.max(stride),
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        Ok(Some(Self { staging, regions, applied: vec![None; scene.morphs.len()], pending: Vec::new(), ray_query }))
    }

    /// Deforms the meshes whose weights changed since they were last deformed and stages
    /// their vertices; returns (mesh, deformed positions) for each, for the ray backend.
    pub fn update(&mut self, scene: &Scene, pose: &Pose) -> Result<Vec<(u32, Vec<Vec3>)>> {
        let mut changed = Vec::new();
        for (k, morph) in scene.morphs.iter().enumerate() {
            let weights = morph.weights_at(pose.time);
            if self.applied[k].as_ref() == Some(&weights) {
                continue;
            }
            let vertices = morph.deform(&scene.meshes[morph.mesh as usize].vertices, &weights);
            self.staging.write(self.regions[k].0 as usize, bytemuck::cast_slice(&vertices))?;
            if !self.pending.contains(&k) {
                self.pending.push(k);
            }
            self.applied[k] = Some(weights);
            changed.push((morph.mesh, vertices.iter().map(|v| Vec3::from(v.position)).collect()));
        }
        Ok(changed)
    }

    /// Records the copies of the staged vertices into `vertices`, between barriers: earlier
    /// readers (draws, shaders, acceleration-structure builds) finish before the copy, later
    /// ones see it. Nothing is recorded when nothing was staged.
    pub fn record(&mut self, rec: &Recorder, vertices: &Buffer) {
        if self.pending.is_empty() {
            return;
        }
        let (readers, reads) = vertex_readers(self.ray_query);
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        rec.memory_barrier((readers, reads), transfer);
        let regions: Vec<(u64, u64, u64)> = self.pending.iter().map(|&k| self.regions[k]).collect();
        rec.copy_buffer_regions(&self.staging, vertices, &regions);
        rec.memory_barrier(transfer, (readers, reads));
        self.pending.clear();
    }
}

/// Who reads the scene's vertex buffer, for the barriers around writing it: draws, shaders,
/// and with ray query the acceleration-structure builds.
pub(super) fn vertex_readers(ray_query: bool) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
    let mut stages = vk::PipelineStageFlags2::VERTEX_SHADER
        | vk::PipelineStageFlags2::FRAGMENT_SHADER
        | vk::PipelineStageFlags2::COMPUTE_SHADER;
    if ray_query {
        stages |= vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR;
    }
    (stages, vk::AccessFlags2::SHADER_READ | vk::AccessFlags2::SHADER_STORAGE_READ)
}
