//! Skinning on the GPU (shaders-glsl/skinning.comp): each frame whose joints moved, every
//! skinned mesh's bind-pose vertices are blended by its joint matrices into the mesh's range of
//! the scene's vertex buffer, and last frame's positions into `prev_positions` for motion
//! vectors, before the ray backend refits its structures. Raster passes, shading passes and
//! both ray backends then read the one vertex buffer.
//!
//! The joint matrices are computed on the CPU (a few per skin, from the pose) and written to a
//! host-visible buffer. The compute backend refits its BVH on the CPU, so for it the positions
//! are skinned on the CPU too ([`crate::scene::SkinnedMesh::skin`], the same formula).

use crate::gpu::{
    Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSet, DescriptorSetLayout, Pipeline, Recorder,
    ShaderLibrary,
    staged::{self, StagedBuffer},
    vk,
};
use crate::scene::{Pose, Scene};
use anyhow::{Result, bail};
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// The pass's one name: the Rust module, the shader, the pipeline.
pub const NAME: &str = "skinning";
/// Threads per group (local_size_x in skinning.comp).
const GROUP: u32 = 64;

/// What one dispatch covers (the push constants of skinning.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Dispatch {
    first_source: u32,
    first_target: u32,
    count: u32,
    first_joint: u32,
    joint_count: u32,
}

pub struct Skinner {
    pipeline: Pipeline,
    _set_layout: DescriptorSetLayout,
    set: DescriptorSet,
    _bind_vertices: Buffer,
    _influences: Buffer,
    /// Per skinned mesh, its joints' matrices this frame then last frame's.
    joints: StagedBuffer,
    dispatches: Vec<Dispatch>,
    /// Per skinned mesh: the (this frame, last frame) matrices last dispatched.
    applied: Vec<Option<(Vec<Mat4>, Vec<Mat4>)>>,
    /// Per skinned mesh: this frame's matrices of the last `update`, last frame's for the next.
    last: Vec<Option<Vec<Mat4>>>,
    pending: Vec<usize>,
    /// Acceleration-structure builds read the vertex buffer too; the compute backend needs
    /// CPU-skinned positions.
    ray_query: bool,
}

