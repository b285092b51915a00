//! The project's own two-level BVH, traced by the compute-shader ray backend.
//!
//! - **Bottom level**, one tree per mesh in mesh-local space, built once ([`MeshBvh::build`])
//!   and pooled with every other mesh's into one run of rows ([`BlasPool`]); each mesh's
//!   references are relative to its own first row, so pooling rewrites nothing.
//!   A deforming mesh's tree is refit in place or rebuilt within rows reserved for it
//!   (`refit.rs`).
//! - **Top level** over the instances' world-space boxes ([`Tlas::build`]), rebuilt whenever
//!   instances move: its cost and upload grow with the instance count, not triangles.
//!
//! Both levels use one binned-SAH builder (`build.rs`) and one node format.
//!
//! # GPU layout: one buffer of `uvec4` rows (std430), every record whole rows
//!
//! ```text
//! row 0                  (top-level root reference, first row of the bottom levels, 0, 0)
//! rows 1..               top-level node and instance records, the root's first; references
//!                        relative to row 0 (one instance: a copy of its mesh's root node
//!                        record follows it, at row 5)
//! rows blas_base..       every mesh's node and triangle records; references relative to
//!                        the mesh's first row (its instances' mesh_base)
//!
//! reference (u32)        kind << 28 | offset: kind 0 = inner node record at row `offset`,
//!                        kind n = leaf of n triangle records (bottom level) or one instance
//!                        record (top level, n = 1) from row `offset`; 0xffffffff = none
//! node (2 rows)          (origin.xyz as f32 bits, ex | ey << 8 | ez << 16 | kind_a << 24 | kind_b << 28)
//!                        (qx, qy, qz, base): q = a_lo | b_lo << 8 | a_hi << 16 | b_hi << 24 per
//!                        axis; plane = origin + q * 2^(e - 127); child A's record(s) at row
//!                        `base`, child B's right after them
//! triangle (3 rows)      (v0.xyz, primitive), (v1.xyz, 0), (v2.xyz, 0): mesh-local f32 bits,
//!                        primitive = triangle index in the mesh's index buffer (offset / 3)
//! instance (4 rows)      world_to_object (3 rows, row-major 3x4),
//!                        (mesh_base, root reference, custom index, mask | flags << 8)
//! ```
//!
//! Child boxes are quantised to bytes, conservatively (see layout.rs): lavapipe pays per
//! 32-bit word a ray loads, so a node costs 8 words for two children, not 14. A mesh small
//! enough for one leaf has no node at all (its root is the leaf). [`traverse`] is the
//! traversal the GLSL must mirror, reading these very rows; each tree is at most
//! [`STACK_SIZE`] inner levels deep, so one stack for both levels needs twice that.

mod build;
mod layout;
mod morton;
pub mod rays;
mod refit;
mod scene_bvh;
pub mod traverse;

pub use build::{BINS, BuildOptions};
pub use layout::{
    BlasPool, BvhInstance, ChildRef, INSTANCE_ALPHA_TESTED, INSTANCE_ROWS, INSTANCE_TRANSLATED, InstanceDesc,
    KIND_SHIFT, MAX_LEAF_SIZE, MeshBvh, MeshRange, NODE_ROWS, NodeRecord, Row, STACK_SIZE, TRIANGLE_ROWS, Tlas,
};
pub use morton::morton_order;
pub use refit::{Refit, reserved_rows};
pub use scene_bvh::instance_descs;
pub use traverse::{Hit, accept_all, any_hit, closest_hit};

/// Both levels: everything the compute backend uploads, and what the CPU traversal reads.
#[derive(Clone, Debug, Default)]
pub struct SceneBvh {
    pub blas: BlasPool,
    pub tlas: Tlas,
}

impl SceneBvh {
    /// Builds the top level over `instances` of the meshes in `blas`.
    pub fn new(blas: BlasPool, instances: &[InstanceDesc]) -> Self {
        let tlas = Tlas::build(&blas, instances);
        Self { blas, tlas }
    }

    /// Rebuilds only the top level, for moved instances.
    pub fn set_instances(&mut self, instances: &[InstanceDesc]) {
        self.tlas = Tlas::build(&self.blas, instances);
    }
}
