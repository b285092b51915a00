//! composite: the frame in linear HDR (shaders-glsl/composite.comp): emission, punctual lights
//! and mesh lights with their ray-traced visibility (and its colour through tinted glass), the
//! diffuse signal remodulated by the albedo, and the specular signal.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::{gbuffer, shadows};
use crate::gpu::vk;
use crate::graph::{self, Output, OutputDesc, Preview, Resource};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "composite";
pub const COLOR: Output = Output::new(NAME, "color");

/// The push-constant block of composite.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    /// 1: `shadows.tint` colours the visibility (the frame plan's `tinted_shadows`).
    tinted: u32,
    /// The reflections pass's: a mesh light's specular lobe on surfaces at or under it is the
    /// reflection rays', above it composite's.
    roughness_cutoff: f32,
    /// 1: `let_through` is full size and added.
    let_through: u32,
    _pad: u32,
    mesh_lights: shadows::MeshLights,
}

/// The signals composite adds, denoised or not: `diffuse`, demodulated diffuse light (gi);
/// `specular`, the specular lobe's ray-traced light (reflections); `let_through`, what glass
/// and blended surfaces let through (reflections), where some do.
pub struct Signals {
    pub diffuse: Resource,
    pub specular: Resource,
    pub let_through: Option<Resource>,
}

/// `visibility`: the shadows chain's output (see shadows::Chain); `tinted`: the chain writes
/// `shadows.tint`; `mesh_lights`: the chain's channels that are mesh lights.
pub fn new(
    b: &PassBuilder,
    visibility: Resource,
    tinted: bool,
    mesh_lights: shadows::MeshLights,
    roughness_cutoff: f32,
    signals: Signals,
) -> Result<FullscreenPass> {
    let mut inputs: Vec<Input> =
        [gbuffer::DEPTH, gbuffer::NORMAL, gbuffer::BASE_COLOR, gbuffer::METAL_ROUGH, gbuffer::EMISSIVE, gbuffer::IDS]
            .map(Input::texel)
            .to_vec();
    inputs.extend([
        Input::texel(visibility).bound_as("in_visibility"),
        Input::texel(shadows::TINT),
        // Sampled (texelFetch): denoised, they are half precision; raw, full.
        Input::filtered(signals.diffuse).bound_as("in_diffuse"),
        Input::filtered(signals.specular).bound_as("in_specular"),
        Input::filtered(signals.let_through.unwrap_or(graph::zero(vk::Format::R32G32B32A32_SFLOAT, true)))
            .bound_as("in_let_through"),
    ]);
    let outputs = vec![OutputDesc::storage(COLOR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color)];
    FullscreenPass::new(
        b,
        NAME,
        "composite.comp",
        inputs,
        outputs,
        &Params {
            tinted: tinted as u32,
            roughness_cutoff,
            let_through: signals.let_through.is_some() as u32,
            _pad: 0,
            mesh_lights,
        },
    )
}
