//! Animations: node transform and morph-weight channels, their samplers and key times, checked
//! and counted against the key budget.

use super::accessors::read_floats;
use super::{ANIMATION_SAMPLERS, Builder, NODES, lookup};
use crate::scene::animation::{Channel, Interpolation, Property};
use crate::scene::{Animation, SceneError, WeightChannel};
use glam::{Vec3, Vec4};
use gltf::json;
use gltf::json::validation::Checked;

// ---------------------------------------------------------------------------------------------
// Animations.

impl Builder<'_> {
    pub(super) fn animations(&mut self) -> Result<(), SceneError> {
        let root = self.data.root;
        for (a, animation) in root.animations.iter().enumerate() {
            let mut channels = Vec::with_capacity(animation.channels.len());
            let mut weights = Vec::new();
            for (c, channel) in animation.channels.iter().enumerate() {
                let path = format!("animations[{a}].channels[{c}]");
                if channel.target.path == Checked::Valid(json::animation::Property::MorphTargetWeights) {
                    weights.extend(self.weight_channel(a, animation, channel, &path)?);
                } else if let Some(channel) = self.channel(a, animation, channel, &path)? {
                    channels.push(channel);
                }
            }
            // Weights loop with the whole animation, as its node channels do.
            let period = weights
                .iter()
                .map(|(_, w): &(Vec<usize>, WeightChannel)| w.times.last().copied().unwrap_or(0.0))
                .fold(channels.iter().map(Channel::duration).fold(0.0, f32::max), f32::max);
            for (morphs, mut channel) in weights {
                channel.period = period;
                for k in morphs {
                    self.scene.morphs[k].channels.push(channel.clone());
                }
            }
            if !channels.is_empty() {
                let name = animation.name.clone().unwrap_or_else(|| format!("animation{a}"));
                self.scene.animations.push(Animation { name, channels });
            }
        }
        Ok(())
    }

    /// One channel; `None` for channels this renderer cannot play (with a warning) or that
    /// target nodes outside the loaded scene.
    pub(super) fn channel(
        &mut self,
        a: usize,
        animation: &json::Animation,
        channel: &json::animation::Channel,
        path: &str,
    ) -> Result<Option<Channel>, SceneError> {
        use json::animation::Property as P;
        let root = self.data.root;
        let s = channel.sampler.value();
        let sampler = lookup(&self.ctx, &animation.samplers, s, ANIMATION_SAMPLERS, &format!("{path}.sampler"))?;
        let target = channel.target.node.value();
        lookup(&self.ctx, &root.nodes, target, NODES, &format!("{path}.target.node"))?;
        let property = match channel.target.path {
            Checked::Valid(P::Translation) => Property::Translation,
            Checked::Valid(P::Rotation) => Property::Rotation,
            Checked::Valid(P::Scale) => Property::Scale,
            // Played by `weight_channel`.
            Checked::Valid(P::MorphTargetWeights) => return Ok(None),
            Checked::Invalid => {
                self.ctx.warn(format!("{path}.target.path: invalid; the channel is skipped"));
                return Ok(None);
            }
        };
        let Some(node) = self.scene_node.get(target).copied().flatten() else {
            log::debug!("{}: {path} animates a node outside the scene", self.ctx.file.display());
            return Ok(None);
        };
        let Some(interpolation) = self.interpolation(a, s, sampler) else {
            return Ok(None);
        };
        let spath = format!("animations[{a}].samplers[{s}]");
        let times = self.key_times(sampler, &spath)?;
        let output = sampler.output.value();
        let opath = format!("{spath}.output");
        let values: Vec<Vec4> = match property {
            Property::Rotation => {
                read_floats::<4>(&self.ctx, &self.data, output, &opath)?.into_iter().map(Vec4::from).collect()
            }
            Property::Translation | Property::Scale => read_floats::<3>(&self.ctx, &self.data, output, &opath)?
                .into_iter()
                .map(|v| Vec3::from(v).extend(0.0))
                .collect(),
        };
        self.count_animation_keys(values.len(), &spath)?;
        let channel = Channel { node, property, interpolation, times, values };
        match channel_defect(&channel) {
            Some(defect) => {
                self.ctx.warn(format!("{spath}: {defect}; the channel is skipped"));
                Ok(None)
            }
            None => Ok(Some(channel)),
        }
    }
}

