//! Binned SAH builder, shared by the bottom levels (triangles) and the top level (instances).
//!
//! Splits are chosen with the surface area heuristic over [`BINS`] bins of primitive centroids,
//! evaluated on all three axes: binning only the widest axis gave a 4% worse SAH cost, 25%
//! fewer CPU rays/s on a sphere, and was no faster to build (the three axes share one pass).
//! Leaves are made when the SAH says a leaf is cheaper than the best split and the node holds
//! at most `max_leaf_size` primitives. Subtrees above [`PARALLEL_MIN`] primitives are built on
//! separate threads (`std::thread::scope`), each into its own node vector that is appended
//! afterwards in the same depth-first order a serial build would produce: the output does not
//! depend on the thread count. The binary tree is then packed into rows ([`pack`]): records
//! depth first, each node's two children adjacent, boxes quantised.

use super::layout::{
    BlasPool, BvhInstance, ChildRef, INSTANCE_ROWS, InstanceDesc, MAX_LEAF_SIZE, MAX_ROWS, MESH_DEPTH, MeshBvh,
    NODE_ROWS, NodeRecord, Row, STACK_SIZE, TRIANGLE_ROWS, Tlas, child_rows, triangle_rows,
};
use glam::{UVec3, Vec3, Vec3A, Vec4};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Centroid bins per axis. Measured SAH cost (1.3M-triangle sphere / 1M-triangle soup):
/// 8 bins 51.37 / 281.8, 16 bins 51.00 / 279.6, 32 bins 50.80 / 278.4; build-time differences
/// were within the noise of this shared machine. 16 takes most of the gain; nodes with fewer
/// primitives than bins use one bin per primitive.
pub const BINS: usize = 16;

/// Most primitives one tree can hold: every triangle record must be addressable by a 28-bit
/// row offset.
const MAX_PRIMITIVES: u32 = MAX_ROWS / TRIANGLE_ROWS;

/// Subtrees with fewer primitives are built on the current thread: below this, spawning
/// costs more than it saves.
const PARALLEL_MIN: usize = 16 * 1024;

/// Builder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Most primitives per leaf, 1..=[`MAX_LEAF_SIZE`] (the leaf encoding's limit).
    pub max_leaf_size: u32,
    /// SAH cost of entering a node (its two box tests), relative to one primitive test.
    pub traversal_cost: f32,
    /// Threads to build with; 0 = all available cores.
    pub threads: usize,
    /// Most inner levels the tree may have. Nodes `max_depth - log2(n)` levels down (n
    /// primitives, log rounded up) and deeper use median splits, which halve the primitive
    /// count, so even a degenerate input whose SAH splits peel off one primitive at a time
    /// stays within it.
    pub max_depth: u32,
}

impl BuildOptions {
    /// Bottom levels (triangles). Traversal cost 1.5: a node costs a 64-byte fetch and two
    /// box tests against a 48-byte fetch and one watertight test per triangle. On the CPU,
    /// costs 1, 1.5 and 2 traced at the same rate within noise while 1.5 has 29% fewer nodes
    /// than 1 (faster build, smaller buffers); SAH-chosen leaves then average ~2.4 triangles.
    /// The cap of 8 bounds the leaf loop's length (warp divergence on the GPU).
    pub const MESH: Self = Self { max_leaf_size: 8, traversal_cost: 1.5, threads: 0, max_depth: MESH_DEPTH };
    /// Top level (instances): entering an instance costs a ray transform plus a root fetch,
    /// far more than a box test, so every instance gets its own leaf box (and the layout
    /// needs it: a top-level leaf is one instance record).
    /// [`Tlas::build`] gives it the depth the meshes leave.
    pub const INSTANCES: Self = Self { max_leaf_size: 1, traversal_cost: 1.0, threads: 1, max_depth: MESH_DEPTH };
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self::MESH
    }
}

/// An axis-aligned box; `EMPTY` is inverted so that growing it by anything gives that thing.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Aabb {
    lo: Vec3A,
    hi: Vec3A,
}

