//! Morph targets (glTF "blend shapes"): a deforming mesh is its base vertices plus weighted
//! per-vertex position and normal deltas, the weights animated over time.
//!
//! Deformation is evaluated on the CPU ([`Morph::deform`]), once per frame that changes the
//! weights, and the result written over the mesh's vertices in the GPU vertex buffer: the
//! raster passes, the shading passes and both ray backends then read one and the same
//! geometry, and the compute backend's BVH refit needs the positions on the CPU anyway.

use super::Vertex;
use super::animation::Interpolation;
use glam::Vec3;

/// One target's deltas, one per vertex of the mesh; an empty list when the target does not
/// move that attribute.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// Keyframed weights of all of a morph's targets.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightChannel {
    pub interpolation: Interpolation,
    /// Key times in seconds, ascending.
    pub times: Vec<f32>,
    /// One weight per target and key, key-major; cubic splines store per key the in-tangents,
    /// the values and the out-tangents, each a run of one weight per target (glTF's layout).
    pub values: Vec<f32>,
    /// The channel loops with this period: the duration of the animation it came from, as
    /// node animations loop over theirs ([`super::Scene::evaluate`]).
    pub period: f32,
}

/// The targets of one deforming mesh and what drives their weights.
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    /// Index into `Scene::meshes`.
    pub mesh: u32,
    pub targets: Vec<MorphTarget>,
    /// Weights when no channel drives them (glTF: the node's `weights`, else the mesh's).
    pub weights: Vec<f32>,
    /// At most one is applied: a later channel overrides an earlier one, as a later glTF
    /// channel targeting the same node's weights does.
    pub channels: Vec<WeightChannel>,
}

impl WeightChannel {
    /// The weights at `time` (looped over `period`), or `None` when the keys and values do
    /// not fit `targets` weights per key.
    pub fn sample(&self, time: f32, targets: usize) -> Option<Vec<f32>> {
        let stride = if self.interpolation == Interpolation::CubicSpline { 3 * targets } else { targets };
        let n = self.times.len();
        if n == 0 || targets == 0 || self.values.len() != n * stride {
            return None;
        }
        let value_at = if self.interpolation == Interpolation::CubicSpline { targets } else { 0 };
        let key = |k: usize| &self.values[k * stride + value_at..k * stride + value_at + targets];
        let t = if self.period > 0.0 { time.rem_euclid(self.period) } else { 0.0 };
        // Index of the first key after t; NaN compares false and so samples the first key.
        let next = self.times.partition_point(|&k| k <= t);
        if next == 0 {
            return Some(key(0).to_vec());
        }
        if next >= n {
            return Some(key(n - 1).to_vec());
        }
        let k = next - 1;
        let dt = self.times[next] - self.times[k];
        let s = if dt > 0.0 { ((t - self.times[k]) / dt).clamp(0.0, 1.0) } else { 0.0 };
        let (a, b) = (key(k), key(next));
        Some(match self.interpolation {
            Interpolation::Step => a.to_vec(),
            Interpolation::Linear => a.iter().zip(b).map(|(a, b)| a + (b - a) * s).collect(),
            Interpolation::CubicSpline => {
                let out_tangent = &self.values[k * stride + 2 * targets..k * stride + 3 * targets];
                let in_tangent = &self.values[next * stride..next * stride + targets];
                let (s2, s3) = (s * s, s * s * s);
                (0..targets)
                    .map(|i| {
                        (2.0 * s3 - 3.0 * s2 + 1.0) * a[i]
                            + (s3 - 2.0 * s2 + s) * dt * out_tangent[i]
                            + (-2.0 * s3 + 3.0 * s2) * b[i]
                            + (s3 - s2) * dt * in_tangent[i]
                    })
                    .collect()
            }
        })
    }
}

