//! CPU reference traversal: the exact algorithm the compute fallback's GLSL runs.
//!
//! Written the way the shader is: one fixed-size stack, no recursion, one loop for both
//! levels taking the same steps in the same order (see [`trace`]).
//!
//! - **Nodes**: both child boxes are tested from one node fetch with a sign-selected slab test
//!   (so an inverted box, min > max, is always missed); the far end of each box interval is
//!   widened by `1 + 2*gamma(3)` ([`BOX_FAR_SCALE`]) so rounding never misses a box that the
//!   watertight triangle test would hit. When both children are hit, the nearer is entered
//!   and the farther is pushed with its entry distance; popped entries farther than the
//!   closest hit so far are dropped.
//! - **Instances**: a top-level leaf transforms the ray by the instance's world-to-object rows
//!   without normalising the direction, so `t` means the same in both spaces, and walks the
//!   mesh's tree on the same stack, above the top level's entries. Instances whose mask
//!   shares no bit with the ray's are skipped. A tree pushes at most one entry per inner
//!   level, and the builder keeps both levels' depths within [`STACK_SIZE`] together.
//! - **Triangles**: watertight test of Woop, Benthin and Wald 2013: translate the vertices to
//!   the ray origin, permute so the direction's largest component is z (swapping x and y when
//!   that component is negative, to keep the winding), shear so the ray runs along +z, then
//!   test the signs of the 2D edge functions U, V, W. An edge function that comes out exactly
//!   0.0 in f32 is recomputed in f64 (products of f32s are exact in f64, so its sign is
//!   right). Hits are two-sided; `front_face` is true when the vertices appear
//!   counter-clockwise seen from the ray origin, judged in object space (as Vulkan does, so a
//!   mirroring instance transform does not flip it). Candidates count when
//!   `tmin <= t <= t_closest`.
//! - **Alpha**: candidates on instances flagged alpha-tested are passed to the callback, which
//!   accepts or ignores them; `any_hit` stops at the first accepted candidate.

use super::SceneBvh;
use super::layout::{
    Bounds, BvhInstance, ChildRef, INSTANCE_ROWS, NodeRecord, Row, STACK_SIZE, TRIANGLE_ROWS, read_triangle,
    transform_point, transform_vector,
};
use glam::Vec3;

/// Widening of a box's far distance: 1 + 2*gamma(3) with gamma(n) = n*eps / (1 - n*eps) and
/// eps = 2^-24 (Ize 2013, "Robust BVH Ray Traversal"), rounded up.
pub const BOX_FAR_SCALE: f32 = 1.000_000_4;

/// Direction components smaller than this are replaced by it (keeping the sign) for the box
/// test only, so `1/d` is finite and `(plane - origin) * (1/d)` is never `0 * inf`.
const MIN_DIR: f32 = 1e-20;

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The instance's custom index.
    pub instance: u32,
    /// Triangle index in the mesh's index buffer (offset / 3).
    pub primitive: u32,
    /// Distance along the (unnormalised) ray direction.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
    /// Counter-clockwise seen from the ray origin (object space).
    pub front_face: bool,
}

/// An alpha callback that accepts every candidate (for scenes without alpha-tested materials).
pub fn accept_all(_instance: u32, _primitive: u32, _u: f32, _v: f32) -> bool {
    true
}

/// Closest hit along `origin + t * dir`, `tmin <= t <= tmax`, among instances whose mask
/// shares a bit with `mask`. `alpha(instance custom index, primitive, u, v)` decides whether
/// a candidate on an alpha-tested instance counts.
pub fn closest_hit(
    bvh: &SceneBvh,
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
    mask: u32,
    alpha: impl FnMut(u32, u32, f32, f32) -> bool,
) -> Option<Hit> {
    trace(bvh, &RaySpace::new(origin, dir), tmin, tmax, mask, false, alpha)
}

/// Whether anything is hit in `tmin <= t <= tmax` (shadow rays); stops at the first accepted
/// candidate.
pub fn any_hit(
    bvh: &SceneBvh,
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
    mask: u32,
    alpha: impl FnMut(u32, u32, f32, f32) -> bool,
) -> bool {
    trace(bvh, &RaySpace::new(origin, dir), tmin, tmax, mask, true, alpha).is_some()
}