impl Aabb {
    const EMPTY: Self = Self { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    fn union(mut self, other: &Self) -> Self {
        self.grow(other.lo, other.hi);
        self
    }

    /// Half the surface area (the SAH only compares ratios); 0 for empty or flat boxes.
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive's bounds plus its index in the caller's primitive list, packed into 32 bytes
/// (the index rides in `lo.w`): the upper levels of a big build stream the whole array
/// several times, so its size is most of their cost. SIMD arithmetic also runs on the `w`
/// lane, so the index bits are offset by [`INDEX_TAG`] to read as a normal float: a raw index
/// would be a subnormal, which stalls every add on some CPUs.
#[derive(Clone, Copy, Debug)]
struct Primitive {
    lo: Vec4,
    hi: Vec4,
}

impl Primitive {
    fn new(lo: Vec3A, hi: Vec3A, index: u32) -> Self {
        Self { lo: lo.extend(f32::from_bits(index | INDEX_TAG)), hi: hi.extend(0.0) }
    }

    fn lo(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    fn hi(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }

    fn index(&self) -> u32 {
        self.lo.w.to_bits() & !INDEX_TAG
    }

    /// Twice the centroid: binning works in doubled-centroid space to save a multiply.
    fn centroid2(&self) -> Vec3A {
        self.lo() + self.hi()
    }
}

/// Exponent bit that makes `index | INDEX_TAG` (index < 2^27) the bits of a float in [2, 2^17).
const INDEX_TAG: u32 = 1 << 30;

/// Bounds of a primitive set and of its (doubled) centroids.
#[derive(Clone, Copy, Debug)]
struct Extent {
    bounds: Aabb,
    centroids: Aabb,
}

impl Extent {
    const EMPTY: Self = Self { bounds: Aabb::EMPTY, centroids: Aabb::EMPTY };

    fn grow(&mut self, p: &Primitive) {
        self.bounds.grow(p.lo(), p.hi());
        let c = p.centroid2();
        self.centroids.grow(c, c);
    }

    fn of(prims: &[Primitive]) -> Self {
        let mut extent = Self::EMPTY;
        for p in prims {
            extent.grow(p);
        }
        extent
    }
}

/// A child in the binary tree the builder makes before packing: an inner node (index into
/// [`Tree::nodes`]) or a leaf's range of [`Tree::order`].
#[derive(Clone, Copy, Debug, PartialEq)]
enum Child {
    Inner(u32),
    Leaf { first: u32, count: u32 },
}

impl Child {
    /// The kind a [`ChildRef`] to it has.
    fn kind(self) -> u32 {
        match self {
            Child::Inner(_) => 0,
            Child::Leaf { count, .. } => count,
        }
    }
}

/// An inner node of the built tree: both children and their boxes.
#[derive(Clone, Copy, Debug)]
struct BuildNode {
    children: [(Child, Aabb); 2],
}

/// A built tree: nodes (depth first, children before grandchildren of later siblings) and the
/// primitive indices in leaf order (leaf ranges index this list).
struct Tree {
    nodes: Vec<BuildNode>,
    order: Vec<u32>,
    bounds: Aabb,
    /// `None` for an empty tree; a leaf when every primitive fits in one.
    root: Option<Child>,
}

/// Builds a tree over primitive boxes. Primitives with non-finite bounds must be filtered out
/// by the caller.
fn build_tree(mut prims: Vec<Primitive>, options: &BuildOptions) -> Tree {
    assert!((1..=MAX_LEAF_SIZE).contains(&options.max_leaf_size), "max_leaf_size must be 1..={MAX_LEAF_SIZE}");
    assert!(prims.len() <= MAX_PRIMITIVES as usize, "too many primitives for one BVH");
    let threads = match options.threads {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    };
    // Two levels of tasks more than cores so that uneven SAH splits still keep all cores busy.
    let spawn_depth = if threads > 1 { threads.next_power_of_two().trailing_zeros() + 2 } else { 0 };
    let median_levels = prims.len().next_power_of_two().trailing_zeros();
    assert!(
        median_levels <= options.max_depth,
        "{} primitives need more than {} levels",
        prims.len(),
        options.max_depth
    );
    let sah_depth = options.max_depth - median_levels;
    let builder = Builder { options, spawn_depth, sah_depth };
    let extent = Extent::of(&prims);
    // A tree of n primitives has at most n - 1 inner nodes; reserving that much avoids
    // regrowing, and pages never written cost nothing.
    let mut nodes = Vec::with_capacity(prims.len());
    let root = (!prims.is_empty()).then(|| builder.node(&mut prims, 0, 0, extent, &mut nodes));
    Tree { nodes, order: prims.iter().map(Primitive::index).collect(), bounds: extent.bounds, root }
}

/// Lays `tree` out as rows after `rows` (the top level keeps its row 0 there): every node's
/// record is followed, eventually, by its two children's records side by side (child A's
/// subtree first), so a node names both with one offset. `leaf_rows` rows per primitive;
/// `write_leaf(records, first, count)` fills a leaf's records for `order[first..first +
/// count]`. Returns the rows, the root's reference and the tree's depth (inner levels).
fn pack(
    tree: &Tree,
    mut rows: Vec<Row>,
    leaf_rows: u32,
    mut write_leaf: impl FnMut(&mut [Row], u32, u32),
) -> (Vec<Row>, ChildRef, u32) {
    let Some(root) = tree.root else {
        return (rows, ChildRef::NONE, 0);
    };
    // Appends room for a child's record(s) and returns its reference.
    let reserve = |rows: &mut Vec<Row>, child: Child| {
        let at = u32::try_from(rows.len()).ok().filter(|&n| n < MAX_ROWS).expect("BVH too large for row offsets");
        rows.resize(rows.len() + child_rows(child.kind(), leaf_rows) as usize, [0; 4]);
        match child {
            Child::Inner(_) => ChildRef::inner(at),
            Child::Leaf { count, .. } => ChildRef::leaf(at, count),
        }
    };
    let root_ref = reserve(&mut rows, root);
    let mut depth = 0;
    // (child, its reference, inner levels above it)
    let mut todo = vec![(root, root_ref, 0)];
    while let Some((child, at, level)) = todo.pop() {
        let start = at.offset() as usize;
        match child {
            Child::Leaf { first, count } => {
                write_leaf(&mut rows[start..start + (count * leaf_rows) as usize], first, count);
            }
            Child::Inner(i) => {
                let [(a, a_box), (b, b_box)] = tree.nodes[i as usize].children;
                let (a_ref, b_ref) = (reserve(&mut rows, a), reserve(&mut rows, b));
                let node = NodeRecord::encode(
                    [(a.kind(), a_box.lo, a_box.hi), (b.kind(), b_box.lo, b_box.hi)],
                    a_ref.offset(),
                );
                rows[start..start + NODE_ROWS as usize].copy_from_slice(&node.0);
                depth = depth.max(level + 1);
                // Child A's subtree is laid out first (popped first), then B's.
                todo.extend([(b, b_ref, level + 1), (a, a_ref, level + 1)]);
            }
        }
    }
    (rows, root_ref, depth)
}

struct Builder<'a> {
    options: &'a BuildOptions,
    spawn_depth: u32,
    /// Nodes at this depth and deeper split at the median (see [`BuildOptions::max_depth`]).
    sah_depth: u32,
}

/// A chosen SAH split: primitives whose centroid bin on `axis` is below `bin` go left.
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    bin: u32,
    /// Sum over both sides of half-area * count.
    cost: f32,
}

/// Maps doubled centroids to bin indices for one node.
struct Binning {
    origin: Vec3A,
    scale: Vec3A,
    /// Bins in use: [`BINS`], or fewer for nodes with fewer primitives, where more bins than
    /// primitives add sweep work but hardly any useful split candidates.
    count: usize,
}

impl Binning {
    fn new(centroids: &Aabb, primitives: usize) -> Self {
        let count = primitives.clamp(2, BINS);
        let size = centroids.hi - centroids.lo;
        // A flat axis gets scale 0: everything lands in bin 0 and that axis offers no split.
        let scale = Vec3A::select(size.cmpgt(Vec3A::ZERO), count as f32 / size, Vec3A::ZERO);
        Self { origin: centroids.lo, scale, count }
    }

