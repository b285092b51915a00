//! GPU-ready BVH records (`#[repr(C)]`, Pod, std430-compatible) and the buffers that hold them.
//!
//! Every record is a whole number of 16-byte rows whose fourth word carries an integer, so
//! GLSL can declare each as an array of `vec4`/`uvec4` in a std430 storage buffer and read
//! the integers with `floatBitsToUint(.w)`. See the module docs of [`super`] for the GLSL view.

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Vec3, Vec3A};

/// Deepest traversal stack either level can need. The builder switches to median splits past
/// [`super::build`]'s SAH depth limit so no tree is deeper than this many inner levels.
pub const STACK_SIZE: usize = 64;

/// Set in a child reference when the child is a leaf.
pub const LEAF_BIT: u32 = 1 << 31;
/// Bit position of `count - 1` in a leaf reference.
pub const LEAF_COUNT_SHIFT: u32 = 27;
/// Most primitives one leaf can hold (4 bits of `count - 1`).
pub const MAX_LEAF_SIZE: u32 = 16;
/// Largest first-primitive index a leaf can encode (27 bits), hence the most primitives one
/// tree (one mesh, or the instances of one top level) can hold.
pub const MAX_PRIMITIVES: u32 = 1 << LEAF_COUNT_SHIFT;

/// Instance flag: the instance's material is alpha-tested, so candidate hits go through the
/// alpha callback (in GLSL: the shader's alpha test) before they are accepted.
pub const INSTANCE_ALPHA_TESTED: u32 = 1;

/// A child reference: an inner node index, or a leaf's primitive range.
///
/// Inner: the node's index (relative to the tree's first node). Leaf: `LEAF_BIT |
/// (count - 1) << 27 | first`, `first` relative to the tree's first primitive. One `u32`
/// describes either kind, so the traversal stack holds plain `u32`s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildRef(pub u32);

impl ChildRef {
    /// The root of every tree: inner node 0.
    pub const ROOT: ChildRef = ChildRef(0);

    pub fn inner(node: u32) -> Self {
        debug_assert!(node & LEAF_BIT == 0);
        ChildRef(node)
    }

    pub fn leaf(first: u32, count: u32) -> Self {
        debug_assert!(first < MAX_PRIMITIVES && (1..=MAX_LEAF_SIZE).contains(&count));
        ChildRef(LEAF_BIT | (count - 1) << LEAF_COUNT_SHIFT | first)
    }

    pub fn is_leaf(self) -> bool {
        self.0 & LEAF_BIT != 0
    }

    /// Inner node index (meaningful for inner references only).
    pub fn node(self) -> u32 {
        self.0
    }

    /// Leaf primitive range `first..first + count` (meaningful for leaf references only).
    pub fn leaf_range(self) -> std::ops::Range<u32> {
        let first = self.0 & (MAX_PRIMITIVES - 1);
        let count = ((self.0 >> LEAF_COUNT_SHIFT) & (MAX_LEAF_SIZE - 1)) + 1;
        first..first + count
    }
}

/// Two-wide BVH node, 64 bytes: both children's boxes and references in one fetch.
///
/// Traversal tests both boxes from this one record and descends into the nearer child, so a
/// node is only read when it is entered. Child B of a tree that is a single leaf (or of an
/// empty tree) is [`BvhNode::EMPTY_BOX`] with min > max, which the sign-selected slab test of
/// the traversal always misses; its reference is never read.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub a_min: [f32; 3],
    /// [`ChildRef`] of child A.
    pub a_ref: u32,
    pub a_max: [f32; 3],
    /// [`ChildRef`] of child B.
    pub b_ref: u32,
    pub b_min: [f32; 3],
    pub pad0: u32,
    pub b_max: [f32; 3],
    pub pad1: u32,
}

impl BvhNode {
    /// Bounds that no ray hits: min = +inf, max = -inf.
    pub const EMPTY_BOX: ([f32; 3], [f32; 3]) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

    pub fn new(a: (ChildRef, Vec3A, Vec3A), b: (ChildRef, Vec3A, Vec3A)) -> Self {
        Self {
            a_min: a.1.into(),
            a_ref: a.0.0,
            a_max: a.2.into(),
            b_ref: b.0.0,
            b_min: b.1.into(),
            pad0: 0,
            b_max: b.2.into(),
            pad1: 0,
        }
    }

    /// A root whose child A is `a` and whose child B is empty.
    pub fn single(a: (ChildRef, Vec3A, Vec3A)) -> Self {
        let (lo, hi) = Self::EMPTY_BOX;
        Self::new(a, (ChildRef::leaf(0, 1), Vec3A::from(lo), Vec3A::from(hi)))
    }