/// A ray with everything the box and triangle tests precompute from it.
#[derive(Clone, Copy, Debug)]
struct RaySpace {
    origin: Vec3,
    dir: Vec3,
    /// 1/dir, with tiny components clamped (box test only).
    inv_dir: Vec3,
    /// Axis permutation: the direction's largest component is `kz`.
    kx: usize,
    ky: usize,
    kz: usize,
    /// Shear: x' = x - sx*z, y' = y - sy*z, z' = sz*z maps the direction to (0, 0, 1).
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RaySpace {
    fn new(origin: Vec3, dir: Vec3) -> Self {
        let safe = Vec3::select(dir.abs().cmplt(Vec3::splat(MIN_DIR)), Vec3::splat(MIN_DIR).copysign(dir), dir);
        let kz = dir.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            origin,
            dir,
            inv_dir: safe.recip(),
            kx,
            ky,
            kz,
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: 1.0 / dir[kz],
        }
    }

    /// Entry distance if the box overlaps `[tmin, tmax]` along the ray.
    fn hit_box(&self, (lo, hi): Bounds, tmin: f32, tmax: f32) -> Option<f32> {
        let (mut near, mut far) = (tmin, tmax);
        for a in 0..3 {
            let (n, f) = if self.inv_dir[a] >= 0.0 { (lo[a], hi[a]) } else { (hi[a], lo[a]) };
            near = near.max((n - self.origin[a]) * self.inv_dir[a]);
            far = far.min((f - self.origin[a]) * self.inv_dir[a] * BOX_FAR_SCALE);
        }
        (near <= far).then_some(near)
    }

    /// Watertight ray/triangle test: (t, u, v, front_face) when hit within `[tmin, tmax]`.
    fn hit_triangle(&self, vertices: [Vec3; 3], tmin: f32, tmax: f32) -> Option<(f32, f32, f32, bool)> {
        let [a, b, c] = vertices.map(|v| v - self.origin);
        let shear = |p: Vec3| (p[self.kx] - self.sx * p[self.kz], p[self.ky] - self.sy * p[self.kz]);
        let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let edge = |px: f32, py: f32, qx: f32, qy: f32| {
                (f64::from(px) * f64::from(qy) - f64::from(py) * f64::from(qx)) as f32
            };
            u = edge(cx, cy, bx, by);
            v = edge(ax, ay, cx, cy);
            w = edge(bx, by, ax, ay);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (self.sz * a[self.kz], self.sz * b[self.kz], self.sz * c[self.kz]);
        let rcp = 1.0 / det;
        let t = (u * az + v * bz + w * cz) * rcp;
        // det = -2 * (signed area of the projected triangle) in a right-handed frame looking
        // along +z, so det > 0 means counter-clockwise seen from the origin.
        (tmin <= t && t <= tmax).then_some((t, v * rcp, w * rcp, det > 0.0))
    }

    /// The ray in an instance's object space (direction not normalised).
    fn in_object_space(&self, instance: &BvhInstance) -> Self {
        let m = &instance.world_to_object;
        Self::new(transform_point(m, self.origin), transform_vector(m, self.dir))
    }
}

/// Fixed-size stack of (reference, entry distance), as in the shader.
struct Stack {
    refs: [u32; STACK_SIZE],
    dist: [f32; STACK_SIZE],
    len: usize,
}

impl Stack {
    fn new() -> Self {
        Self { refs: [0; STACK_SIZE], dist: [0.0; STACK_SIZE], len: 0 }
    }

    fn push(&mut self, r: ChildRef, t: f32) {
        self.refs[self.len] = r.0;
        self.dist[self.len] = t;
        self.len += 1;
    }

    /// Drops the top entries that start farther than `tmax`.
    fn drop_farther(&mut self, tmax: f32) {
        while self.len > 0 && self.dist[self.len - 1] > tmax {
            self.len -= 1;
        }
    }

    fn pop(&mut self) -> Option<ChildRef> {
        self.len = self.len.checked_sub(1)?;
        Some(ChildRef(self.refs[self.len]))
    }
}

/// Tests both children of the node record at `rows[0..2]`; returns the child to enter next
/// (pushing the farther one when both are hit), or `None` when neither is.
fn visit(rows: &[Row], leaf_rows: u32, ray: &RaySpace, tmin: f32, tmax: f32, stack: &mut Stack) -> Option<ChildRef> {
    let [(a, a_box), (b, b_box)] = NodeRecord([rows[0], rows[1]]).decode(leaf_rows);
    let ta = ray.hit_box(a_box, tmin, tmax);
    let tb = ray.hit_box(b_box, tmin, tmax);
    match (ta, tb) {
        (Some(ta), Some(tb)) if tb < ta => {
            stack.push(a, ta);
            Some(b)
        }
        (Some(_), Some(tb)) => {
            stack.push(b, tb);
            Some(a)
        }
        (Some(_), None) => Some(a),
        (None, Some(_)) => Some(b),
        (None, None) => None,
    }
}