    fn bins(&self, p: &Primitive) -> UVec3 {
        let last = UVec3::splat(self.count as u32 - 1);
        ((p.centroid2() - self.origin) * self.scale).as_uvec3().min(last)
    }

    /// `bins(p)[axis]`, computed with the same operations so the two always agree.
    fn bin(&self, p: &Primitive, axis: usize) -> u32 {
        let b = (p.centroid2()[axis] - self.origin[axis]) * self.scale[axis];
        (b as u32).min(self.count as u32 - 1)
    }
}

impl Builder<'_> {
    /// Builds the subtree over `prims` (which start at `first` in the final leaf order) and
    /// returns it; inner nodes are appended to `out` depth-first.
    fn node(&self, prims: &mut [Primitive], first: u32, depth: u32, extent: Extent, out: &mut Vec<BuildNode>) -> Child {
        let n = prims.len();
        let split = if depth < self.sah_depth { self.find_split(prims, &extent) } else { None };
        if n <= self.options.max_leaf_size as usize {
            let area = extent.bounds.half_area();
            let leaf_cost = n as f32 * area;
            let split_cheaper = split.is_some_and(|s| self.options.traversal_cost * area + s.cost < leaf_cost);
            if !split_cheaper {
                return Child::Leaf { first, count: n as u32 };
            }
        }
        let (mid, [left_extent, right_extent]) = match split {
            Some(s) => partition(prims, &Binning::new(&extent.centroids, n), s),
            None => {
                let mid = median_split(prims, &extent.centroids);
                (mid, [Extent::of(&prims[..mid]), Extent::of(&prims[mid..])])
            }
        };
        assert!(0 < mid && mid < n, "BVH split left a side empty");
        let (left, right) = prims.split_at_mut(mid);
        let at = out.len();
        let placeholder = (Child::Inner(0), Aabb::EMPTY);
        out.push(BuildNode { children: [placeholder; 2] });
        let right_first = first + mid as u32;
        let (a, b) = if depth < self.spawn_depth && n >= PARALLEL_MIN {
            std::thread::scope(|s| {
                let task = s.spawn(|| {
                    let mut nodes = Vec::with_capacity(right.len());
                    let r = self.node(right, right_first, depth + 1, right_extent, &mut nodes);
                    (r, nodes)
                });
                let a = self.node(left, first, depth + 1, left_extent, out);
                let (b, nodes) = task.join().expect("BVH build thread panicked");
                (a, append_rebased(out, nodes, b))
            })
        } else {
            let a = self.node(left, first, depth + 1, left_extent, out);
            let b = self.node(right, right_first, depth + 1, right_extent, out);
            (a, b)
        };
        out[at] = BuildNode { children: [(a, left_extent.bounds), (b, right_extent.bounds)] };
        Child::Inner(at as u32)
    }

