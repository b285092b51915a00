//! The two ray backends behind one trait. Both take the scene's meshes and instances and
//! provide what `shaders-glsl/common/trace.glsl` binds in set 0 (bindings 8 and up):
//!
//! - [`hardware`]: one BLAS per mesh and a TLAS through VK_KHR_acceleration_structure, traced
//!   with VK_KHR_ray_query;
//! - [`compute`]: the project's own BVH ([`bvh`]), built on the CPU, traversed in GLSL.
//!
//! Instances that move only touch the top level: the TLAS is rebuilt, or the top-level BVH is
//! rebuilt on the CPU and re-uploaded (bytes grow with instances, not triangles).
//!
//! Deforming meshes (morph targets) touch their own bottom level too: each frame that moves
//! their vertices refits it (a BLAS update, or a bottom-up refit of the CPU tree) and every
//! [`REBUILD_EVERY`] refits rebuilds it instead; the top level is rebuilt after either.

pub mod bvh;
mod compute;
mod hardware;

use crate::backend::Backend;
use crate::gpu::{Binding, Buffer, CommandPool, Context, DescriptorSet, Recorder};
use crate::scene::{Pose, Scene};
use anyhow::Result;
use std::sync::Arc;

/// First set-0 binding owned by the ray backend.
pub const FIRST_BINDING: u32 = 8;

/// A deforming mesh's bottom level is refit this many times, then rebuilt from scratch. A
/// refit keeps the tree split for the shape it was built for: as the mesh moves away from
/// that shape, sibling boxes overlap more and rays visit more nodes. A rebuild every 16
/// deformed frames (half a second at 30 Hz) bounds that drift while most frames pay only
/// for a refit, which costs a fraction of a build and never moves the tree in memory.
pub const REBUILD_EVERY: u32 = 16;

/// Advances a deforming mesh's count of refits since its last build; true when this
/// deformation must rebuild instead (then the count starts over). Both backends keep the same
/// schedule, so their trees are rebuilt on the same frames.
fn rebuild_due(refits: &mut u32) -> bool {
    *refits += 1;
    if *refits >= REBUILD_EVERY {
        *refits = 0;
        return true;
    }
    false
}

/// Sizes and times of the structures, for `info`, the bench and the logs.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct AccelStats {
    /// Wall time to build all bottom levels (ms).
    pub blas_build_ms: f64,
    /// Device memory of the bottom levels (bytes).
    pub blas_bytes: u64,
    /// Bottom-level bytes before compaction (equal when not compacted).
    pub blas_bytes_uncompacted: u64,
    /// Device memory of the top level (bytes).
    pub tlas_bytes: u64,
    /// Bytes uploaded per top-level rebuild.
    pub upload_bytes_per_update: u64,
    pub top_level_rebuilds: u64,
    /// Bottom levels of deforming meshes refit (BLAS updates, or CPU BVH refits).
    pub blas_refits: u64,
    /// Bottom levels of deforming meshes rebuilt (every [`REBUILD_EVERY`] refits).
    pub blas_rebuilds: u64,
    /// Mean time of a frame's bottom-level refits (ms): GPU time of the BLAS updates, or CPU
    /// time of the BVH refits; 0 before the first.
    pub blas_refit_ms: f64,
    /// Mean time of a frame's bottom-level work that includes a rebuild (ms), measured alike.
    pub blas_rebuild_ms: f64,
}

/// Running means of refit and rebuild times, one sample per frame that did either.
#[derive(Clone, Copy, Debug, Default)]
struct RefitTimes {
    refits: (u64, f64),
    rebuilds: (u64, f64),
}

impl RefitTimes {
    fn add(&mut self, rebuilt: bool, ms: f64) {
        let slot = if rebuilt { &mut self.rebuilds } else { &mut self.refits };
        *slot = (slot.0 + 1, slot.1 + ms);
    }

    fn fill(&self, stats: &mut AccelStats) {
        let mean = |(n, total): (u64, f64)| if n == 0 { 0.0 } else { total / n as f64 };
        stats.blas_refit_ms = mean(self.refits);
        stats.blas_rebuild_ms = mean(self.rebuilds);
    }
}

pub trait RayAccel {
    fn backend(&self) -> Backend;
    /// The set-0 bindings the trace interface reads, from [`FIRST_BINDING`] on.
    fn bindings(&self) -> Vec<Binding>;
    fn write_set(&self, set: &DescriptorSet);
    /// Host side of a new pose: instance transforms changed (no-op when nothing moved).
    fn update_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()>;
    /// Host side of deformed meshes: `meshes` lists each mesh whose vertices changed with its
    /// new positions (already written to the scene's vertex buffer by the time the next
    /// [`Self::record_update`] runs). Their bottom levels are refit, or rebuilt every
    /// [`REBUILD_EVERY`] refits, and the top level follows.
    fn update_geometry(&mut self, scene: &Scene, pose: &Pose, meshes: &[(u32, &[glam::Vec3])]) -> Result<()>;
    /// GPU side: records whatever makes the structures current (bottom-level refits, the TLAS
    /// build).
    fn record_update(&mut self, rec: &Recorder) -> Result<()>;
    fn stats(&self) -> AccelStats;
}

/// The scene's pooled geometry, as uploaded for the raster and shading passes.
pub struct Geometry<'a> {
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    /// Per mesh: first index, base vertex.
    pub ranges: Vec<(u32, i32)>,
}

pub fn create(
    backend: Backend,
    ctx: &Arc<Context>,
    pool: &CommandPool,
    scene: &Scene,
    pose: &Pose,
    geometry: &Geometry,
) -> Result<Box<dyn RayAccel>> {
    Ok(match backend {
        Backend::RayQuery => Box::new(hardware::HardwareAccel::new(ctx, pool, scene, pose, geometry)?),
        Backend::Compute => Box::new(compute::ComputeAccel::new(ctx, pool, scene, pose)?),
    })
}

/// Reorders every mesh's triangles along a Morton curve of their centroids. Both backends see
/// the same order, so their primitive ids agree; lavapipe's BLAS builder, which splits the
/// triangle list by index, needs it to build a usable tree (PLATFORM-NOTES.md).
pub fn sort_triangles_spatially(scene: &mut Scene) {
    for mesh in &mut scene.meshes {
        let positions: Vec<glam::Vec3> = mesh.vertices.iter().map(|v| glam::Vec3::from(v.position)).collect();
        let order = bvh::morton_order(&positions, &mesh.indices);
        let sorted: Vec<u32> = order
            .iter()
            .flat_map(|&t| {
                let i = 3 * t as usize;
                [mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]]
            })
            .collect();
        mesh.indices = sorted;
    }
}

/// Whether two poses place every instance identically (then the top level stays as it is).
fn same_instances(scene: &Scene, a: &Pose, b: &Pose) -> bool {
    scene.instances.iter().all(|i| a.world[i.node as usize] == b.world[i.node as usize])
}
