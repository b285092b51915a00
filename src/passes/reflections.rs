//! reflections: the specular lobe, GGX visible-normal sampled, with a roughness cut-off above
//! which no rays are traced and gi's estimate of the lobe stands in
//! (shaders-glsl/reflections.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Read};
use super::radiance_cache::Cache;
use crate::gpu::vk;
use crate::graph::{OutputDesc, Preview};
use anyhow::Result;

pub const NAME: &str = "reflections";
/// The specular lobe's contribution (Fresnel and shadowing included).
pub const RADIANCE: &str = "reflections.radiance";

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ReflectionSettings {
    /// Specular rays per pixel.
    pub rays: u32,
    /// Surfaces rougher than this trace no reflection rays (gi estimates their lobe).
    pub roughness_cutoff: f32,
}

impl Default for ReflectionSettings {
    fn default() -> Self {
        Self { rays: 1, roughness_cutoff: 0.6 }
    }
}

/// `rough_specular`: gi's estimate of the lobe (gi.specular), passed on above the cut-off.
/// `cache`: the radiance cache, which adds the indirect light of what the rays hit; without it
/// the path goes on for `bounces` vertices (gi's setting).
pub fn new(
    b: &PassBuilder,
    s: &ReflectionSettings,
    seed: u32,
    rough_specular: &str,
    cache: &Cache,
    bounces: u32,
) -> Result<FullscreenPass> {
    let inputs = [
        "gbuffer.depth",
        "gbuffer.normal",
        "gbuffer.normal_geo",
        "gbuffer.base_color",
        "gbuffer.metal_rough",
        "gbuffer.ids",
        rough_specular,
    ]
    .map(|n| (n.to_string(), Read::Texel))
    .to_vec();
    let outputs = vec![
        OutputDesc::storage(NAME, "radiance", vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(NAME, "hit_distance", vk::Format::R32_SFLOAT, Preview::Depth),
    ];
    let mut push = Vec::new();
    push.extend_from_slice(&s.rays.max(1).to_le_bytes());
    push.extend_from_slice(&s.roughness_cutoff.to_le_bytes());
    push.extend_from_slice(&seed.to_le_bytes());
    push.extend_from_slice(&bounces.to_le_bytes());
    FullscreenPass::with_buffers(b, NAME, &b.traced_shader("reflections.comp"), inputs, outputs, cache.buffers(), push)
}
