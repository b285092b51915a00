//! Samplers, created once per distinct description and shared.

use super::Context;
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerDesc {
    pub mag_linear: bool,
    pub min_linear: bool,
    pub mipmaps: bool,
    pub wrap_u: vk::SamplerAddressMode,
    pub wrap_v: vk::SamplerAddressMode,
}

impl SamplerDesc {
    /// Bilinear, clamped: for reading full-screen images between passes.
    pub const LINEAR_CLAMP: Self = Self {
        mag_linear: true,
        min_linear: true,
        mipmaps: false,
        wrap_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        wrap_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
}

pub struct Sampler {
    ctx: Arc<Context>,
    pub raw: vk::Sampler,
}

impl Sampler {
    pub fn new(ctx: &Arc<Context>, d: SamplerDesc) -> Result<Self> {
        let filter = |linear| if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter(d.mag_linear))
            .min_filter(filter(d.min_linear))
            .mipmap_mode(if d.min_linear { vk::SamplerMipmapMode::LINEAR } else { vk::SamplerMipmapMode::NEAREST })
            .address_mode_u(d.wrap_u)
            .address_mode_v(d.wrap_v)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .min_lod(0.0)
            .max_lod(if d.mipmaps { vk::LOD_CLAMP_NONE } else { 0.0 });
        // SAFETY: creation on a live device from an info on this stack frame; anisotropy is
        // off, so no feature is needed.
        let raw = unsafe { ctx.device.create_sampler(&info, None) }.context("create sampler")?;
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: made by `new`, destroyed once, after the frames that sampled with it (as for
        // images, see memory.rs).
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}