    /// Best binned SAH split over all three axes, or `None` when every centroid falls in
    /// one bin on every axis (e.g. all centroids equal).
    fn find_split(&self, prims: &[Primitive], extent: &Extent) -> Option<Split> {
        let binning = Binning::new(&extent.centroids, prims.len());
        let bins = binning.count;
        let mut bounds = [[Aabb::EMPTY; BINS]; 3];
        let mut counts = [[0u32; BINS]; 3];
        for p in prims {
            let b = binning.bins(p);
            for axis in 0..3 {
                let i = b[axis] as usize;
                bounds[axis][i].grow(p.lo(), p.hi());
                counts[axis][i] += 1;
            }
        }
        let mut best: Option<Split> = None;
        for axis in 0..3 {
            // Suffix sweep: what lies right of each plane; then a prefix sweep over planes.
            let mut right_cost = [0.0f32; BINS];
            let mut right_count = [0u32; BINS];
            let mut acc = Aabb::EMPTY;
            let mut count = 0;
            for i in (1..bins).rev() {
                acc = acc.union(&bounds[axis][i]);
                count += counts[axis][i];
                right_cost[i] = acc.half_area() * count as f32;
                right_count[i] = count;
            }
            let mut acc = Aabb::EMPTY;
            let mut count = 0;
            for i in 1..bins {
                acc = acc.union(&bounds[axis][i - 1]);
                count += counts[axis][i - 1];
                if count == 0 || right_count[i] == 0 {
                    continue; // not a split
                }
                let cost = acc.half_area() * count as f32 + right_cost[i];
                if best.is_none_or(|b| cost < b.cost) {
                    best = Some(Split { axis, bin: i as u32, cost });
                }
            }
        }
        best
    }
}