impl Morph {
    /// The target weights at `time`: the last channel that samples, else the defaults. Always
    /// one weight per target; non-finite weights count as 0.
    pub fn weights_at(&self, time: f32) -> Vec<f32> {
        let sampled = self.channels.iter().rev().find_map(|c| c.sample(time, self.targets.len()));
        let mut w = sampled.unwrap_or_else(|| self.weights.clone());
        w.resize(self.targets.len(), 0.0);
        for x in &mut w {
            if !x.is_finite() {
                *x = 0.0;
            }
        }
        w
    }

    /// The base vertices moved by the weighted deltas; normals are renormalised (a normal
    /// that cancels out keeps the base one). Tangents and texture coordinates are the base's.
    pub fn deform(&self, base: &[Vertex], weights: &[f32]) -> Vec<Vertex> {
        let mut out = base.to_vec();
        for (target, &w) in self.targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            for (v, d) in out.iter_mut().zip(&target.positions) {
                v.position = (Vec3::from(v.position) + *d * w).to_array();
            }
            for (v, d) in out.iter_mut().zip(&target.normals) {
                v.normal = (Vec3::from(v.normal) + *d * w).to_array();
            }
        }
        if self.targets.iter().any(|t| !t.normals.is_empty()) {
            for (v, b) in out.iter_mut().zip(base) {
                v.normal = Vec3::from(v.normal).try_normalize().unwrap_or(Vec3::from(b.normal)).to_array();
            }
        }
        out
    }

    /// Whether anything changes the weights over time.
    pub fn is_animated(&self) -> bool {
        !self.channels.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(interpolation: Interpolation, times: Vec<f32>, values: Vec<f32>) -> WeightChannel {
        WeightChannel { interpolation, times, values, period: 2.0 }
    }

    #[test]
    fn samples_linear_step_and_cubic() {
        let lin = channel(Interpolation::Linear, vec![0.0, 1.0], vec![0.0, 1.0, 1.0, 0.0]);
        assert_eq!(lin.sample(0.25, 2), Some(vec![0.25, 0.75]));
        // Past the last key the last value holds; the period wraps time.
        assert_eq!(lin.sample(1.5, 2), Some(vec![1.0, 0.0]));
        assert_eq!(lin.sample(2.25, 2), Some(vec![0.25, 0.75]));
        let step = channel(Interpolation::Step, vec![0.0, 1.0], vec![0.0, 1.0, 1.0, 0.0]);
        assert_eq!(step.sample(0.9, 2), Some(vec![0.0, 1.0]));
        // Zero tangents: smoothstep between the values.
        let cubic = channel(Interpolation::CubicSpline, vec![0.0, 1.0], vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let mid = cubic.sample(0.5, 1).expect("fits")[0];
        assert!((mid - 0.5).abs() < 1e-6);
        // A count mismatch samples nothing.
        assert_eq!(lin.sample(0.5, 3), None);
    }

    #[test]
    fn deforms_positions_and_normals() {
        let base = vec![Vertex { position: [0.0, 0.0, 0.0], normal: [0.0, 0.0, 1.0], ..Default::default() }; 2];
        let morph = Morph {
            mesh: 0,
            targets: vec![
                MorphTarget { positions: vec![Vec3::X, Vec3::Y], normals: vec![Vec3::X, Vec3::ZERO] },
                MorphTarget { positions: vec![Vec3::Z, Vec3::ZERO], normals: Vec::new() },
            ],
            weights: vec![0.5, 2.0],
            channels: Vec::new(),
        };
        let w = morph.weights_at(3.0);
        assert_eq!(w, vec![0.5, 2.0]);
        let v = morph.deform(&base, &w);
        assert_eq!(v[0].position, [0.5, 0.0, 2.0]);
        assert_eq!(v[1].position, [0.0, 0.5, 0.0]);
        let n = Vec3::from(v[0].normal);
        assert!((n - Vec3::new(0.5, 0.0, 1.0).normalize()).length() < 1e-6);
        assert_eq!(v[1].normal, [0.0, 0.0, 1.0]);
    }
}
