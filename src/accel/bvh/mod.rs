//! The project's own two-level BVH, traced by the compute-shader ray backend.
//!
//! - **Bottom level**, one tree per mesh in mesh-local space, built once ([`MeshBvh::build`])
//!   and pooled with every other mesh's into one node buffer and one triangle buffer
//!   ([`BlasPool`]); each mesh's references are relative to its own range, so pooling
//!   rewrites nothing.
//! - **Top level** over the instances' world-space boxes ([`Tlas::build`]), rebuilt whenever
//!   instances move: its cost and upload grow with the instance count, not triangles.
//!
//! Both levels use one binned-SAH builder (`build.rs`) and one node format.
//!
//! # GPU layout (std430; every record is whole `vec4` rows)
//!
//! ```glsl
//! struct BvhNode {        // 64 bytes: both children, tested from one fetch
//!     vec4 a_min;         // xyz = child A min, w = floatBitsToUint: child A reference
//!     vec4 a_max;         // xyz = child A max, w = floatBitsToUint: child B reference
//!     vec4 b_min;         // xyz = child B min, w unused
//!     vec4 b_max;         // xyz = child B max, w unused
//! };
//! // reference: bit 31 clear = inner node index (relative to the tree's root);
//! //            bit 31 set   = leaf: bits 27..30 = count - 1, bits 0..26 = first primitive
//! //            (bottom: relative to the mesh's first_triangle; top: instance index).
//! // Node 0 of every tree is its root and is always an inner node; an absent child has
//! // min = +inf, max = -inf (a sign-selected slab test never hits it).
//! struct BvhTriangle {    // 48 bytes, leaf order, mesh-local
//!     vec4 v0;            // w = floatBitsToUint: triangle index in the mesh's index buffer / 3
//!     vec4 v1;
//!     vec4 v2;
//! };
//! struct BvhInstance {    // 128 bytes, top-level leaf order
//!     vec4 world_to_object[3];   // row-major 3x4
//!     vec4 object_to_world[3];   // row-major 3x4 (= VkTransformMatrixKHR)
//!     uint root_node;            // mesh's root in the pooled node buffer
//!     uint first_triangle;       // mesh's first triangle in the pooled triangle buffer
//!     uint custom_index, mask, flags, mesh, material, pad;
//! };
//! ```
//!
//! Buffers: pooled bottom-level nodes ([`BlasPool::nodes`]) and triangles
//! ([`BlasPool::triangles`]), both static; top-level nodes ([`Tlas::nodes`]) and instances
//! ([`Tlas::instances`]), both rewritten when instances move. Top-level leaves index
//! instances. [`traverse`] is the traversal the GLSL must mirror; each level's stack needs at
//! most [`STACK_SIZE`] entries.

mod build;
mod layout;
mod morton;
pub mod rays;
mod scene_bvh;
pub mod traverse;

pub use build::{BINS, BuildOptions};
pub use layout::{
    BlasPool, BvhInstance, BvhNode, BvhTriangle, ChildRef, INSTANCE_ALPHA_TESTED, InstanceDesc, LEAF_BIT,
    LEAF_COUNT_SHIFT, MAX_LEAF_SIZE, MAX_PRIMITIVES, MeshBvh, MeshRange, STACK_SIZE, Tlas,
};
pub use morton::morton_order;
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
