//! gi: diffuse global illumination, one bounce ray per pixel with next-event estimation and the
//! radiance cache at its hit for every further bounce, demodulated by the diffuse albedo
//! (shaders-glsl/gi.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gbuffer;
use super::radiance_cache::Cache;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "gi";
/// Demodulated diffuse radiance: direct light from emitters and the environment, and indirect.
pub const RADIANCE: Output = Output::new(NAME, "radiance");
/// The specular lobe of surfaces rougher than the reflection cut-off, from the same samples.
pub const SPECULAR: Output = Output::new(NAME, "specular");

/// gi.comp's push-constant block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub bounces: u32,
    pub seed: u32,
    pub roughness_cutoff: f32,
}

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
    let inputs =
        [gbuffer::DEPTH, gbuffer::NORMAL, gbuffer::NORMAL_GEO, gbuffer::BASE_COLOR, gbuffer::METAL_ROUGH, gbuffer::IDS]
            .map(Input::texel)
            .to_vec();
    let outputs = vec![
        OutputDesc::storage(RADIANCE, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(SPECULAR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
    ];
    let push = Params { bounces: s.bounces.max(1), seed, roughness_cutoff };
    FullscreenPass::with_buffers(b, NAME, &b.traced_shader("gi.comp"), inputs, outputs, cache.buffers(), &push)
}
