//! Normals and tangents for primitives that lack them.
//!
//! glTF says a primitive without NORMAL is flat-shaded, and that missing tangents are to be
//! computed with MikkTSpace from positions, normals and the normal texture's UVs. The
//! functions here do that on a triangle list; the loader decides which one a primitive needs.
//! All of them assume the indices are in range of the vertices (the loader checks that first).

use super::Vertex;
use glam::{Vec3, Vec4};
use std::collections::HashMap;

/// Gives every triangle its own three vertices carrying the triangle's face normal.
///
/// Flat shading needs one normal per triangle corner, which shared vertices cannot hold, so
/// the mesh is un-welded: afterwards `vertices.len() == indices.len()`.
pub fn flat_normals(vertices: &mut Vec<Vertex>, indices: &mut Vec<u32>) {
    let mut flat = Vec::with_capacity(indices.len());
    for triangle in indices.chunks_exact(3) {
        let &[a, b, c] = triangle else {
            continue;
        };
        let corners = [a, b, c].map(|i| vertices.get(i as usize).copied().unwrap_or_default());
        let normal = face_normal(corners.map(|v| Vec3::from(v.position))).to_array();
        flat.extend(corners.map(|v| Vertex { normal, ..v }));
    }
    *indices = (0..flat.len() as u32).collect();
    *vertices = flat;
}

/// Unit normal of a counter-clockwise triangle; +Z for degenerate triangles, which have no
/// orientation but must not feed NaNs into shading.
fn face_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z)
}

/// Makes every normal unit length; zero or non-finite normals become +Z.
pub fn normalize_normals(vertices: &mut [Vertex]) {
    for v in vertices {
        v.normal = Vec3::from(v.normal).try_normalize().unwrap_or(Vec3::Z).to_array();
    }
}

/// Sets each tangent to an arbitrary unit vector perpendicular to the normal (w = 1).
///
/// Used where no UV-aligned frame exists or none is needed (no normal texture, or no UVs):
/// shaders can still build an orthonormal basis from it without special cases.
pub fn orthonormal_tangents(vertices: &mut [Vertex]) {
    for v in vertices {
        let n = Vec3::from(v.normal).try_normalize().unwrap_or(Vec3::Z);
        v.tangent = n.any_orthonormal_vector().extend(1.0).to_array();
    }
}

/// Makes file-supplied tangents unit length with w = ±1; a zero or non-finite tangent is
/// replaced by an arbitrary one perpendicular to the normal.
pub fn normalize_tangents(vertices: &mut [Vertex]) {
    for v in vertices {
        let t = Vec4::from(v.tangent);
        let n = Vec3::from(v.normal).try_normalize().unwrap_or(Vec3::Z);
        let xyz = t.truncate().try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
        let w = if t.w < 0.0 { -1.0 } else { 1.0 };
        v.tangent = xyz.extend(w).to_array();
    }
}

/// Replaces tangents with MikkTSpace tangents computed from UV set `uv_set` (0 or 1).
///
/// MikkTSpace yields a tangent per triangle corner; where corners sharing a vertex disagree
/// (UV seams, mirrored UVs) the vertex is duplicated, so `vertices` may grow. Returns false,
/// leaving the mesh unchanged, when MikkTSpace fails (bevy_mikktspace 1.0 has no failure yet,
/// but its error type is open to new ones).
pub fn mikktspace_tangents(vertices: &mut Vec<Vertex>, indices: &mut [u32], uv_set: u32) -> bool {
    let mut geometry = MikkGeometry { vertices, indices, uv_set, corner_tangents: vec![[0.0; 4]; indices.len()] };
    if bevy_mikktspace::generate_tangents(&mut geometry).is_err() {
        return false;
    }
    let corner_tangents = geometry.corner_tangents;
    split_by_tangent(vertices, indices, &corner_tangents);
    true
}

/// Work MikkTSpace may do per triangle corner, in pairs of corners compared (see below).
const MIKKTSPACE_PAIRS_PER_CORNER: u64 = 64;

/// Below this many pairs MikkTSpace is fast whatever the mesh.
const MIKKTSPACE_PAIRS_FLOOR: u64 = 1 << 24;

/// Whether MikkTSpace finishes in time roughly proportional to the mesh's size.
///
/// It welds corners by comparing every pair that shares a position, and groups the triangles
/// around a vertex by comparing every pair of them, so its time grows with the sum over
/// positions of (corners at that position)². In real meshes a handful of corners share a
/// position; a hostile one (all positions zero, or a fan of a million triangles) would keep
/// it busy for hours. Positions are compared by value, so -0 and +0 count as one.
pub fn mikktspace_is_tractable(vertices: &[Vertex], indices: &[u32]) -> bool {
    let mut corners_at: HashMap<[u32; 3], u64> = HashMap::new();
    for &i in indices {
        let p = vertices.get(i as usize).map_or([0.0; 3], |v| v.position);
        *corners_at.entry(p.map(|c| (c + 0.0).to_bits())).or_default() += 1;
    }
    let pairs: u64 = corners_at.values().map(|&k| k * k).sum();
    pairs <= (indices.len() as u64 * MIKKTSPACE_PAIRS_PER_CORNER).max(MIKKTSPACE_PAIRS_FLOOR)
}

