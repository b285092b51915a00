//! Deforming meshes: refitting a bottom level in place for moved vertices, and rebuilding it
//! within the rows reserved for it.
//!
//! A refit keeps the topology (which triangles share a leaf, which nodes are siblings) and
//! recomputes every box bottom-up from the new vertices: linear in the triangle count, no
//! sorting, and the tree keeps its size, so it is rewritten where it lies in the pool. The
//! boxes stay tight, but the tree was split for the old shape and degrades as the mesh moves
//! away from it; the caller rebuilds it with SAH now and then. A rebuilt tree has a different
//! shape and row count, so a deforming mesh's pool range is reserved for the largest tree its
//! triangle count can give ([`reserved_rows`]).

use super::layout::{BlasPool, ChildRef, MeshBvh, NODE_ROWS, NodeRecord, Row, TRIANGLE_ROWS, triangle_rows};
use glam::{Vec3, Vec3A};

/// Rows the largest tree over `triangles` triangles takes: a record per triangle and at most
/// one inner node fewer than leaves (every leaf holds at least one triangle).
pub fn reserved_rows(triangles: u32) -> usize {
    let n = triangles as usize;
    n * TRIANGLE_ROWS as usize + n.saturating_sub(1) * NODE_ROWS as usize
}

/// What a refit or rebuild changed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refit {
    /// Rows of the tree from the mesh's first row (the rest of its reserve is unused).
    pub rows: usize,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// Refits the tree whose records are `rows` (references relative to `rows[0]`) to the
/// mesh's new `positions`: triangle records get the new vertices, node records the boxes of
/// their children. `indices` are the mesh's, unchanged since the build.
pub fn refit(rows: &mut [Row], root: ChildRef, positions: &[Vec3], indices: &[u32]) -> Refit {
    if root == ChildRef::NONE {
        return Refit { rows: 0, bounds_min: Vec3::ZERO, bounds_max: Vec3::ZERO };
    }
    let mut end = 0;
    let (lo, hi) = refit_subtree(rows, root, positions, indices, &mut end);
    Refit { rows: end, bounds_min: lo.into(), bounds_max: hi.into() }
}

/// Refits the subtree under `node` and returns its box; `end` grows to the end of the last
/// record visited. Recursion is at most [`super::STACK_SIZE`] deep.
fn refit_subtree(
    rows: &mut [Row],
    node: ChildRef,
    positions: &[Vec3],
    indices: &[u32],
    end: &mut usize,
) -> (Vec3A, Vec3A) {
    let at = node.offset() as usize;
    if node.is_leaf() {
        let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for t in 0..node.kind() as usize {
            let record = at + t * TRIANGLE_ROWS as usize;
            let primitive = rows[record][3];
            let first = 3 * primitive as usize;
            let v = [0, 1, 2].map(|k| positions[indices[first + k] as usize]);
            rows[record..record + TRIANGLE_ROWS as usize].copy_from_slice(&triangle_rows(primitive, v));
            for p in v {
                lo = lo.min(p.into());
                hi = hi.max(p.into());
            }
        }
        *end = (*end).max(at + node.kind() as usize * TRIANGLE_ROWS as usize);
        return (lo, hi);
    }
    // Only the references are read from the old record: its boxes are what is replaced.
    let [(a, _), (b, _)] = NodeRecord([rows[at], rows[at + 1]]).decode(TRIANGLE_ROWS);
    let (a_lo, a_hi) = refit_subtree(rows, a, positions, indices, end);
    let (b_lo, b_hi) = refit_subtree(rows, b, positions, indices, end);
    rows[at..at + NODE_ROWS as usize]
        .copy_from_slice(&NodeRecord::encode([(a.kind(), a_lo, a_hi), (b.kind(), b_lo, b_hi)], a.offset()).0);
    *end = (*end).max(at + NODE_ROWS as usize);
    (a_lo.min(b_lo), a_hi.max(b_hi))
}

impl BlasPool {
    /// Refits mesh `mesh`'s tree in place (see [`refit`]) and updates its bounds.
    pub fn refit_mesh(&mut self, mesh: u32, positions: &[Vec3], indices: &[u32]) -> Refit {
        let m = &mut self.meshes[mesh as usize];
        let rows = &mut self.rows[m.base as usize..(m.base + m.rows) as usize];
        let r = refit(rows, m.root, positions, indices);
        (m.bounds_min, m.bounds_max) = (r.bounds_min, r.bounds_max);
        r
    }

    /// Replaces mesh `mesh`'s tree by `tree`, built anew over the same triangles, within the
    /// mesh's rows (which must hold it: reserve [`reserved_rows`] for a deforming mesh).
    pub fn replace_mesh(&mut self, mesh: u32, tree: MeshBvh) -> Refit {
        let m = &mut self.meshes[mesh as usize];
        assert!(tree.rows.len() <= m.rows as usize, "rebuilt tree larger than the mesh's reserved rows");
        let base = m.base as usize;
        self.rows[base..base + tree.rows.len()].copy_from_slice(&tree.rows);
        m.root = tree.root;
        m.depth = tree.depth;
        (m.bounds_min, m.bounds_max) = (tree.bounds_min, tree.bounds_max);
        Refit { rows: tree.rows.len(), bounds_min: tree.bounds_min, bounds_max: tree.bounds_max }
    }
}

