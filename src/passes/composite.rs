//! composite: the frame in linear HDR (shaders-glsl/composite.comp): emission, punctual lights
//! and mesh lights with their ray-traced visibility (and its colour through tinted glass), the
//! diffuse signal remodulated by the albedo, and the specular signal.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::{gbuffer, shadows};
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Preview, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "composite";
pub const COLOR: Output = Output::new(NAME, "color");

/// `diffuse`: demodulated diffuse light (gi, denoised or not); `specular`: the specular lobe's
/// ray-traced light (reflections, denoised or not).
/// The push-constant block of composite.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    /// 1: `shadows.tint` colours the visibility (the frame plan's `tinted_shadows`).
    tinted: u32,
    /// The reflections pass's: a mesh light's specular lobe on surfaces at or under it is the
    /// reflection rays', above it composite's.
    roughness_cutoff: f32,
    _pad: [u32; 2],
    mesh_lights: shadows::MeshLights,
}

/// `visibility`: the shadows chain's output (see shadows::Chain); `tinted`: the chain writes
/// `shadows.tint`; `mesh_lights`: the chain's channels that are mesh lights.
pub fn new(
    b: &PassBuilder,
    visibility: Resource,
    tinted: bool,
    mesh_lights: shadows::MeshLights,
    roughness_cutoff: f32,
    diffuse: Resource,
    specular: Resource,
) -> Result<FullscreenPass> {
    let mut inputs: Vec<Input> =
        [gbuffer::DEPTH, gbuffer::NORMAL, gbuffer::BASE_COLOR, gbuffer::METAL_ROUGH, gbuffer::EMISSIVE, gbuffer::IDS]
            .map(Input::texel)
            .to_vec();
    inputs.extend([
        Input::texel(visibility).bound_as("in_visibility"),
        Input::texel(shadows::TINT),
        // Sampled (texelFetch): denoised, they are half precision; raw, full.
        Input::filtered(diffuse).bound_as("in_diffuse"),
        Input::filtered(specular).bound_as("in_specular"),
    ]);
    let outputs = vec![OutputDesc::storage(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    FullscreenPass::new(
        b,
        NAME,
        "composite.comp",
        inputs,
        outputs,
        &Params { tinted: tinted as u32, roughness_cutoff, _pad: [0; 2], mesh_lights },
    )
}