    pub fn children(&self) -> [(ChildRef, [f32; 3], [f32; 3]); 2] {
        [(ChildRef(self.a_ref), self.a_min, self.a_max), (ChildRef(self.b_ref), self.b_min, self.b_max)]
    }
}

/// One triangle in leaf order, 48 bytes: the three vertices in mesh-local space, read in one
/// contiguous fetch by the watertight test. `v0[3]` is the original triangle index (index
/// buffer offset / 3) bit-cast to f32; the other `w`s are 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    pub v0: [f32; 4],
    pub v1: [f32; 4],
    pub v2: [f32; 4],
}

impl BvhTriangle {
    pub fn new(primitive: u32, v: [Vec3; 3]) -> Self {
        Self {
            v0: v[0].extend(f32::from_bits(primitive)).into(),
            v1: v[1].extend(0.0).into(),
            v2: v[2].extend(0.0).into(),
        }
    }

    /// Original triangle index in the mesh's index buffer (offset / 3).
    pub fn primitive(&self) -> u32 {
        self.v0[3].to_bits()
    }

    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0, self.v1, self.v2].map(|v| Vec3::new(v[0], v[1], v[2]))
    }
}

/// One instance in top-level leaf order, 128 bytes.
///
/// Matrices are 3x4 row-major (three `vec4` rows, translation in `w`), the layout of
/// `VkTransformMatrixKHR`: `p' = vec3(dot(r0, vec4(p, 1)), dot(r1, ..), dot(r2, ..))`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhInstance {
    pub world_to_object: [[f32; 4]; 3],
    pub object_to_world: [[f32; 4]; 3],
    /// Index of the mesh's root node in the pooled node buffer; the mesh's inner references
    /// are relative to it.
    pub root_node: u32,
    /// Index of the mesh's first triangle in the pooled triangle buffer; the mesh's leaf
    /// ranges are relative to it.
    pub first_triangle: u32,
    /// The instance id reported in hits (`gl_RayQueryGetIntersectionInstanceCustomIndexEXT`).
    pub custom_index: u32,
    /// Low 8 bits: the instance is skipped when `mask & ray_mask == 0`.
    pub mask: u32,
    /// [`INSTANCE_ALPHA_TESTED`] or 0.
    pub flags: u32,
    pub mesh: u32,
    pub material: u32,
    pub pad: u32,
}

impl BvhInstance {
    pub fn new(desc: &InstanceDesc, mesh: &MeshRange) -> Self {
        Self {
            world_to_object: rows(&desc.object_to_world.inverse()),
            object_to_world: rows(&desc.object_to_world),
            root_node: mesh.root_node,
            first_triangle: mesh.first_triangle,
            custom_index: desc.custom_index,
            mask: u32::from(desc.mask),
            flags: if desc.alpha_tested { INSTANCE_ALPHA_TESTED } else { 0 },
            mesh: desc.mesh,
            material: desc.material,
            pad: 0,
        }
    }

    pub fn is_alpha_tested(&self) -> bool {
        self.flags & INSTANCE_ALPHA_TESTED != 0
    }
}

/// Row-major 3x4 form of an affine transform.
pub fn rows(m: &Affine3A) -> [[f32; 4]; 3] {
    let c = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation];
    [0, 1, 2].map(|r| [c[0][r], c[1][r], c[2][r], c[3][r]])
}

/// Applies a row-major 3x4 transform to a point.
pub fn transform_point(m: &[[f32; 4]; 3], p: Vec3) -> Vec3 {
    let r = m.map(|row| row[0] * p.x + row[1] * p.y + row[2] * p.z + row[3]);
    Vec3::from(r)
}

/// Applies the linear part of a row-major 3x4 transform to a direction.
pub fn transform_vector(m: &[[f32; 4]; 3], d: Vec3) -> Vec3 {
    let r = m.map(|row| row[0] * d.x + row[1] * d.y + row[2] * d.z);
    Vec3::from(r)
}

/// What the top level needs to know about one instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceDesc {
    /// Affine object-to-world transform. Non-invertible or non-finite transforms are left out
    /// of the top level (such an instance cannot be hit).
    pub object_to_world: Affine3A,
    /// Index into [`BlasPool::meshes`].
    pub mesh: u32,
    pub custom_index: u32,
    pub mask: u8,
    pub alpha_tested: bool,
    pub material: u32,
}

