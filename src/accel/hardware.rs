//! The ray-query backend: one BLAS per unique mesh (PREFER_FAST_TRACE, compacted when the
//! device reports compacted sizes), one TLAS over all instances, rebuilt when they move.
//! Opaque meshes are flagged opaque; alpha-masked ones are not, so the shader's candidate loop
//! runs the alpha test for them. Deforming meshes' BLASes are built with ALLOW_UPDATE (and
//! so not compacted) and updated in place each frame their vertices move, rebuilt every
//! [`super::REBUILD_EVERY`] updates.

use super::{AccelStats, FIRST_BINDING, Geometry, RayAccel, RefitTimes, rebuild_due, same_instances};
use crate::backend::Backend;
use crate::gpu::{
    AccelStruct, Binding, BindingKind, BlasGeometry, BlasRefit, BlasRefitter, CommandPool, Context, DescriptorSet,
    Recorder, TimestampPool, Tlas, TlasInstance, build_blases,
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
    /// Deforming meshes' geometries, in the order of `refitter`'s scratch regions.
    deforming: Vec<Deforming>,
    deforming_geometries: Vec<BlasGeometry>,
    refitter: Option<BlasRefitter>,
    /// Brackets each frame's bottom-level work; read back at the next recording (the frame
    /// has finished by then) or by `stats`.
    timestamps: Option<TimestampPool>,
    /// The bracketed work not yet read back included a rebuild (`Some(true)`) or only
    /// updates (`Some(false)`).
    timed: Option<bool>,
    times: RefitTimes,
}

struct Deforming {
    mesh: u32,
    /// Updates since the BLAS was last built.
    updates: u32,
    /// What the next `record_update` does to the BLAS (its vertices changed).
    pending: Option<BlasRefit>,
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
                opaque: !scene.materials[mesh.material as usize].rays_test_candidates(),
            })
            .collect();
        // Static meshes are built once for fast tracing and compacted; deforming ones are
        // updated in place, which compaction would not allow.
        let allow_update: Vec<bool> = (0..geometries.len()).map(|i| scene.deforms(i as u32)).collect();
        let deforming: Vec<Deforming> = (0..geometries.len() as u32)
            .filter(|&i| allow_update[i as usize])
            .map(|mesh| Deforming { mesh, updates: 0, pending: None })
            .collect();
        let deforming_geometries: Vec<BlasGeometry> = deforming.iter().map(|d| geometries[d.mesh as usize]).collect();
        let (refitter, timestamps) = if deforming.is_empty() {
            (None, None)
        } else {
            (Some(BlasRefitter::new(ctx, &deforming_geometries)?), Some(TimestampPool::new(ctx, 2)?))
        };
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
            ..Default::default()
        };
        let mut accel = Self {
            blases,
            tlas,
            last_pose: pose.clone(),
            dirty: true,
            stats,
            deforming,
            deforming_geometries,
            refitter,
            timestamps,
            timed: None,
            times: RefitTimes::default(),
        };
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

    fn update_geometry(&mut self, _scene: &Scene, _pose: &Pose, meshes: &[(u32, &[glam::Vec3])]) -> Result<()> {
        // The BLAS reads the deformed vertices from the vertex buffer; only the schedule of
        // updates and rebuilds is kept here.
        for &(mesh, _) in meshes {
            let Some(d) = self.deforming.iter_mut().find(|d| d.mesh == mesh) else {
                anyhow::bail!("mesh {mesh} deformed, but its BLAS was not built for updates");
            };
            if d.pending.is_some() {
                continue; // deformed twice before a recording: one refit covers both
            }
            d.pending = Some(if rebuild_due(&mut d.updates) { BlasRefit::Rebuild } else { BlasRefit::Update });
        }
        self.dirty |= !meshes.is_empty();
        Ok(())
    }

    fn record_update(&mut self, rec: &Recorder) -> Result<()> {
        if let Some(refitter) = &self.refitter {
            let work: Vec<(usize, &AccelStruct, BlasRefit)> = self
                .deforming
                .iter()
                .enumerate()
                .filter_map(|(i, d)| d.pending.map(|what| (i, &self.blases[d.mesh as usize], what)))
                .collect();
            if let (Some(ts), Some(rebuilt)) = (&self.timestamps, self.timed.take())
                && let Some(t) = ts.read_ms(2)
            {
                self.times.add(rebuilt, t[1]);
            }
            let timestamps = self.timestamps.as_ref().filter(|_| !work.is_empty());
            if let Some(ts) = timestamps {
                ts.reset(rec.cmd);
                rec.timestamp(ts, 0);
            }
            refitter.record(rec, &self.deforming_geometries, &work)?;
            if let Some(ts) = timestamps {
                rec.timestamp(ts, 1);
                self.timed = Some(work.iter().any(|w| w.2 == BlasRefit::Rebuild));
            }
            for (_, _, what) in &work {
                match what {
                    BlasRefit::Update => self.stats.blas_refits += 1,
                    BlasRefit::Rebuild => self.stats.blas_rebuilds += 1,
                }
            }
            for d in &mut self.deforming {
                d.pending = None;
            }
        }
        // A TLAS must be rebuilt after any of its BLASes changed.
        if self.dirty {
            self.tlas.record_build(rec)?;
            self.dirty = false;
            self.stats.top_level_rebuilds += 1;
        }
        Ok(())
    }

    fn stats(&self) -> AccelStats {
        let mut stats = self.stats.clone();
        let mut times = self.times;
        if let (Some(ts), Some(rebuilt)) = (&self.timestamps, self.timed)
            && let Some(t) = ts.read_ms(2)
        {
            times.add(rebuilt, t[1]);
        }
        times.fill(&mut stats);
        stats
    }
}
