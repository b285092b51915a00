//! `hybrid-rt bench soak`: many frames of an animated scene, watching host and device memory
//! and frame times (src/bench/soak.rs).

use super::{EnvironmentArgs, GpuArgs, SceneArgs, parse_size};
use crate::backend;
use crate::bench::{self, soak};
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io;
use crate::render::{CameraChoice, Renderer, Settings};
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct SoakArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Frames to render, warm-up included.
    #[arg(long, default_value_t = soak::Options::default().frames)]
    frames: u32,
    /// Frames before the baseline sample (first-use costs land there).
    #[arg(long, default_value_t = soak::Options::default().warmup)]
    warmup: u32,
    /// Frames between memory samples.
    #[arg(long, default_value_t = soak::Options::default().every)]
    every: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "32x32")]
    size: String,
    /// JSON output (default: out/bench/soak-<unix time>.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

pub fn run(a: &SoakArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    let out = a.out.clone().unwrap_or_else(|| bench::default_output("soak"));
    image_io::check_overwrite(&out, a.force)?;
    let opts = soak::Options { frames: a.frames, warmup: a.warmup, every: a.every };
    let scene = a.scene.load()?;
    let scene_name = scene.name.clone();
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (picked, why) = backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", picked.variant());
    // The frame `hybrid-rt render` makes by default (TAA on).
    let settings =
        Settings { width, height, taa: true, environment: a.environment.environment(), ..Default::default() };
    let shaders = ShaderLibrary::embedded();
    let mut renderer = Renderer::new(&ctx, &shaders, scene, settings, &CameraChoice::Default, picked)?;
    let bar = crate::progress::progress_bar(a.frames as u64, "frames");
    let result = soak::run(&mut renderer, &opts, &|n| bar.set_position(n as u64))?;
    bar.finish_and_clear();
    drop(renderer);
    outln!(
        "device: {} ({}), {} backend, {width}x{height}, {}",
        ctx.caps.device_name,
        ctx.caps.driver,
        picked.variant(),
        scene_name
    );
    print!("{}", soak::table(&result));
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "scene": scene_name,
        "backend": picked,
        "validate": a.gpu.validate,
        "width": width,
        "height": height,
        "result": result,
    });
    image_io::write_atomic(&out, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    outln!("wrote {}", out.display());
    finish_validation(ctx)
}
