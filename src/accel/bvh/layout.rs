//! The packed GPU layout: every record is whole 16-byte rows ([`Row`], a `uvec4` in GLSL) of
//! one buffer, and child boxes are quantised to bytes. See the module docs of [`super`] for
//! the GLSL view.
//!
//! Why so compact: lavapipe (the CPU Vulkan driver this backend must beat) runs 8 shader
//! invocations per AVX2 vector, but a storage-buffer load at a different address per
//! invocation costs a bounds-checked scalar load and a blend per 32-bit word and lane, while
//! arithmetic costs one instruction for all 8 lanes. Words loaded per ray are what a traversal
//! step costs, so nodes trade words for arithmetic: 8 words for two children instead of 14.

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Vec3, Vec3A};

/// One `uvec4` of the packed buffer.
pub type Row = [u32; 4];

/// Entries of the traversal stack, which both levels share: a tree pushes at most one entry
/// per inner level on the way down, so the builder keeps the top level's depth plus the
/// deepest mesh's within this. Small, because lavapipe zero-fills the whole stack of every
/// 8 invocations before they start (8 bytes an entry and invocation).
pub const STACK_SIZE: usize = 64;
/// Most inner levels a mesh's tree has; the top level gets what is left of [`STACK_SIZE`]
/// (at least 20 levels, so at least 2^19 instances).
pub const MESH_DEPTH: u32 = 44;

/// Bit position of a child reference's kind (see [`ChildRef`]).
pub const KIND_SHIFT: u32 = 28;
/// Most primitives one leaf can hold (kind 15 is [`ChildRef::NONE`]'s).
pub const MAX_LEAF_SIZE: u32 = 14;
/// Offsets are 28-bit row counts: a tree (one mesh, or the top level) spans at most this
/// many rows (4 GiB).
pub const MAX_ROWS: u32 = 1 << KIND_SHIFT;

/// Rows of an inner node record.
pub const NODE_ROWS: u32 = 2;
/// Rows of a triangle record.
pub const TRIANGLE_ROWS: u32 = 3;
/// Rows of an instance record (a top-level leaf).
pub const INSTANCE_ROWS: u32 = 4;

/// Instance flag: the instance's material is alpha-tested, so candidate hits go through the
/// alpha callback (in GLSL: the shader's alpha test) before they are accepted.
pub const INSTANCE_ALPHA_TESTED: u32 = 1;
/// Instance flag: `world_to_object` only translates (its 3x3 part is exactly the identity),
/// so the shader moves the ray's origin and keeps the rest of it. The results equal the full
/// transform's: multiplying by exact ones and zeros rounds nothing.
pub const INSTANCE_TRANSLATED: u32 = 2;

/// A child reference: `kind << 28 | offset`. Kind 0 is an inner node whose record starts
/// `offset` rows into the tree; kind `n` in 1..=14 is a leaf of `n` triangle records (bottom
/// level) or one instance record (top level, `n` = 1) starting there. One `u32` describes
/// either, so the traversal stack holds plain `u32`s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildRef(pub u32);

impl ChildRef {
    /// No node: the root of an empty tree.
    pub const NONE: ChildRef = ChildRef(u32::MAX);

    pub fn inner(offset: u32) -> Self {
        debug_assert!(offset < MAX_ROWS);
        ChildRef(offset)
    }

    pub fn leaf(offset: u32, count: u32) -> Self {
        debug_assert!(offset < MAX_ROWS && (1..=MAX_LEAF_SIZE).contains(&count));
        ChildRef(count << KIND_SHIFT | offset)
    }

    pub fn is_leaf(self) -> bool {
        self.kind() != 0 && self != Self::NONE
    }

    /// 0 for an inner node, else the leaf's primitive count.
    pub fn kind(self) -> u32 {
        self.0 >> KIND_SHIFT
    }

    /// First row of the child's record(s), relative to its tree.
    pub fn offset(self) -> u32 {
        self.0 & (MAX_ROWS - 1)
    }
}