/// The instance whose mesh the traversal is in.
struct Inside<'a> {
    instance: BvhInstance,
    /// The mesh's rows (its references are relative to their start).
    rows: &'a [Row],
    /// Stack depth when it was entered: the entries below belong to the top level.
    stack_base: usize,
    /// The ray in its object space.
    ray: RaySpace,
}

/// The closest (or, with `first_hit`, the first accepted) hit.
///
/// One loop walks both levels with one stack, as the shader does: each step tests the next
/// triangle of the current leaf, or, with none left, pops (leaving the instance once only
/// top-level entries remain), visits an inner node and starts the leaf it leads to. A
/// top-level leaf is one instance record: entering it switches to its object-space ray and
/// its mesh's tree, starting at the mesh's root (which may be a leaf). The shader takes these
/// steps in the same order (one of each kind per loop iteration, so that SIMD lanes at
/// different levels advance together).
fn trace(
    bvh: &SceneBvh,
    world: &RaySpace,
    tmin: f32,
    tmax: f32,
    mask: u32,
    first_hit: bool,
    mut alpha: impl FnMut(u32, u32, f32, f32) -> bool,
) -> Option<Hit> {
    let mut closest = Closest { t: tmax, hit: None };
    let mut stack = Stack::new();
    let mut inside: Option<Inside> = None;
    // The current leaf's triangle records not yet tested: rows tri_next..tri_end.
    let (mut tri_next, mut tri_end) = (0, 0);
    let mut current = Some(bvh.tlas.root()).filter(|&r| r != ChildRef::NONE);
    loop {
        if let (true, Some(inst)) = (tri_next < tri_end, &inside) {
            let (primitive, vertices) = read_triangle(&inst.rows[tri_next as usize..]);
            tri_next += TRIANGLE_ROWS;
            if let Some((t, u, v, front_face)) = inst.ray.hit_triangle(vertices, tmin, closest.t) {
                let instance = inst.instance.custom_index;
                if !inst.instance.is_alpha_tested() || alpha(instance, primitive, u, v) {
                    closest.t = t;
                    closest.hit = Some(Hit { instance, primitive, t, u, v, front_face });
                    if first_hit {
                        return closest.hit;
                    }
                }
            }
        }
        if tri_next < tri_end {
            continue;
        }
        let r = match current {
            Some(r) => r,
            None => {
                stack.drop_farther(closest.t);
                if inside.as_ref().is_some_and(|i| stack.len <= i.stack_base) {
                    inside = None;
                }
                match stack.pop() {
                    Some(r) => r,
                    None => return closest.hit,
                }
            }
        };
        current = if r.is_leaf() {
            Some(r)
        } else {
            let at = r.offset() as usize;
            match &inside {
                Some(i) => visit(&i.rows[at..], TRIANGLE_ROWS, &i.ray, tmin, closest.t, &mut stack),
                None => visit(&bvh.tlas.rows[at..], INSTANCE_ROWS, world, tmin, closest.t, &mut stack),
            }
        };
        if let Some(leaf) = current.filter(|r| r.is_leaf()) {
            current = None;
            let at = leaf.offset();
            if inside.is_some() {
                (tri_next, tri_end) = (at, at + leaf.kind() * TRIANGLE_ROWS);
            } else {
                debug_assert_eq!(leaf.kind(), 1, "a top-level leaf is one instance");
                let instance = BvhInstance::read(&bvh.tlas.rows[at as usize..]);
                if instance.mask() & mask != 0 {
                    let ray = world.in_object_space(&instance);
                    let rows = &bvh.blas.rows[instance.mesh_base as usize..];
                    inside = Some(Inside { instance, rows, stack_base: stack.len, ray });
                    current = Some(ChildRef(instance.root));
                }
            }
        }
    }
}