/// Gives each vertex the tangent of its corners, duplicating vertices whose corners differ.
fn split_by_tangent(vertices: &mut Vec<Vertex>, indices: &mut [u32], corner_tangents: &[[f32; 4]]) {
    let mut assigned = vec![false; vertices.len()];
    let mut copies: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    for (index, &tangent) in indices.iter_mut().zip(corner_tangents) {
        let i = *index as usize;
        let (Some(done), Some(vertex)) = (assigned.get_mut(i), vertices.get_mut(i)) else {
            continue;
        };
        if !*done {
            vertex.tangent = tangent;
            *done = true;
            continue;
        }
        if vertex.tangent.map(f32::to_bits) == tangent.map(f32::to_bits) {
            continue;
        }
        let copy = Vertex { tangent, ..*vertex };
        *index = *copies.entry((*index, tangent.map(f32::to_bits))).or_insert_with(|| {
            vertices.push(copy);
            (vertices.len() - 1) as u32
        });
    }
}

/// A triangle list as MikkTSpace sees it, collecting one tangent per corner.
struct MikkGeometry<'a> {
    vertices: &'a [Vertex],
    indices: &'a [u32],
    uv_set: u32,
    corner_tangents: Vec<[f32; 4]>,
}

impl MikkGeometry<'_> {
    fn vertex(&self, face: usize, vert: usize) -> Vertex {
        self.indices.get(face * 3 + vert).and_then(|&i| self.vertices.get(i as usize)).copied().unwrap_or_default()
    }
}

