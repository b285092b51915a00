//! Morton (Z-order) ordering of a mesh's triangles, for the hardware backend.
//!
//! lavapipe's BLAS builder splits triangles in half by index without sorting them spatially,
//! so a mesh with randomly ordered triangles traces ~100x slower there. Uploading the index
//! buffer in Morton order of the triangle centroids gives its index halves spatial coherence.

use glam::Vec3;

/// A permutation of triangle indices (0..indices.len() / 3) sorted by the 30-bit Morton code
/// (10 bits per axis, x most significant) of each triangle's centroid, quantized within the
/// bounds of the centroids (inside the mesh bounds and tighter, so every bit is used); ties
/// keep index order. Triangles with out-of-range indices or non-finite vertices sort as code 0.
pub fn morton_order(positions: &[Vec3], indices: &[u32]) -> Vec<u32> {
    let vertex = |i: u32| positions.get(i as usize).copied().unwrap_or(Vec3::NAN);
    let centroids: Vec<Vec3> =
        indices.chunks_exact(3).map(|t| (vertex(t[0]) + vertex(t[1]) + vertex(t[2])) / 3.0).collect();
    let (lo, hi) = centroids
        .iter()
        .filter(|c| c.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
    let size = hi - lo;
    // 1023.99 rather than 1024 keeps the maximum inside 10 bits; flat axes quantize to 0.
    let scale = Vec3::select(size.cmpgt(Vec3::ZERO), 1023.99 / size, Vec3::ZERO);
    let mut keyed: Vec<(u32, u32)> = centroids
        .iter()
        .enumerate()
        .map(|(t, c)| {
            // `as u32` saturates, and maps NaN to 0.
            let q = ((*c - lo) * scale).to_array().map(|x| x as u32);
            (spread_bits(q[0]) << 2 | spread_bits(q[1]) << 1 | spread_bits(q[2]), t as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, t)| t).collect()
}

/// Spreads the low 10 bits of `x` to every third bit (bit i goes to bit 3i).
fn spread_bits(x: u32) -> u32 {
    let mut x = x & 0x3FF;
    x = (x | x << 16) & 0x0300_00FF;
    x = (x | x << 8) & 0x0300_F00F;
    x = (x | x << 4) & 0x030C_30C3;
    (x | x << 2) & 0x0924_9249
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::rays::SplitMix64;

    #[test]
    fn spreads_bits() {
        assert_eq!(spread_bits(0b1), 0b1);
        assert_eq!(spread_bits(0b11), 0b1001);
        assert_eq!(spread_bits(0x3FF), 0x0924_9249);
    }

    #[test]
    fn orders_a_grid_along_the_z_curve() {
        // Four unit triangles at the corners of a square, listed in scrambled order.
        let corners = [(1.0, 1.0), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
        let mut positions = Vec::new();
        for (x, y) in corners {
            positions.extend([Vec3::new(x, y, 0.0), Vec3::new(x + 0.1, y, 0.0), Vec3::new(x, y + 0.1, 0.0)]);
        }
        let indices: Vec<u32> = (0..12).collect();
        // x is the most significant axis, then y: (0,0), (0,1), (1,0), (1,1).
        assert_eq!(morton_order(&positions, &indices), vec![1, 3, 2, 0]);
    }

    #[test]
    fn is_a_permutation_that_improves_locality() {
        let mut rng = SplitMix64::new(5);
        let n = 20_000;
        let positions: Vec<Vec3> = (0..3 * n).map(|_| Vec3::new(rng.unit(), rng.unit(), rng.unit())).collect();
        let mut indices: Vec<u32> = (0..3 * n as u32).collect();
        // One triangle with a NaN vertex and one with a bad index still get a place.
        indices[0] = u32::MAX;
        let order = morton_order(&positions, &indices);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n as u32).collect::<Vec<_>>());
        let centroid = |t: u32| {
            let t = t as usize;
            (positions[3 * t] + positions[3 * t + 1] + positions[3 * t + 2]) / 3.0
        };
        let walk = |seq: &[u32]| -> f32 {
            let valid: Vec<u32> = seq.iter().copied().filter(|&t| t != 0).collect();
            valid.windows(2).map(|w| centroid(w[0]).distance(centroid(w[1]))).sum()
        };
        let identity: Vec<u32> = (0..n as u32).collect();
        let (before, after) = (walk(&identity), walk(&order));
        assert!(after * 10.0 < before, "walk {before} -> {after}");
    }

    #[test]
    fn degenerate_inputs() {
        assert!(morton_order(&[], &[]).is_empty());
        let p = [Vec3::ONE; 3];
        assert_eq!(morton_order(&p, &[0, 1, 2, 0, 1, 2]), vec![0, 1]);
    }
}
