//! gi: diffuse global illumination, one bounce ray per pixel with next-event estimation and the
//! radiance cache at its hit for every further bounce, demodulated by the diffuse albedo
//! (shaders-glsl/gi.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use super::radiance_cache::Cache;
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "gi";
/// Demodulated diffuse radiance: direct light from emitters and the environment, and indirect.
pub const RADIANCE: &str = "gi.radiance";
/// The specular lobe of surfaces rougher than the reflection cut-off, from the same samples.
pub const SPECULAR: &str = "gi.specular";

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct GiSettings {
    /// Path vertices traced after the primary surface before the radiance cache answers (1:
    /// the cache answers at the bounce ray's hit); with the cache off, the bounces traced.
    pub bounces: u32,
}

impl Default for GiSettings {
    fn default() -> Self {
        Self { bounces: 1 }
    }
}

/// `roughness_cutoff`: the reflections pass's; gi estimates the specular lobe above it.
pub fn new(b: &PassBuilder, s: &GiSettings, seed: u32, roughness_cutoff: f32, cache: &Cache) -> Result<FullscreenPass> {
    let inputs = [
        "gbuffer.depth",
        "gbuffer.normal",
        "gbuffer.normal_geo",
        "gbuffer.base_color",
        "gbuffer.metal_rough",
        "gbuffer.ids",
    ]
    .map(|n| (n.to_string(), Read::Texel))
    .to_vec();
    let outputs = vec![
        OutputDesc::storage(NAME, "radiance", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(NAME, "specular", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
    ];
    let mut push: Vec<u8> = [s.bounces.max(1), seed].iter().flat_map(|v| v.to_le_bytes()).collect();
    push.extend_from_slice(&roughness_cutoff.to_le_bytes());
    FullscreenPass::with_buffers(b, NAME, &b.traced_shader("gi.comp"), inputs, outputs, cache.buffers(), push)
}