impl bevy_mikktspace::Geometry for MikkGeometry<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).position
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).normal
    }

    /// MikkTSpace assumes v grows upwards in the image, glTF that it grows downwards; flipping
    /// v makes the bitangent sign match glTF's (checked against the tangents shipped with
    /// NormalTangentMirrorTest in the loader's tests).
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let v = self.vertex(face, vert);
        let [s, t] = if self.uv_set == 1 { v.uv1 } else { v.uv0 };
        [s, 1.0 - t]
    }

    /// MikkTSpace gives no tangent space to a corner of a degenerate triangle that has no
    /// neighbour to borrow one from (None), and may give a zero one: such corners get an
    /// arbitrary unit tangent perpendicular to their normal, as in [`orthonormal_tangents`].
    fn set_tangent(&mut self, space: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        let normal = Vec3::from(self.vertex(face, vert).normal).try_normalize().unwrap_or(Vec3::Z);
        if let Some(slot) = self.corner_tangents.get_mut(face * 3 + vert) {
            let t = space.map_or(Vec4::ZERO, |s| Vec4::from(s.tangent_encoded()));
            let xyz = t.truncate().try_normalize().unwrap_or_else(|| normal.any_orthonormal_vector());
            *slot = xyz.extend(if t.w < 0.0 { -1.0 } else { 1.0 }).to_array();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(p: [f32; 3], uv: [f32; 2]) -> Vertex {
        Vertex { position: p, normal: [0.0, 0.0, 1.0], uv0: uv, ..Default::default() }
    }

    /// A unit quad in the XY plane facing +Z, UVs with u along +X and v along -Y (glTF's
    /// v-down image convention).
    fn quad() -> (Vec<Vertex>, Vec<u32>) {
        let vertices = vec![
            vertex([0.0, 0.0, 0.0], [0.0, 1.0]),
            vertex([1.0, 0.0, 0.0], [1.0, 1.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 0.0]),
            vertex([0.0, 1.0, 0.0], [0.0, 0.0]),
        ];
        (vertices, vec![0, 1, 2, 0, 2, 3])
    }

    #[test]
    fn flat_normals_unweld_and_face_outwards() {
        let (mut vertices, mut indices) = quad();
        for v in &mut vertices {
            v.normal = [0.0; 3];
        }
        flat_normals(&mut vertices, &mut indices);
        assert_eq!(vertices.len(), 6);
        assert_eq!(indices, vec![0, 1, 2, 3, 4, 5]);
        assert!(vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
        assert_eq!(vertices[4].position, [1.0, 1.0, 0.0]);
    }

    #[test]
    fn degenerate_triangles_get_a_finite_normal() {
        let p = vertex([1.0, 2.0, 3.0], [0.0; 2]);
        let mut vertices = vec![p, p, p];
        let mut indices = vec![0, 1, 2];
        flat_normals(&mut vertices, &mut indices);
        assert!(vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
    }

    #[test]
    fn mikktspace_follows_u() {
        let (mut vertices, mut indices) = quad();
        assert!(mikktspace_tangents(&mut vertices, &mut indices, 0));
        assert_eq!(vertices.len(), 4, "a smooth quad needs no split");
        for v in &vertices {
            // glTF: the bitangent cross(N, T) * w points up the image (towards v = 0), +Y here.
            let t = Vec4::from(v.tangent);
            assert!(t.truncate().abs_diff_eq(Vec3::X, 1e-5), "{t:?}");
            assert_eq!(t.w, 1.0);
        }
    }

    #[test]
    fn degenerate_triangles_get_a_unit_tangent_perpendicular_to_the_normal() {
        // All three corners at one point with one UV: MikkTSpace has no tangent space for them.
        let n = Vec3::new(0.0, 0.6, 0.8);
        let corner = Vertex { position: [1.0, 2.0, 3.0], normal: n.to_array(), uv0: [0.5; 2], ..Default::default() };
        let mut vertices = vec![corner; 3];
        let mut indices = vec![0, 1, 2];
        assert!(mikktspace_tangents(&mut vertices, &mut indices, 0));
        for v in &vertices {
            let t = Vec4::from(v.tangent);
            assert!(t.truncate().is_normalized() && t.truncate().dot(n).abs() < 1e-6, "{t:?}");
            assert!(t.w == 1.0 || t.w == -1.0, "{t:?}");
        }
    }

    #[test]
    fn mirrored_uvs_split_shared_vertices() {
        // Two quads sharing the edge x = 1; the right one has u mirrored.
        let mut vertices = vec![
            vertex([0.0, 0.0, 0.0], [0.0, 1.0]),
            vertex([1.0, 0.0, 0.0], [1.0, 1.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 0.0]),
            vertex([0.0, 1.0, 0.0], [0.0, 0.0]),
            vertex([2.0, 0.0, 0.0], [0.0, 1.0]),
            vertex([2.0, 1.0, 0.0], [0.0, 0.0]),
        ];
        let mut indices = vec![0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2];
        assert!(mikktspace_tangents(&mut vertices, &mut indices, 0));
        assert_eq!(vertices.len(), 8, "the two shared vertices are split");
        for tri in indices.chunks_exact(3) {
            let ts: Vec<Vec4> = tri.iter().map(|&i| Vec4::from(vertices[i as usize].tangent)).collect();
            assert!(ts.iter().all(|t| *t == ts[0]), "{ts:?}");
        }
    }

    #[test]
    fn uv_set_one_is_used_when_asked() {
        let (mut vertices, mut indices) = quad();
        for v in &mut vertices {
            // Set 1 has u along +Y.
            v.uv1 = [v.position[1], v.position[0]];
            v.uv0 = [0.0; 2];
        }
        assert!(mikktspace_tangents(&mut vertices, &mut indices, 1));
        let t = Vec4::from(vertices[0].tangent);
        assert!(t.truncate().abs_diff_eq(Vec3::Y, 1e-5), "{t:?}");
    }

    #[test]
    fn mikktspace_is_refused_where_it_would_take_quadratic_time() {
        // A 200 x 200 grid: every position is shared by at most six corners.
        let n = 200;
        let grid: Vec<Vertex> = (0..n * n).map(|i| vertex([(i % n) as f32, (i / n) as f32, 0.0], [0.0; 2])).collect();
        let quads = (0..n - 1).flat_map(|y| (0..n - 1).map(move |x| y * n + x));
        let indices: Vec<u32> = quads.flat_map(|i| [i, i + 1, i + n + 1, i, i + n + 1, i + n]).collect();
        assert!(mikktspace_is_tractable(&grid, &indices));
        // The same corners all at the origin (with -0 and +0 mixed): n^4 pairs.
        let zero = |i: u32| if i.is_multiple_of(2) { 0.0 } else { -0.0 };
        let origin: Vec<Vertex> = (0..n * n).map(|i| vertex([zero(i), 0.0, 0.0], [0.0; 2])).collect();
        assert!(!mikktspace_is_tractable(&origin, &indices));
        // A small mesh is always fine, however degenerate.
        assert!(mikktspace_is_tractable(&origin[..3], &indices[..3]));
    }

    #[test]
    fn orthonormal_tangents_are_perpendicular_unit_vectors() {
        let mut vertices = vec![Vertex { normal: [0.3, -0.5, 0.8], ..Default::default() }];
        orthonormal_tangents(&mut vertices);
        let n = Vec3::from(vertices[0].normal).normalize();
        let t = Vec4::from(vertices[0].tangent);
        assert!(t.truncate().is_normalized());
        assert!(t.truncate().dot(n).abs() < 1e-6);
        assert_eq!(t.w, 1.0);
    }

    #[test]
    fn normalize_normals_repairs_zero_normals() {
        let mut vertices = vec![
            Vertex { normal: [0.0, 2.0, 0.0], ..Default::default() },
            Vertex { normal: [0.0; 3], ..Default::default() },
        ];
        normalize_normals(&mut vertices);
        assert_eq!(vertices[0].normal, [0.0, 1.0, 0.0]);
        assert_eq!(vertices[1].normal, [0.0, 0.0, 1.0]);
    }
}