/// Moves primitives left of the split plane to the front; returns how many there are and
/// the extents of both sides, measured in the same pass. Branch-free (every element is
/// swapped, the cursor advances by 0 or 1, the side's extent is picked by index): which side
/// a primitive goes to is unpredictable, and mispredictions cost more than the extra swaps.
fn partition(prims: &mut [Primitive], binning: &Binning, split: Split) -> (usize, [Extent; 2]) {
    let mut sides = [Extent::EMPTY; 2];
    let mut left = 0;
    for i in 0..prims.len() {
        let p = prims[i];
        let goes_left = binning.bin(&p, split.axis) < split.bin;
        sides[usize::from(!goes_left)].grow(&p);
        prims.swap(left, i);
        left += usize::from(goes_left);
    }
    (left, sides)
}

/// Splits at the median centroid of the widest centroid axis; used where SAH gives no split
/// (all centroids in one bin) or the depth limit is reached. Always leaves both sides
/// non-empty, so recursion terminates even when every centroid is equal.
fn median_split(prims: &mut [Primitive], centroids: &Aabb) -> usize {
    let axis = (centroids.hi - centroids.lo).max_position();
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
    mid
}

/// Appends a subtree built into its own vector, shifting its inner references by where it
/// lands; returns the subtree root, shifted likewise.
fn append_rebased(out: &mut Vec<BuildNode>, nodes: Vec<BuildNode>, root: Child) -> Child {
    let base = out.len() as u32;
    let shift = |c: Child| match c {
        Child::Inner(i) => Child::Inner(i + base),
        leaf => leaf,
    };
    out.extend(nodes.into_iter().map(|n| BuildNode { children: n.children.map(|(c, b)| (shift(c), b)) }));
    shift(root)
}

impl MeshBvh {
    /// Builds the bottom level of one mesh (mesh-local space). Triangles with an index out of
    /// range or a non-finite vertex are left out (they could never be hit); zero-area
    /// triangles are kept and simply never report a hit.
    pub fn build(positions: &[Vec3], indices: &[u32], options: &BuildOptions) -> Self {
        let triangle = |t: usize| -> Option<[Vec3; 3]> {
            let i = indices.get(3 * t..3 * t + 3)?;
            let v = [positions.get(i[0] as usize)?, positions.get(i[1] as usize)?, positions.get(i[2] as usize)?];
            v.iter().all(|p| p.is_finite()).then(|| v.map(|p| *p))
        };
        let count = indices.len() / 3;
        let mut prims = Vec::with_capacity(count);
        prims.extend((0..count).filter_map(|t| {
            let [a, b, c] = triangle(t)?.map(Vec3A::from);
            Some(Primitive::new(a.min(b).min(c), a.max(b).max(c), t as u32))
        }));
        if prims.len() < count {
            log::warn!("BVH: left out {} invalid triangles of {count}", count - prims.len());
        }
        let triangle_count = prims.len() as u32;
        let tree = build_tree(prims, options);
        let (rows, root, depth) = pack(&tree, Vec::new(), TRIANGLE_ROWS, |records, first, count| {
            for (i, &t) in tree.order[first as usize..(first + count) as usize].iter().enumerate() {
                let v = triangle(t as usize).expect("validated above");
                records[i * 3..i * 3 + 3].copy_from_slice(&triangle_rows(t, v));
            }
        });
        let (bounds_min, bounds_max) = if root == ChildRef::NONE {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (tree.bounds.lo.into(), tree.bounds.hi.into())
        };
        Self { rows, root, triangle_count, depth, bounds_min, bounds_max }
    }
}