/// Rows a child of `kind` takes in a tree whose leaves are `leaf_rows` rows per primitive.
pub fn child_rows(kind: u32, leaf_rows: u32) -> u32 {
    if kind == 0 { NODE_ROWS } else { kind * leaf_rows }
}

/// An axis-aligned box as the traversal sees it.
pub type Bounds = (Vec3, Vec3);

/// Inner node, 2 rows: two children, whose records are adjacent (child A at `base`, child B
/// right after it), with boxes quantised to bytes on a per-axis power-of-two grid anchored at
/// the node's minimum corner (Ylitie, Karras, Laine 2017):
///
/// ```text
/// row 0: origin.x, origin.y, origin.z (f32 bits), ex | ey << 8 | ez << 16 | kind_a << 24 | kind_b << 28
/// row 1: qx, qy, qz, base   with q = a_lo | b_lo << 8 | a_hi << 16 | b_hi << 24 per axis
/// ```
///
/// A plane decodes to `origin + q * 2^(e - 127)`; `q * 2^k` is exact, so the one rounding is
/// the addition, and the builder picks `q` so the decoded box contains the child's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeRecord(pub [Row; 2]);

impl NodeRecord {
    /// Encodes children `(kind, box)` whose records start at `base`.
    pub fn encode(children: [(u32, Vec3A, Vec3A); 2], base: u32) -> Self {
        let origin = children[0].1.min(children[1].1);
        let mut q = [0u32; 3];
        let mut exponents = 0;
        for axis in 0..3 {
            let p = origin[axis];
            let planes = children.map(|(_, lo, hi)| (lo[axis], hi[axis]));
            let (e, [(a_lo, a_hi), (b_lo, b_hi)]) = quantize_axis(p, planes);
            exponents |= e << (8 * axis);
            q[axis] = a_lo | b_lo << 8 | a_hi << 16 | b_hi << 24;
        }
        let kinds = children[0].0 << 24 | children[1].0 << 28;
        let o = origin.to_array().map(f32::to_bits);
        NodeRecord([[o[0], o[1], o[2], exponents | kinds], [q[0], q[1], q[2], base]])
    }

    /// Both children's references (relative to the tree) and decoded boxes, computed exactly
    /// as the shader does; `leaf_rows` as in [`child_rows`].
    pub fn decode(&self, leaf_rows: u32) -> [(ChildRef, Bounds); 2] {
        let [r0, r1] = self.0;
        let origin = Vec3::new(f32::from_bits(r0[0]), f32::from_bits(r0[1]), f32::from_bits(r0[2]));
        let step = Vec3::from_array([0, 1, 2].map(|a| f32::from_bits(((r0[3] >> (8 * a)) & 0xff) << 23)));
        let plane = |shift: u32| {
            let q = Vec3::from_array([0, 1, 2].map(|a| ((r1[a] >> shift) & 0xff) as f32));
            origin + q * step
        };
        let (kind_a, kind_b) = ((r0[3] >> 24) & 0xf, r0[3] >> 28);
        let base = r1[3];
        let a = ChildRef(kind_a << KIND_SHIFT | base);
        let b = ChildRef(kind_b << KIND_SHIFT | (base + child_rows(kind_a, leaf_rows)));
        [(a, (plane(0), plane(16))), (b, (plane(8), plane(24)))]
    }
}

/// `origin + q * step` in f32, as the shader decodes a plane.
fn dequantize(origin: f32, q: u32, step: f32) -> f32 {
    origin + q as f32 * step
}