impl Builder<'_> {
    /// A sampler's interpolation; `None` (with a warning) when invalid.
    pub(super) fn interpolation(
        &mut self,
        a: usize,
        s: usize,
        sampler: &json::animation::Sampler,
    ) -> Option<Interpolation> {
        match sampler.interpolation {
            Checked::Valid(json::animation::Interpolation::Step) => Some(Interpolation::Step),
            Checked::Valid(json::animation::Interpolation::Linear) => Some(Interpolation::Linear),
            Checked::Valid(json::animation::Interpolation::CubicSpline) => Some(Interpolation::CubicSpline),
            Checked::Invalid => {
                self.ctx.warn(format!("animations[{a}].samplers[{s}].interpolation: invalid; the channel is skipped"));
                None
            }
        }
    }

    pub(super) fn key_times(
        &mut self,
        sampler: &json::animation::Sampler,
        spath: &str,
    ) -> Result<Vec<f32>, SceneError> {
        let times = read_floats::<1>(&self.ctx, &self.data, sampler.input.value(), &format!("{spath}.input"))?;
        let times: Vec<f32> = times.into_iter().map(|[t]| t).collect();
        self.count_animation_keys(times.len(), spath)?;
        Ok(times)
    }

    /// A channel that animates morph target weights: the morphs it drives (those whose
    /// driver is the target node) and their weights; `None` when there are none or the
    /// channel cannot be played (with a warning).
    pub(super) fn weight_channel(
        &mut self,
        a: usize,
        animation: &json::Animation,
        channel: &json::animation::Channel,
        path: &str,
    ) -> Result<Option<(Vec<usize>, WeightChannel)>, SceneError> {
        let root = self.data.root;
        let s = channel.sampler.value();
        let sampler = lookup(&self.ctx, &animation.samplers, s, ANIMATION_SAMPLERS, &format!("{path}.sampler"))?;
        let target = channel.target.node.value();
        lookup(&self.ctx, &root.nodes, target, NODES, &format!("{path}.target.node"))?;
        let morphs: Vec<usize> =
            (0..self.morph_driver.len()).filter(|&k| self.morph_driver[k] == Some(target)).collect();
        let Some(&first) = morphs.first() else {
            if self.scene_node.get(target).copied().flatten().is_some() {
                self.ctx
                    .warn(format!("{path}: node {target} draws no morph targets of its own; the channel is skipped"));
            }
            return Ok(None);
        };
        let Some(interpolation) = self.interpolation(a, s, sampler) else {
            return Ok(None);
        };
        let spath = format!("animations[{a}].samplers[{s}]");
        let times = self.key_times(sampler, &spath)?;
        let values = read_floats::<1>(&self.ctx, &self.data, sampler.output.value(), &format!("{spath}.output"))?;
        let values: Vec<f32> = values.into_iter().map(|[v]| v).collect();
        self.count_animation_keys(values.len(), &spath)?;
        let per_key =
            self.scene.morphs[first].targets.len() * if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let defect = key_times_defect(&times).or_else(|| {
            if values.len() != times.len() * per_key {
                Some(format!("{} output values for {} keys of {per_key} weights", values.len(), times.len()))
            } else if !values.iter().all(|v| v.is_finite()) {
                Some("output values are not finite".into())
            } else {
                None
            }
        });
        if let Some(defect) = defect {
            self.ctx.warn(format!("{spath}: {defect}; the channel is skipped"));
            return Ok(None);
        }
        Ok(Some((morphs, WeightChannel { interpolation, times, values, period: 0.0 })))
    }

    /// Adds keyframe times or values to the scene total and checks the limit.
    pub(super) fn count_animation_keys(&mut self, added: usize, path: &str) -> Result<(), SceneError> {
        self.total_animation_keys += added as u64;
        let limit = self.ctx.limits().max_animation_keys;
        let what = format!("{path}: animation keys in the scene so far");
        self.ctx.check(&what, "max_animation_keys", self.total_animation_keys, limit)
    }
}

/// Why key times cannot be played, if they cannot.
pub(super) fn key_times_defect(times: &[f32]) -> Option<String> {
    if times.is_empty() {
        return Some("no keyframes".into());
    }
    if !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[0] > w[1]) {
        return Some("key times are not finite and ascending".into());
    }
    None
}

/// Why a channel cannot be played, if it cannot.
pub(super) fn channel_defect(channel: &Channel) -> Option<String> {
    let keys = channel.times.len();
    let per_key = if channel.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    if let Some(defect) = key_times_defect(&channel.times) {
        return Some(defect);
    }
    if channel.values.len() != keys * per_key {
        return Some(format!("{} output values for {keys} keys (expected {})", channel.values.len(), keys * per_key));
    }
    if !channel.values.iter().all(|v| v.is_finite()) {
        return Some("output values are not finite".into());
    }
    None
}
