//! reflections: the specular lobe, GGX visible-normal sampled, with a roughness cut-off above
//! which no rays are traced and gi's estimate of the lobe stands in
//! (shaders-glsl/reflections.comp).

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gbuffer;
use super::radiance_cache::Cache;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "reflections";
/// The specular lobe's contribution (Fresnel and shadowing included).
pub const RADIANCE: Output = Output::new(NAME, "radiance");
/// Where the specular signal's history is, along the view ray beyond the surface: the
/// reflection's mean hit distance, or 0 (the surface itself).
pub const HIT_DISTANCE: Output = Output::new(NAME, "hit_distance");
/// What the pixel shows through its surface (glass's transmitted light, a blended surface's
/// uncovered share), in rgb, ready to add; in alpha how far along the view ray beyond the
/// surface it was seen, where its history is (0: the path escaped, or a lens turned it: the
/// surface). 1x1 and unwritten where no material lets anything through (the plan's
/// `let_through`).
pub const LET_THROUGH: Output = Output::new(NAME, "let_through");

/// reflections.comp's push-constant block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub rays: u32,
    pub roughness_cutoff: f32,
    pub seed: u32,
    pub bounces: u32,
    /// 1: write `LET_THROUGH` (it is full size), and leave it out of `RADIANCE`.
    pub let_through: u32,
}

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

/// `rough_specular`: gi's estimate of the lobe (gi.specular, or zero), passed on above the
/// cut-off (bound as `in_specular`). `cache`: the radiance cache, which adds the indirect light
/// of what the rays hit; without it the path goes on for `bounces` vertices (gi's setting).
/// `let_through`: some surface lets light through (`LET_THROUGH`).
pub fn new(
    b: &PassBuilder,
    s: &ReflectionSettings,
    seed: u32,
    rough_specular: Resource,
    cache: &Cache,
    bounces: u32,
    let_through: bool,
) -> Result<FullscreenPass> {
    let mut inputs: Vec<Input> =
        [gbuffer::DEPTH, gbuffer::NORMAL, gbuffer::NORMAL_GEO, gbuffer::BASE_COLOR, gbuffer::METAL_ROUGH, gbuffer::IDS]
            .map(Input::texel)
            .to_vec();
    inputs.push(Input::texel(rough_specular).bound_as("in_specular"));
    let through = OutputDesc::storage(LET_THROUGH, vk::Format::R32G32B32A32_SFLOAT, Preview::Color);
    let outputs = vec![
        OutputDesc::storage(RADIANCE, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(HIT_DISTANCE, vk::Format::R32_SFLOAT, Preview::Depth),
        if let_through { through } else { through.with_extent(1, 1) },
    ];
    let push = Params {
        rays: s.rays.max(1),
        roughness_cutoff: s.roughness_cutoff,
        seed,
        bounces,
        let_through: let_through as u32,
    };
    FullscreenPass::with_buffers(b, NAME, &b.traced_shader("reflections.comp"), inputs, outputs, cache.buffers(), &push)
}