/// The smallest biased exponent `e` (grid step `2^(e - 127)`, a normal float) whose bytes
/// hold both children's planes on this axis conservatively (lower planes rounded down, upper
/// up, as decoded in f32), and those bytes. `origin` is at most every lower plane.
fn quantize_axis(origin: f32, planes: [(f32, f32); 2]) -> (u32, [(u32, u32); 2]) {
    let top = planes[0].1.max(planes[1].1);
    let extent = f64::from(top) - f64::from(origin);
    let mut e = if extent > 0.0 { ((extent / 255.0).log2().ceil() as i32 + 127).clamp(1, 254) as u32 } else { 1 };
    loop {
        let step = f32::from_bits(e << 23);
        let quantize = |(lo, hi): (f32, f32)| -> Option<(u32, u32)> {
            let grid = |x: f32| (f64::from(x) - f64::from(origin)) / f64::from(step);
            let mut q_lo = grid(lo).floor().clamp(0.0, 255.0) as u32;
            while q_lo > 0 && dequantize(origin, q_lo, step) > lo {
                q_lo -= 1;
            }
            let mut q_hi = grid(hi).ceil().clamp(0.0, 256.0) as u32;
            while q_hi <= 255 && dequantize(origin, q_hi, step) < hi {
                q_hi += 1;
            }
            (q_hi <= 255).then_some((q_lo, q_hi))
        };
        if let (Some(a), Some(b)) = (quantize(planes[0]), quantize(planes[1])) {
            return (e, [a, b]);
        }
        assert!(e < 254, "BVH box too large to quantise");
        e += 1;
    }
}

/// Triangle record, 3 rows: the vertices (mesh-local, f32 bits) and, in row 0's `w`, the
/// triangle's index in the mesh's index buffer (offset / 3).
pub fn triangle_rows(primitive: u32, v: [Vec3; 3]) -> [Row; 3] {
    let row = |p: Vec3, w: u32| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), w];
    [row(v[0], primitive), row(v[1], 0), row(v[2], 0)]
}

/// The primitive index and vertices of the triangle record at `rows[0..3]`.
pub fn read_triangle(rows: &[Row]) -> (u32, [Vec3; 3]) {
    let v = |r: &Row| Vec3::new(f32::from_bits(r[0]), f32::from_bits(r[1]), f32::from_bits(r[2]));
    (rows[0][3], [v(&rows[0]), v(&rows[1]), v(&rows[2])])
}

/// Instance record, 4 rows (64 bytes), a top-level leaf.
///
/// `world_to_object` is 3x4 row-major (three `vec4` rows, translation in `w`):
/// `p' = vec3(dot(r0, vec4(p, 1)), dot(r1, ..), dot(r2, ..))`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhInstance {
    pub world_to_object: [[f32; 4]; 3],
    /// First row of the mesh's tree in the pooled bottom levels ([`BlasPool::rows`]).
    pub mesh_base: u32,
    /// The mesh's root, relative to `mesh_base`.
    pub root: u32,
    /// The instance id reported in hits (`gl_RayQueryGetIntersectionInstanceCustomIndexEXT`).
    pub custom_index: u32,
    /// Bits 0..7: the instance is skipped when `mask & ray_mask == 0`; bit 8 and up: flags
    /// ([`INSTANCE_ALPHA_TESTED`], [`INSTANCE_TRANSLATED`]).
    pub mask_flags: u32,
}

impl BvhInstance {
    pub fn new(desc: &InstanceDesc, mesh: &MeshRange) -> Self {
        let world_to_object = rows(&desc.object_to_world.inverse());
        let identity = (0..3).all(|r| (0..3).all(|c| world_to_object[r][c] == if r == c { 1.0 } else { 0.0 }));
        let flags =
            if desc.alpha_tested { INSTANCE_ALPHA_TESTED } else { 0 } | if identity { INSTANCE_TRANSLATED } else { 0 };
        Self {
            world_to_object,
            mesh_base: mesh.base,
            root: mesh.root.0,
            custom_index: desc.custom_index,
            mask_flags: u32::from(desc.mask) | flags << 8,
        }
    }

    /// The record as rows of the packed buffer.
    pub fn to_rows(self) -> [Row; 4] {
        bytemuck::cast(self)
    }

    /// The record at `rows[0..4]`.
    pub fn read(rows: &[Row]) -> Self {
        bytemuck::cast([rows[0], rows[1], rows[2], rows[3]])
    }

    pub fn mask(&self) -> u32 {
        self.mask_flags & 0xff
    }