impl BlasPool {
    /// Builds `count` meshes' bottom levels with `build(i)` on all cores, a mesh per task (a
    /// typical scene has many meshes below the size where one build splits over threads),
    /// and pools them in index order, so mesh `i` gets id `i`.
    pub fn build(count: usize, build: impl Fn(usize) -> MeshBvh + Sync) -> Self {
        let threads = std::thread::available_parallelism().map_or(1, usize::from);
        let next = AtomicUsize::new(0);
        let work = || {
            let mut built = Vec::new();
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= count {
                    return built;
                }
                built.push((i, build(i)));
            }
        };
        let mut built: Vec<(usize, MeshBvh)> = std::thread::scope(|s| {
            let helpers: Vec<_> = (1..threads).map(|_| s.spawn(work)).collect();
            let mut built = work();
            for h in helpers {
                built.extend(h.join().expect("BVH build thread panicked"));
            }
            built
        });
        built.sort_unstable_by_key(|(i, _)| *i);
        built.into_iter().map(|(_, mesh)| mesh).collect()
    }
}

impl Tlas {
    /// Builds the top level over the instances' world bounds (the mesh bounds' corners
    /// transformed). Instances of empty meshes, and with non-invertible or non-finite
    /// transforms, are left out: they cannot be hit.
    pub fn build(blas: &BlasPool, instances: &[InstanceDesc]) -> Self {
        let mut descs = Vec::with_capacity(instances.len());
        let mut prims = Vec::with_capacity(instances.len());
        for desc in instances {
            let mesh = &blas.meshes[desc.mesh as usize];
            let m = &desc.object_to_world;
            let det = m.matrix3.determinant();
            if mesh.triangle_count == 0 || !m.is_finite() || det == 0.0 || !det.is_finite() {
                continue;
            }
            let mut world = Aabb::EMPTY;
            for corner in 0..8 {
                let pick = |bit: u32, lo: f32, hi: f32| if corner & bit == 0 { lo } else { hi };
                let (lo, hi) = (mesh.bounds_min, mesh.bounds_max);
                let local = Vec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z));
                let p = Vec3A::from(m.transform_point3(local));
                world.grow(p, p);
            }
            prims.push(Primitive::new(world.lo, world.hi, descs.len() as u32));
            descs.push(*desc);
        }
        // The traversal stack holds the top level's entries below the deepest mesh's.
        let mesh_depth = descs.iter().map(|d| blas.meshes[d.mesh as usize].depth).max().unwrap_or(0);
        let max_depth = STACK_SIZE as u32 - mesh_depth;
        let tree = build_tree(prims, &BuildOptions { max_depth, ..BuildOptions::INSTANCES });
        let mut instances = Vec::with_capacity(descs.len());
        let (mut rows, root, depth) = pack(&tree, vec![[0; 4]], INSTANCE_ROWS, |record, first, _| {
            let desc = descs[tree.order[first as usize] as usize];
            record.copy_from_slice(&BvhInstance::new(&desc, &blas.meshes[desc.mesh as usize]).to_rows());
            instances.push(desc);
        });
        rows[0][0] = root.0;
        debug_assert!(root == ChildRef::NONE || root.offset() == 1, "the root record follows row 0");
        if root.is_leaf() {
            // One instance: its mesh's root node record is copied to row 5 too, so the shader
            // reads it, like the top level's root, from a constant address.
            let mesh = &blas.meshes[instances[0].mesh as usize];
            if !mesh.root.is_leaf() {
                let at = (mesh.base + mesh.root.offset()) as usize;
                rows.extend_from_slice(&blas.rows[at..at + NODE_ROWS as usize]);
            }
        }
        Self { rows, depth, instances }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::accel::bvh::layout::read_triangle;
    use crate::accel::bvh::rays::SplitMix64;

    /// Everything a correct tree satisfies: each triangle exactly once, every decoded box
    /// (quantised) on the way contains the triangles under it, leaves within the size limit,
    /// depth within the stack, children records after their parent and inside the tree.
    /// Returns (SAH cost with traversal cost 1, over the decoded boxes; max inner depth; leaf
    /// count).
    pub(crate) fn check_tree(mesh: &MeshBvh, max_leaf: u32) -> (f32, u32, u32) {
        let rows = &mesh.rows;
        if mesh.root == ChildRef::NONE {
            assert!(rows.is_empty() && mesh.triangle_count == 0);
            return (0.0, 0, 0);
        }
        let mut seen = std::collections::HashSet::new();
        let (mut cost, mut max_depth, mut leaves) = (1.0f64, 0, 0);
        let root_box = Aabb { lo: mesh.bounds_min.into(), hi: mesh.bounds_max.into() };
        let root_area = root_box.half_area().max(f32::MIN_POSITIVE) as f64;
        // (reference, inner depth, the boxes on the way down)
        let mut stack = vec![(mesh.root, 0u32, vec![root_box])];
        while let Some((r, depth, boxes)) = stack.pop() {
            assert!(depth <= MESH_DEPTH);
            let at = r.offset() as usize;
            let area = boxes.last().expect("root box").half_area() as f64 / root_area;
            if r.is_leaf() {
                leaves += 1;
                assert!(r.kind() <= max_leaf);
                cost += area * r.kind() as f64;
                for t in 0..r.kind() as usize {
                    let (prim, v) = read_triangle(&rows[at + 3 * t..]);
                    assert!(seen.insert(prim), "triangle {prim} in two leaves");
                    for b in &boxes {
                        for v in v.map(Vec3A::from) {
                            assert!(v.cmpge(b.lo).all() && v.cmple(b.hi).all(), "triangle {prim} outside a box");
                        }
                    }
                }
                continue;
            }
            max_depth = max_depth.max(depth + 1);
            cost += area;
            let children = NodeRecord([rows[at], rows[at + 1]]).decode(TRIANGLE_ROWS);
            assert!(children[0].0.offset() as usize > at, "children come after their parent");
            for (child, (lo, hi)) in children {
                let end = child.offset() + child_rows(child.kind(), TRIANGLE_ROWS);
                assert!(end as usize <= rows.len());
                let mut path = boxes.clone();
                path.push(Aabb { lo: lo.into(), hi: hi.into() });
                stack.push((child, depth + 1, path));
            }
        }
        assert_eq!(seen.len(), mesh.triangle_count as usize, "a triangle is in no leaf");
        (cost as f32, max_depth, leaves)
    }

    /// A triangle soup: `n` random triangles of size ~`size` in the unit cube.
    pub(crate) fn soup(n: usize, size: f32, seed: u64) -> (Vec<Vec3>, Vec<u32>) {
        let mut rng = SplitMix64::new(seed);
        let mut positions = Vec::with_capacity(3 * n);
        for _ in 0..n {
            let c = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            for _ in 0..3 {
                let d = Vec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5;
                positions.push(c + d * size);
            }
        }
        let indices = (0..3 * n as u32).collect();
        (positions, indices)
    }

    fn check(positions: &[Vec3], indices: &[u32], options: &BuildOptions) -> MeshBvh {
        let bvh = MeshBvh::build(positions, indices, options);
        check_tree(&bvh, options.max_leaf_size);
        bvh
    }

    #[test]
    fn empty_mesh_has_no_root() {
        let bvh = check(&[], &[], &BuildOptions::MESH);
        assert_eq!(bvh.root, ChildRef::NONE);
        assert!(bvh.rows.is_empty());
    }

    #[test]
    fn one_triangle() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = check(&p, &[0, 1, 2], &BuildOptions::MESH);
        // A tree that is one leaf has no node: the root is the leaf.
        assert_eq!(bvh.root, ChildRef::leaf(0, 1));
        assert_eq!(read_triangle(&bvh.rows), (0, [Vec3::ZERO, Vec3::X, Vec3::Y]));
        assert_eq!(bvh.bounds_max, Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn all_centroids_equal() {
        // 10,000 copies of one triangle: no SAH split exists, median splits must terminate.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let indices: Vec<u32> = (0..10_000).flat_map(|_| [0, 1, 2]).collect();
        let bvh = check(&p, &indices, &BuildOptions::MESH);
        assert_eq!(bvh.triangle_count, 10_000);
    }

    #[test]
    fn zero_area_and_invalid_triangles() {
        let (mut positions, mut indices) = soup(2000, 0.01, 7);
        // Points and segments (zero area) are kept; NaN vertices and bad indices are dropped.
        let n = positions.len() as u32;
        positions.extend([Vec3::splat(0.5), Vec3::splat(f32::NAN), Vec3::new(0.1, 0.2, 0.3)]);
        indices.extend([n, n, n, n, n + 2, n + 2, n, n + 1, n + 2, 0, 1, n + 9]);
        let bvh = check(&positions, &indices, &BuildOptions::MESH);
        assert_eq!(bvh.triangle_count, 2002);
    }

    #[test]
    fn flat_and_collinear_meshes() {
        // Degenerate triangles on one line: boxes have zero area, so SAH costs are all 0.
        let positions: Vec<Vec3> = (0..3000).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let indices: Vec<u32> = (0..1000u32).flat_map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        check(&positions, &indices, &BuildOptions::MESH);
    }

    #[test]
    fn flat_along_each_axis() {
        // A grid flat along x, then y, then z: the flat axis offers no split, and must not
        // hide the other two.
        let (positions, indices) = soup(3000, 0.02, 5);
        for axis in 0..3 {
            let flat: Vec<Vec3> = positions
                .iter()
                .map(|p| {
                    let mut p = *p;
                    p[axis] = 0.25;
                    p
                })
                .collect();
            let bvh = check(&flat, &indices, &BuildOptions::MESH);
            let (cost, depth, _) = check_tree(&bvh, 8);
            assert!(depth < 30 && cost < 100.0, "axis {axis}: depth {depth} cost {cost}");
        }
    }

    #[test]
    fn output_does_not_depend_on_threads() {
        let (positions, indices) = soup(60_000, 0.02, 3);
        let one = MeshBvh::build(&positions, &indices, &BuildOptions { threads: 1, ..BuildOptions::MESH });
        let four = MeshBvh::build(&positions, &indices, &BuildOptions { threads: 4, ..BuildOptions::MESH });
        assert_eq!((one.root, &one.rows), (four.root, &four.rows));
        let (cost, depth, _) = check_tree(&four, 8);
        assert!(cost > 0.0 && depth < 40, "cost {cost} depth {depth}");
    }

    #[test]
    fn depth_limits_hold() {
        // Median splits take over where SAH would go too deep, even for one copy of a
        // triangle per position along a line (SAH peels one off at a time).
        let positions: Vec<Vec3> =
            (0..3000).map(|i| Vec3::new((i / 3) as f32 * (i as f32).sqrt(), 0.0, (i % 3) as f32)).collect();
        let indices: Vec<u32> = (0..3000).collect();
        for max_depth in [11, 12, 20] {
            let bvh = MeshBvh::build(
                &positions,
                &indices,
                &BuildOptions { max_depth, max_leaf_size: 1, ..BuildOptions::MESH },
            );
            let (_, depth, _) = check_tree(&bvh, 1);
            assert!(
                depth <= max_depth && depth == bvh.depth,
                "limit {max_depth}: depth {depth}, recorded {}",
                bvh.depth
            );
        }
    }

    #[test]
    fn leaf_size_limits_hold() {
        let (positions, indices) = soup(5000, 0.05, 11);
        for max_leaf_size in [1, 4, MAX_LEAF_SIZE] {
            let options = BuildOptions { max_leaf_size, ..BuildOptions::MESH };
            check(&positions, &indices, &options);
        }
    }
}