/// The closest accepted hit so far; `t` doubles as the ray's current far end.
struct Closest {
    t: f32,
    hit: Option<Hit>,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::accel::bvh::build::tests::soup;
    use crate::accel::bvh::rays::{BenchView, Ray, SplitMix64, triangle_bounds};
    use crate::accel::bvh::{BuildOptions, InstanceDesc, MeshBvh};
    use glam::{Affine3A, Quat};
    use std::collections::HashMap;

    /// A unit icosphere with `20 * 4^level` triangles, wound counter-clockwise seen from
    /// outside; the triangles are shuffled so the builder cannot rely on index order.
    pub(crate) fn icosphere(level: u32) -> (Vec<Vec3>, Vec<u32>) {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut positions: Vec<Vec3> = [
            (-1.0, t, 0.0),
            (1.0, t, 0.0),
            (-1.0, -t, 0.0),
            (1.0, -t, 0.0),
            (0.0, -1.0, t),
            (0.0, 1.0, t),
            (0.0, -1.0, -t),
            (0.0, 1.0, -t),
            (t, 0.0, -1.0),
            (t, 0.0, 1.0),
            (-t, 0.0, -1.0),
            (-t, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
        .collect();
        let mut faces: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..level {
            let mut midpoints = HashMap::new();
            let mut mid = |a: u32, b: u32| {
                *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let p = (positions[a as usize] + positions[b as usize]).normalize();
                    positions.push(p);
                    positions.len() as u32 - 1
                })
            };
            faces = faces
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                    [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
                })
                .collect();
        }
        let mut rng = SplitMix64::new(9);
        for i in (1..faces.len()).rev() {
            faces.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        (positions, faces.concat())
    }

    fn instance(object_to_world: Affine3A, mesh: u32, custom_index: u32) -> InstanceDesc {
        InstanceDesc { object_to_world, mesh, custom_index, mask: 0xFF, alpha_tested: false, material: 0 }
    }

    fn single_mesh(positions: &[Vec3], indices: &[u32]) -> SceneBvh {
        let blas = [MeshBvh::build(positions, indices, &BuildOptions::MESH)].into_iter().collect();
        SceneBvh::new(blas, &[instance(Affine3A::IDENTITY, 0, 0)])
    }

    /// Closest hit by testing every triangle of every instance.
    fn brute_force(bvh: &SceneBvh, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let world = RaySpace::new(origin, dir);
        let mut best: Option<Hit> = None;
        for desc in &bvh.tlas.instances {
            let local = world.in_object_space(&BvhInstance::new(desc, &bvh.blas.meshes[desc.mesh as usize]));
            for (primitive, vertices) in bvh.blas.triangles(desc.mesh) {
                let t_far = best.map_or(tmax, |h| h.t);
                if let Some((t, u, v, front_face)) = local.hit_triangle(vertices, tmin, t_far) {
                    best = Some(Hit { instance: desc.custom_index, primitive, t, u, v, front_face });
                }
            }
        }
        best
    }

    /// Three meshes under rotations, non-uniform and mirroring scales, plus an empty mesh.
    fn instanced_scene() -> SceneBvh {
        let (sphere_p, sphere_i) = icosphere(3);
        let (soup_p, soup_i) = soup(1500, 0.05, 1);
        let meshes = [
            MeshBvh::build(&sphere_p, &sphere_i, &BuildOptions::MESH),
            MeshBvh::build(&[], &[], &BuildOptions::MESH),
            MeshBvh::build(&soup_p, &soup_i, &BuildOptions::MESH),
        ];
        let mut instances = Vec::new();
        let mut rng = SplitMix64::new(4);
        for i in 0..24 {
            let scale = Vec3::new(0.5 + rng.unit(), 0.5 + rng.unit(), 0.5 + rng.unit())
                * if i % 5 == 0 { Vec3::new(-1.0, 1.0, 1.0) } else { Vec3::ONE };
            let rotation = Quat::from_euler(glam::EulerRot::XYZ, rng.unit() * 6.0, rng.unit() * 6.0, 0.3);
            let at = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 6.0;
            let m = Affine3A::from_scale_rotation_translation(scale, rotation, at);
            instances.push(instance(m, [0, 1, 2][i % 3], 100 + i as u32));
        }
        SceneBvh::new(meshes.into_iter().collect(), &instances)
    }