    pub fn is_alpha_tested(&self) -> bool {
        (self.mask_flags >> 8) & INSTANCE_ALPHA_TESTED != 0
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
    /// Its candidate hits go through the shaders' hit_alpha_accept (common/hit.glsl): the alpha
    /// test, and shadow rays' passage through see-through surfaces.
    pub alpha_tested: bool,
    pub material: u32,
}

/// The BVH of one mesh before pooling: its rows (node and triangle records, references
/// relative to row 0) and its root.
#[derive(Clone, Debug)]
pub struct MeshBvh {
    pub rows: Vec<Row>,
    /// [`ChildRef::NONE`] for a mesh without triangles; a leaf for one small enough.
    pub root: ChildRef,
    pub triangle_count: u32,
    /// Inner levels on the longest path from the root (0 when the root is a leaf).
    pub depth: u32,
    /// Mesh-local bounds of the triangles in the tree (empty box when there are none).
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// Where one mesh's tree lives in the pooled rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshRange {
    pub base: u32,
    pub root: ChildRef,
    pub rows: u32,
    pub triangle_count: u32,
    pub depth: u32,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// All bottom levels, pooled: one run of rows for every mesh, so the shader binds one buffer
/// however many meshes there are. Built once per scene.
#[derive(Clone, Debug, Default)]
pub struct BlasPool {
    pub rows: Vec<Row>,
    pub meshes: Vec<MeshRange>,
}

impl BlasPool {
    /// Appends a mesh's tree and returns its mesh id (index into [`Self::meshes`]).
    /// References stay relative to the mesh's first row, so nothing is rewritten.
    pub fn push(&mut self, mesh: MeshBvh) -> u32 {
        let range = MeshRange {
            base: offset(self.rows.len()),
            root: mesh.root,
            rows: offset(mesh.rows.len()),
            triangle_count: mesh.triangle_count,
            depth: mesh.depth,
            bounds_min: mesh.bounds_min,
            bounds_max: mesh.bounds_max,
        };
        // The first mesh's rows are taken over rather than copied (big single-mesh scenes).
        if self.rows.is_empty() {
            self.rows = mesh.rows;
        } else {
            self.rows.extend_from_slice(&mesh.rows);
        }
        self.meshes.push(range);
        offset(self.meshes.len() - 1)
    }

