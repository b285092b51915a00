//! Deforming meshes on the GPU: each frame whose morph weights differ from the last frame's,
//! the deformed vertices (evaluated on the CPU, [`crate::scene::Morph::deform`]) are written
//! to a host-visible staging buffer and copied over the mesh's range of the scene's vertex
//! buffer, before the ray backend refits its structures from them. Raster passes, shading
//! passes and both ray backends read the one vertex buffer, so they all see the same geometry.
//! The positions they replace go into the mesh's range of `prev_positions`, where the G-buffer
//! reads where each vertex was last frame (motion vectors), as it does for skinned meshes.

use crate::gpu::{Buffer, Context, MemoryLocation, Recorder, vk};
use crate::scene::{Pose, Scene, Vertex};
use anyhow::Result;
use glam::Vec3;
use std::sync::Arc;

/// Where one morph's data lies: `(staging offset, destination offset, bytes)` for its vertices
/// (into the vertex buffer) and for its last frame's positions (into `prev_positions`).
#[derive(Clone, Copy)]
struct Region {
    vertices: (u64, u64, u64),
    prev: (u64, u64, u64),
}

pub struct Deformer {
    /// One region per morph of the scene, as large as its mesh's vertices and their positions.
    staging: Buffer,
    regions: Vec<Region>,
    /// Per morph: the weights its mesh's vertices were last deformed with.
    applied: Vec<Option<Vec<f32>>>,
    /// Per morph: the positions the vertex buffer holds (from the last deformation).
    positions: Vec<Option<Vec<[f32; 3]>>>,
    /// Per morph: its last deformation moved it, so `prev_positions` differs from the vertex
    /// buffer until a frame that leaves it where it is writes them equal again.
    moving: Vec<bool>,
    /// Morphs whose vertices, and whose last frame's positions, were staged since the last
    /// recording (indices into `regions`).
    pending_vertices: Vec<usize>,
    pending_prev: Vec<usize>,
    /// Acceleration-structure builds read the vertex buffer too.
    ray_query: bool,
}

impl Deformer {
    /// `None` when no mesh of the scene deforms. `base_vertex[m]` is mesh m's first vertex in
    /// the vertex buffer (and in `prev_positions`, one vec3 per vertex).
    pub fn new(ctx: &Arc<Context>, scene: &Scene, base_vertex: &[i32], ray_query: bool) -> Result<Option<Self>> {
        if scene.morphs.is_empty() {
            return Ok(None);
        }
        let (stride, position) = (size_of::<Vertex>() as u64, size_of::<[f32; 3]>() as u64);
        let mut regions = Vec::with_capacity(scene.morphs.len());
        let mut total = 0;
        for morph in &scene.morphs {
            let (count, base) =
                (scene.meshes[morph.mesh as usize].vertices.len() as u64, base_vertex[morph.mesh as usize] as u64);
            let vertices = (total, base * stride, count * stride);
            let prev = (total + count * stride, base * position, count * position);
            regions.push(Region { vertices, prev });
            total += count * (stride + position);
        }
        let staging = Buffer::new(
            ctx,
            "morph vertices (staging)",
            total.max(stride),
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let n = scene.morphs.len();
        Ok(Some(Self {
            staging,
            regions,
            applied: vec![None; n],
            positions: vec![None; n],
            moving: vec![false; n],
            pending_vertices: Vec::new(),
            pending_prev: Vec::new(),
            ray_query,
        }))
    }

    /// Deforms the meshes whose weights changed since they were last deformed and stages
    /// their vertices, and the positions those replace as last frame's; returns (mesh,
    /// deformed positions) for each, for the ray backend. A mesh that moved last frame and
    /// not in this one stages its positions as last frame's: it stands still.
    pub fn update(&mut self, scene: &Scene, pose: &Pose) -> Result<Vec<(u32, Vec<Vec3>)>> {
        let mut changed = Vec::new();
        for (k, morph) in scene.morphs.iter().enumerate() {
            let weights = morph.weights_at(pose.time);
            if self.applied[k].as_ref() == Some(&weights) {
                if self.moving[k] {
                    let now = self.positions[k].as_deref().expect("a moving mesh was deformed");
                    self.staging.write(self.regions[k].prev.0 as usize, bytemuck::cast_slice(now))?;
                    push_once(&mut self.pending_prev, k);
                    self.moving[k] = false;
                }
                continue;
            }
            let vertices = morph.deform(&scene.meshes[morph.mesh as usize].vertices, &weights);
            let now: Vec<[f32; 3]> = vertices.iter().map(|v| v.position).collect();
            // The first deformation has no last frame: it did not move.
            let before = self.positions[k].take().unwrap_or_else(|| now.clone());
            self.staging.write(self.regions[k].vertices.0 as usize, bytemuck::cast_slice(&vertices))?;
            self.staging.write(self.regions[k].prev.0 as usize, bytemuck::cast_slice(&before))?;
            push_once(&mut self.pending_vertices, k);
            push_once(&mut self.pending_prev, k);
            self.moving[k] = before != now;
            changed.push((morph.mesh, now.iter().map(|&p| Vec3::from(p)).collect()));
            self.positions[k] = Some(now);
            self.applied[k] = Some(weights);
        }
        Ok(changed)
    }

    /// Records the copies of the staged vertices into `vertices` and of last frame's positions
    /// into `prev_positions`, between barriers: earlier readers (draws, shaders,
    /// acceleration-structure builds) finish before the copies, later ones see them. Nothing is
    /// recorded when nothing was staged.
    pub fn record(&mut self, rec: &Recorder, vertices: &Buffer, prev_positions: &Buffer) {
        if self.pending_vertices.is_empty() && self.pending_prev.is_empty() {
            return;
        }
        let (readers, reads) = vertex_readers(self.ray_query);
        let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        rec.memory_barrier((readers, reads), transfer);
        let to_vertices: Vec<_> = self.pending_vertices.drain(..).map(|k| self.regions[k].vertices).collect();
        rec.copy_buffer_regions(&self.staging, vertices, &to_vertices);
        let to_prev: Vec<_> = self.pending_prev.drain(..).map(|k| self.regions[k].prev).collect();
        rec.copy_buffer_regions(&self.staging, prev_positions, &to_prev);
        rec.memory_barrier(transfer, (readers, reads));
    }
}

fn push_once(list: &mut Vec<usize>, k: usize) {
    if !list.contains(&k) {
        list.push(k);
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
