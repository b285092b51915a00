//! Keyframed node animation: one [`Channel`] drives one property of one node, sampled as the
//! glTF 2.0 specification describes (its appendix "Interpolation" for cubic splines).

use glam::{Quat, Vec3, Vec4};

/// The node property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Holds each key's value until the next key.
    Step,
    /// Lerp for translation and scale, shortest-path slerp for rotation.
    Linear,
    /// Cubic Hermite spline with per-key in- and out-tangents.
    CubicSpline,
}

/// Keyframes for one property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    /// Index into `Scene::nodes`.
    pub node: u32,
    pub property: Property,
    pub interpolation: Interpolation,
    /// Key times in seconds, ascending.
    pub times: Vec<f32>,
    /// One value per key (xyz for translation and scale, xyzw quaternion for rotation); three
    /// per key for cubic splines: in-tangent, value, out-tangent.
    pub values: Vec<Vec4>,
}

impl Channel {
    /// Time of the last key.
    pub fn duration(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Writes the channel's value at time `t` into the node's local (translation, rotation,
    /// scale). Before the first key the first value holds, after the last key the last.
    /// A channel whose keys and values disagree in number, or whose node is out of range,
    /// changes nothing.
    pub fn apply(&self, t: f32, locals: &mut [(Vec3, Quat, Vec3)]) {
        let Some(value) = self.sample(t) else {
            return;
        };
        if !value.is_finite() {
            return;
        }
        let Some(local) = locals.get_mut(self.node as usize) else {
            return;
        };
        match self.property {
            Property::Translation => local.0 = value.truncate(),
            Property::Rotation => {
                let q = Quat::from_vec4(value);
                // A spline may pass through (or a file may contain) a zero quaternion, which
                // has no rotation to normalise to: keep the previous pose rather than NaNs.
                if q.length_squared() > 0.0 {
                    local.1 = q.normalize();
                }
            }
            Property::Scale => local.2 = value.truncate(),
        }
    }

    /// Values per key in `values`.
    fn stride(&self) -> usize {
        match self.interpolation {
            Interpolation::CubicSpline => 3,
            Interpolation::Step | Interpolation::Linear => 1,
        }
    }

    /// The value (not a tangent) of key `k`.
    fn key_value(&self, k: usize) -> Option<Vec4> {
        let offset = usize::from(self.interpolation == Interpolation::CubicSpline);
        self.values.get(k * self.stride() + offset).copied()
    }

    fn sample(&self, t: f32) -> Option<Vec4> {
        let n = self.times.len();
        if n == 0 || self.values.len() != n * self.stride() {
            return None;
        }
        // Index of the first key after t; NaN compares false and so samples the first key.
        let next = self.times.partition_point(|&key| key <= t);
        if next == 0 {
            return self.key_value(0);
        }
        if next >= n {
            return self.key_value(n - 1);
        }
        let k = next - 1;
        let t0 = self.times[k];
        let dt = self.times[next] - t0;
        let s = if dt > 0.0 { ((t - t0) / dt).clamp(0.0, 1.0) } else { 0.0 };
        match self.interpolation {
            Interpolation::Step => self.key_value(k),
            Interpolation::Linear => self.linear(k, s),
            Interpolation::CubicSpline => self.cubic(k, s, dt),
        }
    }

    fn linear(&self, k: usize, s: f32) -> Option<Vec4> {
        let a = self.key_value(k)?;
        let b = self.key_value(k + 1)?;
        Some(match self.property {
            Property::Rotation => slerp(a, b, s),
            Property::Translation | Property::Scale => a.lerp(b, s),
        })
    }

    /// Hermite spline between keys k and k + 1; tangents are scaled by the key spacing `dt`.
    fn cubic(&self, k: usize, s: f32, dt: f32) -> Option<Vec4> {
        let v0 = self.values.get(3 * k + 1)?;
        let out0 = self.values.get(3 * k + 2)?;
        let in1 = self.values.get(3 * k + 3)?;
        let v1 = self.values.get(3 * k + 4)?;
        let s2 = s * s;
        let s3 = s2 * s;
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        Some(*v0 * h00 + *out0 * (h10 * dt) + *v1 * h01 + *in1 * (h11 * dt))
    }
}

/// Shortest-path spherical interpolation of two xyzw quaternions.
fn slerp(a: Vec4, b: Vec4, s: f32) -> Vec4 {
    let qa = Quat::from_vec4(a);
    let qb = Quat::from_vec4(b);
    if qa.length_squared() == 0.0 || qb.length_squared() == 0.0 {
        return a.lerp(b, s);
    }
    Vec4::from(qa.normalize().slerp(qb.normalize(), s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    fn channel(property: Property, interpolation: Interpolation, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { node: 0, property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    fn identity() -> Vec<(Vec3, Quat, Vec3)> {
        vec![(Vec3::ZERO, Quat::IDENTITY, Vec3::ONE)]
    }

    #[test]
    fn linear_translation_interpolates_and_clamps() {
        let ch = channel(
            Property::Translation,
            Interpolation::Linear,
            &[1.0, 3.0],
            &[Vec4::ZERO, Vec4::new(2.0, 4.0, 6.0, 0.0)],
        );
        let mut locals = identity();
        ch.apply(2.0, &mut locals);
        assert!(locals[0].0.abs_diff_eq(Vec3::new(1.0, 2.0, 3.0), 1e-6));
        ch.apply(0.0, &mut locals);
        assert_eq!(locals[0].0, Vec3::ZERO);
        ch.apply(10.0, &mut locals);
        assert_eq!(locals[0].0, Vec3::new(2.0, 4.0, 6.0));
        assert_eq!(ch.duration(), 3.0);
    }

    #[test]
    fn step_holds_the_previous_key() {
        let ch = channel(Property::Scale, Interpolation::Step, &[0.0, 1.0], &[Vec4::splat(1.0), Vec4::splat(2.0)]);
        let mut locals = identity();
        ch.apply(0.99, &mut locals);
        assert_eq!(locals[0].2, Vec3::ONE);
        ch.apply(1.0, &mut locals);
        assert_eq!(locals[0].2, Vec3::splat(2.0));
    }

    #[test]
    fn linear_rotation_takes_the_shortest_path() {
        let a = Quat::from_rotation_z(0.0);
        // -q is the same rotation as q; slerp must not swing the long way round.
        let b = -Quat::from_rotation_z(FRAC_PI_2);
        let ch = channel(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &[Vec4::from(a), Vec4::from(b)]);
        let mut locals = identity();
        ch.apply(0.5, &mut locals);
        let expected = Quat::from_rotation_z(FRAC_PI_2 / 2.0);
        assert!(locals[0].1.is_normalized());
        assert!(locals[0].1.dot(expected).abs() > 0.9999, "{:?}", locals[0].1);
    }

    #[test]
    fn cubic_spline_hits_keys_and_follows_tangents() {
        // Values 0 -> 1 with zero tangents: a smoothstep, 0.5 at the midpoint.
        let z = Vec4::ZERO;
        let one = Vec4::new(1.0, 0.0, 0.0, 0.0);
        let ch = channel(Property::Translation, Interpolation::CubicSpline, &[0.0, 2.0], &[z, z, z, z, one, z]);
        let mut locals = identity();
        ch.apply(1.0, &mut locals);
        assert!((locals[0].0.x - 0.5).abs() < 1e-6);
        ch.apply(0.5, &mut locals);
        assert!((locals[0].0.x - 0.15625).abs() < 1e-6);
        ch.apply(2.0, &mut locals);
        assert_eq!(locals[0].0.x, 1.0);

        // Straight line v = t with unit tangents (per second): exact at every time.
        let slope = Vec4::new(1.0, 0.0, 0.0, 0.0);
        let two = Vec4::new(2.0, 0.0, 0.0, 0.0);
        let line = channel(
            Property::Translation,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[slope, z, slope, slope, two, slope],
        );
        line.apply(0.7, &mut locals);
        assert!((locals[0].0.x - 0.7).abs() < 1e-5);
    }

    #[test]
    fn cubic_rotation_is_normalised() {
        let a = Vec4::from(Quat::IDENTITY);
        let b = Vec4::from(Quat::from_rotation_y(1.0));
        let z = Vec4::ZERO;
        let ch = channel(Property::Rotation, Interpolation::CubicSpline, &[0.0, 1.0], &[z, a, z, z, b, z]);
        let mut locals = identity();
        ch.apply(0.5, &mut locals);
        assert!(locals[0].1.is_normalized());
    }

    #[test]
    fn inconsistent_channels_change_nothing() {
        let mut locals = identity();
        let too_few = channel(Property::Translation, Interpolation::CubicSpline, &[0.0], &[Vec4::ONE]);
        too_few.apply(0.0, &mut locals);
        let empty = channel(Property::Translation, Interpolation::Linear, &[], &[]);
        empty.apply(0.0, &mut locals);
        let mut wrong_node = channel(Property::Translation, Interpolation::Step, &[0.0], &[Vec4::ONE]);
        wrong_node.node = 5;
        wrong_node.apply(0.0, &mut locals);
        assert_eq!(locals[0].0, Vec3::ZERO);
        assert_eq!(empty.duration(), 0.0);
    }
}