impl Skinner {
    /// `None` when no mesh of the scene is skinned. `base_vertex[m]` is mesh m's first vertex
    /// in `vertices`, the scene's vertex buffer; `prev_positions` holds one vec3 per vertex.
    pub fn new(
        ctx: &Arc<Context>,
        pool: &CommandPool,
        shaders: &ShaderLibrary,
        scene: &Scene,
        base_vertex: &[i32],
        (vertices, prev_positions): (&Buffer, &Buffer),
        ray_query: bool,
    ) -> Result<Option<Self>> {
        if scene.skinned.is_empty() {
            return Ok(None);
        }
        let mut bind = Vec::new();
        let mut influences = Vec::new();
        let mut dispatches = Vec::new();
        let mut joints = 0u32;
        for s in &scene.skinned {
            let mesh = &scene.meshes[s.mesh as usize];
            let joint_count = scene.skins[s.skin as usize].joints.len() as u32;
            dispatches.push(Dispatch {
                first_source: bind.len() as u32,
                first_target: base_vertex[s.mesh as usize] as u32,
                count: mesh.vertices.len() as u32,
                first_joint: joints,
                joint_count,
            });
            bind.extend_from_slice(&mesh.vertices);
            influences.extend_from_slice(&s.influences);
            joints += 2 * joint_count;
        }
        let joint_bytes = u64::from(joints) * size_of::<Mat4>() as u64;
        let range = u64::from(ctx.caps.max_storage_buffer_range);
        if joint_bytes > range {
            bail!(
                "{}: the skins' {} joints need {joint_bytes} bytes of joint matrices; this device binds at most {range}",
                scene.source.as_deref().map_or(scene.name.clone(), |p| p.display().to_string()),
                joints / 2
            );
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let bind_vertices = crate::gpu::upload::device_buffer(
            ctx,
            pool,
            "skinning.bind_vertices",
            bytemuck::cast_slice(&bind),
            storage,
        )?;
        let influences_buf = crate::gpu::upload::device_buffer(
            ctx,
            pool,
            "skinning.influences",
            bytemuck::cast_slice(&influences),
            storage,
        )?;
        let joints_buf = StagedBuffer::new(ctx, "skinning.joints", joint_bytes, storage)?;
        let b = |binding| Binding { binding, kind: BindingKind::StorageBuffer, count: 1 };
        let set_layout = DescriptorSetLayout::new(ctx, &[b(0), b(1), b(2), b(3), b(4)], false)?;
        let set = DescriptorSet::new(ctx, &set_layout)?;
        for (binding, buffer) in
            [(0, &bind_vertices), (1, &influences_buf), (2, joints_buf.buffer()), (3, vertices), (4, prev_positions)]
        {
            set.write_buffer(binding, BindingKind::StorageBuffer, buffer);
        }
        let spirv = shaders.get("skinning.comp")?;
        let pipeline = Pipeline::compute(ctx, NAME, &spirv, &[&set_layout], size_of::<Dispatch>() as u32)?;
        let n = scene.skinned.len();
        log::info!("{NAME}: {n} skinned meshes, {} vertices, {} joints, on the GPU", bind.len(), joints / 2);
        Ok(Some(Self {
            pipeline,
            _set_layout: set_layout,
            set,
            _bind_vertices: bind_vertices,
            _influences: influences_buf,
            joints: joints_buf,
            dispatches,
            applied: vec![None; n],
            last: vec![None; n],
            pending: Vec::new(),
            ray_query,
        }))
    }

    /// Writes the joint matrices of the meshes whose joints moved (or stopped moving: their
    /// last-frame positions must catch up) and stages their dispatch; returns (mesh, skinned
    /// positions) for each whose shape changed, for the ray backend and the light table. With
    /// ray query the positions are left empty unless the mesh emits: the BLAS update reads the
    /// GPU's vertices.
    pub fn update(&mut self, scene: &Scene, pose: &Pose) -> Result<Vec<(u32, Vec<Vec3>)>> {
        let mut changed = Vec::new();
        for (k, s) in scene.skinned.iter().enumerate() {
            let now = scene.skins[s.skin as usize].joint_matrices(pose, s.node);
            let before = self.last[k].replace(now.clone()).unwrap_or_else(|| now.clone());
            let pair = (now, before);
            if self.applied[k].as_ref() == Some(&pair) {
                continue;
            }
            let moved = self.applied[k].as_ref().is_none_or(|(a, _)| *a != pair.0);
            let (now, before) = &pair;
            let d = self.dispatches[k];
            let at = d.first_joint as usize * size_of::<Mat4>();
            self.joints.write(at, bytemuck::cast_slice(now))?;
            self.joints.write(at + d.joint_count as usize * size_of::<Mat4>(), bytemuck::cast_slice(before))?;
            if !self.pending.contains(&k) {
                self.pending.push(k);
            }
            if moved {
                let mesh = &scene.meshes[s.mesh as usize];
                // The compute backend refits its BVH from them, and an emissive mesh's light
                // table is built from them; a BLAS update reads the GPU's vertices.
                let positions = if self.ray_query && !scene.materials[mesh.material as usize].is_emissive() {
                    Vec::new()
                } else {
                    s.skin(&mesh.vertices, now).iter().map(|v| Vec3::from(v.position)).collect()
                };
                changed.push((s.mesh, positions));
            }
            self.applied[k] = Some(pair);
        }
        Ok(changed)
    }

    /// Records the staged dispatches between barriers: earlier readers of the vertex buffer
    /// (draws, shaders, acceleration-structure builds) finish before it is written, later ones
    /// see the writes. Nothing is recorded when nothing was staged.
    pub fn record(&mut self, rec: &Recorder) {
        if self.pending.is_empty() {
            return;
        }
        staged::record_copies(rec, &mut [&mut self.joints]);
        let (readers, reads) = super::deform::vertex_readers(self.ray_query);
        let write = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        // Last frame's skinning wrote what this one overwrites: its writes are ordered too.
        rec.memory_barrier((readers, reads | vk::AccessFlags2::SHADER_STORAGE_WRITE), write);
        rec.bind_pipeline(&self.pipeline);
        rec.bind_own_set(&self.pipeline, &self.set);
        for &k in &self.pending {
            let d = self.dispatches[k];
            rec.push_constants(&self.pipeline, bytemuck::bytes_of(&d));
            rec.dispatch(d.count.div_ceil(GROUP), 1, 1);
        }
        rec.memory_barrier(write, (readers, reads));
        self.pending.clear();
    }
}
