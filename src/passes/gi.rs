//! gi: diffuse global illumination, one bounce ray per pixel with next-event estimation and the
//! radiance cache at its hit for every further bounce, demodulated by the diffuse albedo
//! (shaders-glsl/gi.comp). It also shades the emissive triangles and the punctual lights past
//! the shadowed ones, one resampled per pixel with a reservoir kept across frames
//! (common/light_reservoir.glsl). At half or quarter rate gi_fill completes its signals.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input};
use super::gbuffer;
use super::gi_fill;
use super::history::{self, Kept};
use super::radiance_cache::Cache;
use crate::gpu::vk;
use crate::graph::{Output, OutputDesc, Pass, Preview};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const NAME: &str = "gi";
/// Demodulated diffuse radiance: direct light from the environment and the resampled lights
/// (emitters and punctual lights past the shadowed ones), and indirect.
/// At a reduced rate the untraced pixels are black, with what gi_fill needs in alpha.
pub const RADIANCE: Output = Output::new(NAME, "radiance");
/// The specular lobe of surfaces rougher than the reflection cut-off, from the same samples;
/// on every surface, the resampled punctual lights' share of it.
pub const SPECULAR: Output = Output::new(NAME, "specular");
/// Per pixel the resampled light chosen (its light-table entry), its contribution weight, the
/// candidates behind it and the point on the light, for the next frame (1x1 when no light is
/// resampled).
pub const RESERVOIR: Output = Output::new(NAME, "reservoir");
const RESERVOIR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Where last frame's resampled light, visible then, is in shadow now (an occluder the frame was
/// not told of): the luminance of what it brought to the diffuse (r) and specular (g) signals,
/// which restarts their SVGF histories and TAA's (1x1 when no light is resampled).
pub const LIGHT_LOST: Output = Output::new(NAME, "light_lost");

/// gi.comp's push-constant block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    pub bounces: u32,
    pub seed: u32,
    pub roughness_cutoff: f32,
    /// GiRate::pixels: 1, 2 or 4.
    pub rate: u32,
    /// 0: no emissive triangle is left to the reservoirs (none, or all in the shadows chain's
    /// mesh lights).
    pub resampled_emitters: u32,
}

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct GiSettings {
    /// Path vertices traced after the primary surface before the radiance cache answers (1:
    /// the cache answers at the bounce ray's hit); with the cache off, the bounces traced.
    pub bounces: u32,
    /// Which pixels are traced each frame; gi_fill fills the others from their traced
    /// neighbours, and an untraced pixel hands its resampled lights' reservoir on as it was.
    pub rate: GiRate,
}

/// How many of the pixels gi traces each frame (`--gi-rate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum GiRate {
    /// Every pixel every frame.
    Full,
    /// Half: a checkerboard that alternates every frame.
    Half,
    /// A quarter: one pixel of each 2x2 block, each in turn over four frames.
    Quarter,
}

impl GiRate {
    /// The pixels per traced pixel: 1, 2 or 4.
    pub fn pixels(self) -> u32 {
        match self {
            GiRate::Full => 1,
            GiRate::Half => 2,
            GiRate::Quarter => 4,
        }
    }

    /// The rate of `pixels` per traced pixel, if it is one.
    pub fn from_pixels(pixels: u32) -> Option<Self> {
        [GiRate::Full, GiRate::Half, GiRate::Quarter].into_iter().find(|r| r.pixels() == pixels)
    }
}

impl Default for GiSettings {
    fn default() -> Self {
        Self { bounces: 1, rate: GiRate::Half }
    }
}

/// gi's passes and the signals they leave for the rest of the frame.
pub struct Signals {
    pub passes: Vec<Box<dyn Pass>>,
    /// Demodulated diffuse radiance, every pixel.
    pub radiance: Output,
    /// The specular signal, every pixel.
    pub specular: Output,
}

/// gi, and gi_fill after it at a reduced rate.
/// `roughness_cutoff`: the reflections pass's; gi estimates the specular lobe above it.
/// `reservoirs`: whether the plan leaves lights to gi's reservoirs (frame-sized then);
/// `resampled_emitters`: whether some of them are emissive triangles.
pub fn new(
    b: &PassBuilder,
    s: &GiSettings,
    seed: u32,
    roughness_cutoff: f32,
    cache: &Cache,
    reservoirs: bool,
    resampled_emitters: bool,
) -> Result<Signals> {
    let mut inputs: Vec<Input> = [
        gbuffer::DEPTH,
        gbuffer::NORMAL,
        gbuffer::NORMAL_GEO,
        gbuffer::BASE_COLOR,
        gbuffer::METAL_ROUGH,
        gbuffer::IDS,
        gbuffer::MOTION,
    ]
    .map(Input::texel)
    .to_vec();
    inputs.extend([gbuffer::DEPTH, gbuffer::NORMAL_GEO, gbuffer::IDS, RESERVOIR].map(|o| Input::texel(history::of(o))));
    let outputs = vec![
        OutputDesc::storage(RADIANCE, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(SPECULAR, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        reservoir_size(OutputDesc::storage(RESERVOIR, RESERVOIR_FORMAT, Preview::Scalar), reservoirs),
        reservoir_size(OutputDesc::storage(LIGHT_LOST, vk::Format::R32G32_SFLOAT, Preview::Color), reservoirs),
    ];
    match s.rate {
        GiRate::Full => {}
        GiRate::Half => log::info!(
            "gi: half of the pixels traced each frame (a checkerboard), the others filled from their neighbours"
        ),
        GiRate::Quarter => log::info!(
            "gi: a quarter of the pixels traced each frame (one of each 2x2 block), the others filled from their neighbours"
        ),
    }
    let push = Params {
        bounces: s.bounces.max(1),
        seed,
        roughness_cutoff,
        rate: s.rate.pixels(),
        resampled_emitters: resampled_emitters.into(),
    };
    let mut gi =
        FullscreenPass::with_buffers(b, NAME, &b.traced_shader("gi.comp"), inputs, outputs, cache.buffers(), &push)?;
    if s.rate == GiRate::Full {
        return Ok(Signals { passes: vec![Box::new(gi)], radiance: RADIANCE, specular: SPECULAR });
    }
    gi.pixels_per_invocation = [2, 1];
    Ok(Signals {
        passes: vec![Box::new(gi), Box::new(gi_fill::new(b)?)],
        radiance: gi_fill::RADIANCE,
        specular: gi_fill::SPECULAR,
    })
}

/// The reservoirs' copy for the next frame.
pub fn kept(reservoirs: bool) -> Kept {
    let k = Kept::new(RESERVOIR, RESERVOIR_FORMAT, Preview::Scalar);
    if reservoirs { k } else { k.with_extent(1, 1) }
}

fn reservoir_size(d: OutputDesc, reservoirs: bool) -> OutputDesc {
    if reservoirs { d } else { d.with_extent(1, 1) }
}