    /// Every triangle of a mesh as (primitive index, vertices), in leaf order.
    pub fn triangles(&self, mesh: u32) -> Vec<(u32, [Vec3; 3])> {
        let m = &self.meshes[mesh as usize];
        let rows = &self.rows[m.base as usize..(m.base + m.rows) as usize];
        let mut out = Vec::with_capacity(m.triangle_count as usize);
        for leaf in leaves(rows, m.root, TRIANGLE_ROWS) {
            for t in 0..leaf.kind() {
                let at = (leaf.offset() + t * TRIANGLE_ROWS) as usize;
                out.push(read_triangle(&rows[at..]));
            }
        }
        out
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

/// The leaves under `root` (depth first, A before B) of a tree whose leaves are `leaf_rows`
/// rows per primitive.
pub fn leaves(rows: &[Row], root: ChildRef, leaf_rows: u32) -> Vec<ChildRef> {
    let mut out = Vec::new();
    let mut todo = vec![root];
    while let Some(r) = todo.pop() {
        if r == ChildRef::NONE {
            continue;
        }
        if r.is_leaf() {
            out.push(r);
            continue;
        }
        let at = r.offset() as usize;
        let [a, b] = NodeRecord([rows[at], rows[at + 1]]).decode(leaf_rows);
        todo.extend([b.0, a.0]);
    }
    out
}

/// The top level: row 0 holds the root reference (and, on the GPU, where the bottom levels
/// start); node and instance records follow, references relative to row 0, the root's record
/// first (at row 1). A top level of one instance also holds a copy of its mesh's root node
/// record at row 5. Rebuilt whenever instances move; its size grows with instances, not
/// triangles.
#[derive(Clone, Debug)]
pub struct Tlas {
    pub rows: Vec<Row>,
    /// Inner levels on the longest path from the root.
    pub depth: u32,
    /// The instances in the tree, in leaf (record) order.
    pub instances: Vec<InstanceDesc>,
}

impl Default for Tlas {
    fn default() -> Self {
        Self { rows: vec![[ChildRef::NONE.0, 0, 0, 0]], depth: 0, instances: Vec::new() }
    }
}

impl Tlas {
    pub fn root(&self) -> ChildRef {
        ChildRef(self.rows[0][0])
    }

    /// Rows the top level of `instances` instances can take: row 0, fewer than n inner
    /// nodes (or, for one instance, the copied mesh root) and n instance records.
    pub fn rows_for(instances: usize) -> usize {
        1 + instances.max(1) * (NODE_ROWS + INSTANCE_ROWS) as usize
    }
}

/// A buffer offset as the `u32` the GPU records hold.
fn offset(n: usize) -> u32 {
    u32::try_from(n).ok().filter(|&n| n < MAX_ROWS).expect("BVH buffer larger than 28-bit row offsets address")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::rays::SplitMix64;
    use std::mem::{offset_of, size_of};

    #[test]
    fn records_are_whole_rows() {
        assert_eq!(size_of::<BvhInstance>(), 16 * INSTANCE_ROWS as usize);
        assert_eq!(offset_of!(BvhInstance, mesh_base), 48);
        assert_eq!(offset_of!(BvhInstance, mask_flags), 60);
    }

    #[test]
    fn child_refs_round_trip() {
        let leaf = ChildRef::leaf(MAX_ROWS - 1, MAX_LEAF_SIZE);
        assert!(leaf.is_leaf() && !ChildRef::NONE.is_leaf());
        assert_eq!((leaf.offset(), leaf.kind()), (MAX_ROWS - 1, MAX_LEAF_SIZE));
        let inner = ChildRef::inner(12345);
        assert!(!inner.is_leaf());
        assert_eq!(inner.offset(), 12345);
    }

    #[test]
    fn quantised_boxes_contain_the_originals() {
        let mut rng = SplitMix64::new(5);
        let mut v = |scale: f32| Vec3A::new(rng.unit(), rng.unit(), rng.unit()) * scale - scale * 0.5;
        for i in 0..20_000 {
            // Wide and tiny boxes, far from and near the origin, flat ones, touching ones.
            let scale = [1e-6, 1e-3, 1.0, 1e4, 1e20][i % 5];
            let centre = v(1e3) * if i % 7 == 0 { 0.0 } else { 1.0 };
            let (a0, a1, b0, b1) = (centre + v(scale), centre + v(scale), centre + v(scale), centre + v(scale));
            let mut a = (a0.min(a1), a0.max(a1));
            let b = if i % 3 == 0 { a } else { (b0.min(b1), b0.max(b1)) };
            if i % 11 == 0 {
                a.1.y = a.0.y;
            }
            let node = NodeRecord::encode([(0, a.0, a.1), (3, b.0, b.1)], 77);
            let [(ra, (alo, ahi)), (rb, (blo, bhi))] = node.decode(TRIANGLE_ROWS);
            assert_eq!((ra, rb), (ChildRef::inner(77), ChildRef::leaf(77 + NODE_ROWS, 3)));
            for (lo, hi, orig) in [(alo, ahi, a), (blo, bhi, b)] {
                assert!(lo.cmple(Vec3::from(orig.0)).all() && hi.cmpge(Vec3::from(orig.1)).all(), "{i}: {orig:?}");
                // Loose by at most a few grid steps of the node's extent.
                let extent = (a.1.max(b.1) - a.0.min(b.0)).max_element();
                let slack = (Vec3::from(orig.0) - lo).max(hi - Vec3::from(orig.1)).max_element();
                assert!(slack <= extent / 64.0 + 1e-30 || extent == 0.0, "{i}: slack {slack} of {extent}");
            }
        }
    }

    #[test]
    fn triangle_keeps_primitive_bits() {
        let rows = triangle_rows(0x7FC0_0001, [Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(read_triangle(&rows), (0x7FC0_0001, [Vec3::ZERO, Vec3::X, Vec3::Y]));
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