    #[test]
    fn matches_brute_force_on_instanced_scene() {
        let bvh = instanced_scene();
        let (lo, hi) = triangle_bounds(&bvh);
        let view = BenchView::new(lo, hi);
        let mut rays = view.incoherent(1500);
        rays.extend(view.primary(32, 32));
        let mut hits = 0;
        for (i, r) in rays.iter().enumerate() {
            // Unnormalised directions and a finite interval must not change anything.
            let dir = Vec3::from(r.dir) * if i % 2 == 0 { 1.0 } else { 2.5 };
            let (tmin, tmax) = if i % 3 == 0 { (0.5, 4.0) } else { (r.tmin, r.tmax) };
            let origin = Vec3::from(r.origin);
            let expected = brute_force(&bvh, origin, dir, tmin, tmax);
            let got = closest_hit(&bvh, origin, dir, tmin, tmax, 0xFF, accept_all);
            assert_eq!(got, expected, "ray {i}");
            assert_eq!(any_hit(&bvh, origin, dir, tmin, tmax, 0xFF, accept_all), expected.is_some());
            hits += usize::from(got.is_some());
        }
        assert!(hits > 200, "only {hits} hits");
    }

    #[test]
    fn barycentrics_and_facing() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = single_mesh(&p, &[0, 1, 2]);
        let down = closest_hit(&bvh, Vec3::new(0.2, 0.3, 1.0), -Vec3::Z, 0.0, 10.0, 0xFF, accept_all);
        let h = down.expect("hit from above");
        assert!((h.t - 1.0).abs() < 1e-6 && (h.u - 0.2).abs() < 1e-6 && (h.v - 0.3).abs() < 1e-6);
        assert!(h.front_face, "counter-clockwise seen from +z");
        let up = closest_hit(&bvh, Vec3::new(0.2, 0.3, -2.0), Vec3::Z * 2.0, 0.0, 10.0, 0xFF, accept_all);
        let h = up.expect("hit from below");
        assert!((h.t - 1.0).abs() < 1e-6 && !h.front_face);
        // Random rays through random triangles: the interpolated point is on the ray, and
        // facing agrees with the geometric normal, for every dominant axis and sign.
        let mut rng = SplitMix64::new(12);
        for _ in 0..2000 {
            let mut v = || Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - 1.0;
            let tri = [v(), v(), v()];
            let (origin, target) = (v() * 3.0, (tri[0] + tri[1] + tri[2]) / 3.0);
            let dir = target - origin;
            let bvh = single_mesh(&tri, &[0, 1, 2]);
            let h = closest_hit(&bvh, origin, dir, 0.0, f32::MAX, 0xFF, accept_all).expect("centroid hit");
            let point = (1.0 - h.u - h.v) * tri[0] + h.u * tri[1] + h.v * tri[2];
            assert!(point.distance(origin + h.t * dir) < 1e-4);
            let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            assert_eq!(h.front_face, normal.dot(dir) < 0.0);
        }
    }

    #[test]
    fn facing_is_judged_in_object_space() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let blas = [MeshBvh::build(&p, &[0, 1, 2], &BuildOptions::MESH)].into_iter().collect();
        let mirror = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let bvh = SceneBvh::new(blas, &[instance(mirror, 0, 7)]);
        let h = closest_hit(&bvh, Vec3::new(-0.2, 0.3, 1.0), -Vec3::Z, 0.0, 10.0, 0xFF, accept_all);
        let h = h.expect("hit");
        assert_eq!((h.instance, h.front_face), (7, true));
        assert!((h.u - 0.2).abs() < 1e-6);
    }

    #[test]
    fn closed_mesh_does_not_leak() {
        // Rays from inside a closed sphere, many aimed exactly at vertices and edge midpoints
        // (where a non-watertight test can slip between triangles), must all hit.
        let (positions, indices) = icosphere(4);
        let bvh = single_mesh(&positions, &indices);
        let mut targets: Vec<Vec3> = positions.clone();
        targets.extend(indices.chunks(3).map(|t| (positions[t[0] as usize] + positions[t[1] as usize]) * 0.5));
        let mut rng = SplitMix64::new(3);
        for (i, target) in targets.iter().enumerate() {
            let origin =
                if i % 2 == 0 { Vec3::ZERO } else { Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 0.5 - 0.25 };
            let dir = *target - origin;
            assert!(closest_hit(&bvh, origin, dir, 0.0, f32::MAX, 0xFF, accept_all).is_some(), "leak toward {target}");
            assert!(any_hit(&bvh, origin, dir, 0.0, f32::MAX, 0xFF, accept_all));
        }
    }

    #[test]
    fn grid_has_no_cracks() {
        // Axis-aligned rays through every vertex and edge of a grid of shared-edge quads.
        let n = 16;
        let positions: Vec<Vec3> =
            (0..=n).flat_map(|y| (0..=n).map(move |x| Vec3::new(x as f32 * 0.1, y as f32 * 0.1, 0.0))).collect();
        let mut indices = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let i = y * (n + 1) + x;
                indices.extend([i, i + 1, i + n + 2, i, i + n + 2, i + n + 1]);
            }
        }
        let bvh = single_mesh(&positions, &indices);
        for y in 1..2 * n {
            for x in 1..2 * n {
                let origin = Vec3::new(x as f32 * 0.05, y as f32 * 0.05, 1.0);
                for dir in [-Vec3::Z, Vec3::new(0.01, 0.02, -1.0)] {
                    let hit = closest_hit(&bvh, origin, dir, 0.0, f32::MAX, 0xFF, accept_all);
                    assert!(hit.is_some_and(|h| h.front_face), "crack at {origin}");
                }
            }
        }
    }

    /// Two parallel triangles, primitive 0 at z = 0 and primitive 1 at z = -1, on one
    /// instance flagged alpha-tested.
    fn stacked(alpha_tested: bool) -> SceneBvh {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, -Vec3::Z, Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, -1.0)];
        let blas = [MeshBvh::build(&p, &[0, 1, 2, 3, 4, 5], &BuildOptions::MESH)].into_iter().collect();
        SceneBvh::new(blas, &[InstanceDesc { alpha_tested, mask: 0x03, ..instance(Affine3A::IDENTITY, 0, 5) }])
    }

    #[test]
    fn alpha_callback_filters_candidates() {
        let (o, d) = (Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        let bvh = stacked(true);
        let mut calls = Vec::new();
        let hit = closest_hit(&bvh, o, d, 0.0, 10.0, 0xFF, |i, p, _, _| {
            calls.push((i, p));
            p != 0
        });
        assert_eq!(hit.map(|h| (h.instance, h.primitive)), Some((5, 1)));
        assert!(calls.contains(&(5, 0)) && calls.contains(&(5, 1)));
        assert!(closest_hit(&bvh, o, d, 0.0, 10.0, 0xFF, |_, _, _, _| false).is_none());
        assert!(!any_hit(&bvh, o, d, 0.0, 10.0, 0xFF, |_, _, _, _| false));
        // Candidates outside [tmin, t_closest] never reach the callback.
        let mut calls = 0;
        closest_hit(&bvh, o, d, 0.0, 1.5, 0xFF, |_, p, _, _| {
            calls += 1;
            assert_eq!(p, 0);
            true
        });
        assert_eq!(calls, 1);
        // Opaque instances never call it.
        let opaque = stacked(false);
        let hit = closest_hit(&opaque, o, d, 0.0, 10.0, 0xFF, |_, _, _, _| unreachable!());
        assert_eq!(hit.map(|h| h.primitive), Some(0));
    }

    #[test]
    fn masks_and_intervals() {
        let (o, d) = (Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        let bvh = stacked(false);
        assert!(closest_hit(&bvh, o, d, 0.0, 10.0, 0x04, accept_all).is_none());
        assert!(closest_hit(&bvh, o, d, 0.0, 10.0, 0x02, accept_all).is_some());
        assert_eq!(closest_hit(&bvh, o, d, 1.5, 10.0, 0xFF, accept_all).map(|h| h.primitive), Some(1));
        assert!(closest_hit(&bvh, o, d, 0.0, 0.5, 0xFF, accept_all).is_none());
        // Inclusive ends: a hit exactly at tmax counts.
        assert!(any_hit(&bvh, o, d, 0.0, 1.0, 0xFF, accept_all));
    }

    #[test]
    fn one_instance_top_level_copies_the_mesh_root() {
        // The shader reads the first node every ray visits from row 5 of the top level.
        let (p, i) = icosphere(2);
        let bvh = single_mesh(&p, &i);
        let mesh = &bvh.blas.meshes[0];
        let at = (mesh.base + mesh.root.offset()) as usize;
        assert!(!mesh.root.is_leaf());
        assert_eq!(bvh.tlas.root(), ChildRef::leaf(1, 1));
        assert_eq!(&bvh.tlas.rows[5..7], &bvh.blas.rows[at..at + 2]);
    }

    #[test]
    fn empty_scene_and_moved_instances() {
        let empty = SceneBvh::default();
        assert_eq!((empty.tlas.root(), empty.tlas.rows.len()), (ChildRef::NONE, 1));
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let blas = [MeshBvh::build(&p, &[0, 1, 2], &BuildOptions::MESH)].into_iter().collect();
        let mut bvh = SceneBvh::new(blas, &[]);
        let (o, d) = (Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        assert!(closest_hit(&bvh, o, d, 0.0, 10.0, 0xFF, accept_all).is_none());
        bvh.set_instances(&[instance(Affine3A::from_translation(Vec3::Z * -3.0), 0, 1)]);
        let rows_before = bvh.blas.rows.clone();
        let h = closest_hit(&bvh, o, d, 0.0, 10.0, 0xFF, accept_all).expect("moved instance");
        assert!((h.t - 4.0).abs() < 1e-6);
        assert_eq!(bvh.blas.rows, rows_before);
    }

    /// Build time and CPU ray rates on ~1M-triangle meshes, for the default options and the
    /// traversal costs around it: `cargo test --release -- --ignored --nocapture bench`.
    #[test]
    #[ignore]
    fn bench_big_meshes() {
        use crate::accel::bvh::build::tests::check_tree;
        use crate::accel::bvh::rays::{DEFAULT_HEIGHT, DEFAULT_INCOHERENT, DEFAULT_WIDTH};
        use std::time::Instant;
        let meshes = [("icosphere level 8", icosphere(8)), ("triangle soup", soup(1 << 20, 0.004, 1))];
        for (name, (positions, indices)) in &meshes {
            println!("{name}: {} triangles", indices.len() / 3);
            for (threads, traversal_cost) in [(1, 1.5), (0, 1.5), (0, 1.0), (0, 2.0)] {
                let options = BuildOptions { threads, traversal_cost, ..BuildOptions::MESH };
                let mut best = f64::MAX;
                let mut mesh = None;
                for _ in 0..3 {
                    let start = Instant::now();
                    mesh = Some(MeshBvh::build(positions, indices, &options));
                    best = best.min(start.elapsed().as_secs_f64());
                }
                let mesh = mesh.expect("built");
                let (sah, depth, leaves) = check_tree(&mesh, options.max_leaf_size);
                let rows = mesh.rows.len();
                let bvh = SceneBvh::new([mesh].into_iter().collect(), &[instance(Affine3A::IDENTITY, 0, 0)]);
                let (lo, hi) = triangle_bounds(&bvh);
                let view = BenchView::new(lo, hi);
                let primary = view.primary(DEFAULT_WIDTH, DEFAULT_HEIGHT);
                let (primary_rate, hits) = rate(&bvh, &primary, false);
                let shadow = view.shadow(&primary, &hits);
                let (shadow_rate, _) = rate(&bvh, &shadow, true);
                let (incoherent_rate, _) = rate(&bvh, &view.incoherent(DEFAULT_INCOHERENT), false);
                let ms = best * 1e3;
                let shadows = shadow.len();
                println!(
                    "  threads {threads} traversal cost {traversal_cost}: build {ms:.0} ms; \
                     {rows} rows, SAH {sah:.2}, depth {depth}, {leaves} leaves; \
                     Mrays/s on 2 threads: primary {primary_rate:.2}, \
                     shadow {shadow_rate:.2} ({shadows} rays), incoherent {incoherent_rate:.2}"
                );
            }
        }
    }

    /// Rays per second (millions) tracing `rays` on two threads, and the closest-hit t's.
    fn rate(bvh: &SceneBvh, rays: &[Ray], shadow: bool) -> (f64, Vec<Option<f32>>) {
        let start = std::time::Instant::now();
        let trace = |r: &Ray| {
            let (o, d) = (Vec3::from(r.origin), Vec3::from(r.dir));
            if shadow {
                any_hit(bvh, o, d, r.tmin, r.tmax, 0xFF, accept_all).then_some(0.0)
            } else {
                closest_hit(bvh, o, d, r.tmin, r.tmax, 0xFF, accept_all).map(|h| h.t)
            }
        };
        let half = rays.len() / 2;
        let hits = std::thread::scope(|s| {
            let second = s.spawn(|| rays[half..].iter().map(trace).collect::<Vec<_>>());
            let mut hits: Vec<_> = rays[..half].iter().map(trace).collect();
            hits.extend(second.join().expect("trace thread"));
            hits
        });
        (rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6, hits)
    }
}