/// The BVH of one mesh before pooling: nodes with tree-relative references, triangles in
/// leaf order.
#[derive(Clone, Debug, Default)]
pub struct MeshBvh {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    /// Mesh-local bounds of the triangles in the tree (empty box when there are none).
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// Where one mesh's tree lives in the pooled buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshRange {
    pub root_node: u32,
    pub node_count: u32,
    pub first_triangle: u32,
    pub triangle_count: u32,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// All bottom levels, pooled: one node buffer and one triangle buffer for every mesh, so the
/// shader binds two buffers however many meshes there are. Built once per scene.
#[derive(Clone, Debug, Default)]
pub struct BlasPool {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    pub meshes: Vec<MeshRange>,
}

impl BlasPool {
    /// Appends a mesh's tree and returns its mesh id (index into [`Self::meshes`]).
    /// References stay relative to the mesh's range, so nothing is rewritten.
    pub fn push(&mut self, mesh: MeshBvh) -> u32 {
        let range = MeshRange {
            root_node: offset(self.nodes.len()),
            node_count: offset(mesh.nodes.len()),
            first_triangle: offset(self.triangles.len()),
            triangle_count: offset(mesh.triangles.len()),
            bounds_min: mesh.bounds_min,
            bounds_max: mesh.bounds_max,
        };
        // The first mesh's buffers are taken over rather than copied (big single-mesh scenes).
        if self.nodes.is_empty() && self.triangles.is_empty() {
            self.nodes = mesh.nodes;
            self.triangles = mesh.triangles;
        } else {
            self.nodes.extend_from_slice(&mesh.nodes);
            self.triangles.extend_from_slice(&mesh.triangles);
        }
        self.meshes.push(range);
        offset(self.meshes.len() - 1)
    }
}

impl FromIterator<MeshBvh> for BlasPool {
    fn from_iter<I: IntoIterator<Item = MeshBvh>>(iter: I) -> Self {
        let mut pool = Self::default();
        for mesh in iter {
            pool.push(mesh);
        }
        pool
    }
}

/// The top level: a tree over instance world bounds whose leaves index `instances` (in leaf
/// order). Rebuilt whenever instances move; its size grows with instances, not triangles.
#[derive(Clone, Debug, Default)]
pub struct Tlas {
    pub nodes: Vec<BvhNode>,
    pub instances: Vec<BvhInstance>,
}

/// A buffer offset as the `u32` the GPU records hold.
fn offset(n: usize) -> u32 {
    u32::try_from(n).expect("BVH buffer larger than u32 indices can address")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, offset_of, size_of};

    #[test]
    fn records_are_whole_std430_rows() {
        assert_eq!(size_of::<BvhNode>(), 64);
        assert_eq!(size_of::<BvhTriangle>(), 48);
        assert_eq!(size_of::<BvhInstance>(), 128);
        assert_eq!(align_of::<BvhNode>(), 4);
        assert_eq!(offset_of!(BvhNode, a_ref), 12);
        assert_eq!(offset_of!(BvhNode, b_ref), 28);
        assert_eq!(offset_of!(BvhNode, b_min), 32);
        assert_eq!(offset_of!(BvhNode, b_max), 48);
        assert_eq!(offset_of!(BvhInstance, object_to_world), 48);
        assert_eq!(offset_of!(BvhInstance, root_node), 96);
        assert_eq!(offset_of!(BvhInstance, material), 120);
    }

    #[test]
    fn child_refs_round_trip() {
        let leaf = ChildRef::leaf(MAX_PRIMITIVES - 1, MAX_LEAF_SIZE);
        assert!(leaf.is_leaf());
        assert_eq!(leaf.leaf_range(), MAX_PRIMITIVES - 1..MAX_PRIMITIVES - 1 + MAX_LEAF_SIZE);
        assert_eq!(ChildRef::leaf(5, 1).leaf_range(), 5..6);
        let inner = ChildRef::inner(12345);
        assert!(!inner.is_leaf());
        assert_eq!(inner.node(), 12345);
    }

    #[test]
    fn triangle_keeps_primitive_bits() {
        let t = BvhTriangle::new(0x7FC0_0001, [Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(t.primitive(), 0x7FC0_0001);
        assert_eq!(t.vertices(), [Vec3::ZERO, Vec3::X, Vec3::Y]);
        let bytes: &[u8] = bytemuck::bytes_of(&t);
        assert_eq!(&bytes[12..16], &0x7FC0_0001u32.to_ne_bytes());
    }

    #[test]
    fn rows_match_affine() {
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 2.0, 3.0),
            glam::Quat::from_rotation_y(0.7),
            Vec3::new(4.0, 5.0, 6.0),
        );
        let r = rows(&m);
        let p = Vec3::new(0.3, -1.0, 2.0);
        assert!((transform_point(&r, p) - m.transform_point3(p)).length() < 1e-5);
        assert!((transform_vector(&r, p) - m.transform_vector3(p)).length() < 1e-5);
    }
}
