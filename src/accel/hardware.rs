//! The ray-query backend: one BLAS per unique mesh (PREFER_FAST_TRACE, compacted when the
//! device reports compacted sizes), one TLAS over all instances, rebuilt when they move.
//! Opaque meshes are flagged opaque; alpha-masked ones are not, so the shader's candidate loop
//! runs the alpha test for them.

use super::{AccelStats, FIRST_BINDING, Geometry, RayAccel, same_instances};
use crate::backend::Backend;
use crate::gpu::{
    AccelStruct, Binding, BindingKind, BlasGeometry, CommandPool, Context, DescriptorSet, Recorder, Tlas, TlasInstance,
    build_blases,
};
use crate::scene::{Pose, Scene, Vertex};
use anyhow::Result;
use std::sync::Arc;
use std::time::Instant;

pub struct HardwareAccel {
    blases: Vec<AccelStruct>,
    tlas: Tlas,
    last_pose: Pose,
    /// The TLAS must be (re)built before the next trace.
    dirty: bool,
    stats: AccelStats,
}

impl HardwareAccel {
    pub fn new(ctx: &Arc<Context>, pool: &CommandPool, scene: &Scene, pose: &Pose, geo: &Geometry) -> Result<Self> {
        let geometries: Vec<BlasGeometry> = scene
            .meshes
            .iter()
            .zip(&geo.ranges)
            .map(|(mesh, &(first_index, base_vertex))| BlasGeometry {
                // The mesh's vertices are addressed directly rather than through firstVertex:
                // lavapipe (Mesa 25.0) ignores firstVertex for indexed triangles, and the two
                // are equivalent by the spec.
                vertex_address: geo.vertices.address + base_vertex as u64 * size_of::<Vertex>() as u64,
                vertex_stride: size_of::<Vertex>() as u64,
                max_vertex: mesh.vertices.len().saturating_sub(1) as u32,
                first_vertex: 0,
                index_address: geo.indices.address,
                index_offset: first_index * 4,
                triangle_count: mesh.triangle_count() as u32,
                opaque: scene.materials[mesh.material as usize].alpha_mode.cutoff().is_none(),
            })
            .collect();
        // No mesh deforms yet (skinning and morph targets are not loaded), so every BLAS is
        // built once for fast tracing and compacted.
        let allow_update = vec![false; geometries.len()];
        let start = Instant::now();
        let (blases, blas_stats) = build_blases(ctx, pool, &geometries, &allow_update)?;
        let blas_build_ms = start.elapsed().as_secs_f64() * 1e3;
        let tlas = Tlas::new(ctx, scene.instances.len() as u32)?;
        let stats = AccelStats {
            blas_build_ms,
            blas_bytes: blas_stats.final_bytes,
            blas_bytes_uncompacted: blas_stats.built_bytes,
            tlas_bytes: tlas.accel.size,
            upload_bytes_per_update: (scene.instances.len() * 64) as u64,
            top_level_rebuilds: 0,
        };
        let mut accel = Self { blases, tlas, last_pose: pose.clone(), dirty: true, stats };
        accel.write_instances(scene, pose)?;
        Ok(accel)
    }

    fn write_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        let list: Vec<TlasInstance> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(i, inst)| {
                let m = pose.world[inst.node as usize];
                let t = m.transpose().to_cols_array_2d();
                TlasInstance {
                    // Rows of the 3x4 object-to-world matrix: the first three columns of the
                    // transpose.
                    transform: [t[0], t[1], t[2]],
                    custom_index: i as u32,
                    mask: 0xff,
                    blas_address: self.blases[inst.mesh as usize].address,
                }
            })
            .collect();
        self.tlas.write_instances(&list)?;
        self.dirty = true;
        Ok(())
    }
}

impl RayAccel for HardwareAccel {
    fn backend(&self) -> Backend {
        Backend::RayQuery
    }

    fn bindings(&self) -> Vec<Binding> {
        vec![Binding { binding: FIRST_BINDING, kind: BindingKind::AccelerationStructure, count: 1 }]
    }

    fn write_set(&self, set: &DescriptorSet) {
        set.write_acceleration_structure(FIRST_BINDING, self.tlas.accel.raw);
    }

    fn update_instances(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        if same_instances(scene, &self.last_pose, pose) {
            return Ok(());
        }
        self.write_instances(scene, pose)?;
        self.last_pose = pose.clone();
        Ok(())
    }

    fn record_update(&mut self, rec: &Recorder) -> Result<()> {
        if self.dirty {
            self.tlas.record_build(rec)?;
            self.dirty = false;
            self.stats.top_level_rebuilds += 1;
        }
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