#[cfg(test)]
mod tests {
    use super::super::layout::{TRIANGLE_ROWS, leaves, read_triangle};
    use super::super::{BuildOptions, accept_all, closest_hit, rays::SplitMix64};
    use super::*;

    /// A wavy grid of `n` x `n` quads; `phase` moves its vertices.
    fn grid(n: u32, phase: f32) -> (Vec<Vec3>, Vec<u32>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                p.push(Vec3::new(x + 0.2 * (y * 7.0 + phase).sin(), y, 0.5 * (x * 9.0 + phase * 2.0).sin()));
            }
        }
        let mut idx = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b) = (j * (n + 1) + i, (j + 1) * (n + 1) + i);
                idx.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
            }
        }
        (p, idx)
    }

    /// Every triangle lies in the box of every node on its path from the root.
    fn assert_bounds_contain_triangles(rows: &[Row], root: ChildRef, positions: &[Vec3], indices: &[u32]) {
        let mut todo = vec![(root, Vec3::NEG_INFINITY, Vec3::INFINITY)];
        let mut seen = 0;
        while let Some((r, lo, hi)) = todo.pop() {
            if r.is_leaf() {
                for t in 0..r.kind() {
                    let (prim, v) = read_triangle(&rows[(r.offset() + t * TRIANGLE_ROWS) as usize..]);
                    let first = 3 * prim as usize;
                    for (k, p) in v.iter().enumerate() {
                        assert_eq!(*p, positions[indices[first + k] as usize], "triangle {prim} not refit");
                        assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "triangle {prim} outside its node box");
                    }
                    seen += 1;
                }
                continue;
            }
            let at = r.offset() as usize;
            for (child, (clo, chi)) in NodeRecord([rows[at], rows[at + 1]]).decode(TRIANGLE_ROWS) {
                todo.push((child, clo, chi));
            }
        }
        assert_eq!(seen, indices.len() / 3);
    }

    #[test]
    fn refit_bounds_contain_every_deformed_triangle() {
        let (p0, idx) = grid(24, 0.0);
        let built = MeshBvh::build(&p0, &idx, &BuildOptions::MESH);
        let mut pool = BlasPool::default();
        pool.push(MeshBvh { rows: vec![[0; 4]; 5], ..MeshBvh::build(&[], &[], &BuildOptions::MESH) });
        let mut padded = built.clone();
        padded.rows.resize(reserved_rows(built.triangle_count), [0; 4]);
        let id = pool.push(padded);
        for step in 1..6 {
            let (p, _) = grid(24, step as f32 * 0.7);
            let r = pool.refit_mesh(id, &p, &idx);
            assert_eq!(r.rows, built.rows.len(), "a refit keeps the tree's size");
            let m = pool.meshes[id as usize];
            let rows = &pool.rows[m.base as usize..(m.base + m.rows) as usize];
            assert_bounds_contain_triangles(rows, m.root, &p, &idx);
            let (lo, hi) = p.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
            assert_eq!((m.bounds_min, m.bounds_max), (lo, hi));
            assert_eq!(leaves(rows, m.root, TRIANGLE_ROWS), leaves(&built.rows, built.root, TRIANGLE_ROWS));
        }
        // The first mesh's rows are untouched.
        assert_eq!(&pool.rows[..5], &[[0; 4]; 5]);
    }

    #[test]
    fn refit_and_rebuild_find_the_same_hits() {
        use super::super::{InstanceDesc, SceneBvh};
        let (p0, idx) = grid(16, 0.0);
        let mut tree = MeshBvh::build(&p0, &idx, &BuildOptions::MESH);
        tree.rows.resize(reserved_rows(tree.triangle_count), [0; 4]);
        let instances = [InstanceDesc {
            object_to_world: glam::Affine3A::IDENTITY,
            mesh: 0,
            custom_index: 0,
            mask: 0xff,
            alpha_tested: false,
            material: 0,
        }];
        let mut refit_bvh = SceneBvh::new([tree].into_iter().collect(), &instances);
        let mut rebuilt_bvh = refit_bvh.clone();
        let (p, _) = grid(16, 2.5);
        refit_bvh.blas.refit_mesh(0, &p, &idx);
        refit_bvh.set_instances(&instances);
        let fresh = MeshBvh::build(&p, &idx, &BuildOptions::MESH);
        assert!(fresh.rows.len() <= reserved_rows(fresh.triangle_count));
        rebuilt_bvh.blas.replace_mesh(0, fresh);
        rebuilt_bvh.set_instances(&instances);
        let mut rng = SplitMix64::new(3);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = Vec3::new(rng.unit() * 1.6 - 0.3, rng.unit() * 1.2 - 0.1, 2.0);
            let d = (Vec3::new(rng.unit(), rng.unit(), -4.0) - Vec3::new(0.5, 0.5, 0.0)).normalize();
            let a = closest_hit(&refit_bvh, o, d, 0.0, 100.0, 0xff, accept_all);
            let b = closest_hit(&rebuilt_bvh, o, d, 0.0, 100.0, 0xff, accept_all);
            assert_eq!(a.map(|h| (h.primitive, h.t)), b.map(|h| (h.primitive, h.t)));
            hits += usize::from(a.is_some());
        }
        assert!(hits > 500, "only {hits} rays hit the grid");
    }
}
