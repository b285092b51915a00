//! `hybrid-rt bench frame`: where the default frame's time goes, pass by pass, at the sizes
//! asked for (src/bench/frame.rs).

use super::{EnvironmentArgs, GpuArgs, SceneArgs, parse_size};
use crate::backend;
use crate::bench::{self, frame};
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct FrameArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Image sizes, WIDTHxHEIGHT, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "640x360,1920x1080")]
    sizes: Vec<String>,
    /// Frames rendered before measuring (pipeline compilation, histories filling, a GPU's
    /// clocks rising); the warm-up goes on for at least a second whatever this says.
    #[arg(long, default_value_t = 4)]
    warmup: u32,
    /// Frames measured, each unprofiled and profiled; each pass's median is reported.
    #[arg(long, default_value_t = 8)]
    frames: u32,
    /// Run every pass instead of the scene's frame plan.
    #[arg(long)]
    full: bool,
    /// JSON output (default: out/bench/frame-<unix time>.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// Compile shaders from this shaders-glsl folder at start-up instead of the embedded ones
    /// (needs a build with `--features shader-compiler`): what a shader change costs, pass by
    /// pass, without rebuilding.
    #[arg(long)]
    shader_dir: Option<PathBuf>,
}

pub fn run(a: &FrameArgs) -> Result<()> {
    let sizes = a.sizes.iter().map(|s| parse_size(s)).collect::<Result<Vec<_>>>()?;
    let out = a.out.clone().unwrap_or_else(|| bench::default_output("frame"));
    image_io::check_overwrite(&out, a.force)?;
    let scene = a.scene.load()?;
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (picked, why) = backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", picked.variant());
    let shaders = ShaderLibrary::from_dir_or_embedded(a.shader_dir.as_deref())?;
    let bar = crate::progress::progress_bar(sizes.len() as u64, "sizes");
    let mut costs = Vec::new();
    for &size in &sizes {
        bar.set_message(format!("{}x{}", size.0, size.1));
        let settings = crate::render::Settings {
            width: size.0,
            height: size.1,
            taa: true,
            full: a.full,
            environment: a.environment.environment(),
            ..Default::default()
        };
        costs.push(frame::measure(&ctx, &shaders, scene.clone(), picked, settings, (a.warmup, a.frames))?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    outln!(
        "device: {} ({}), {} backend, scene {}, {}",
        ctx.caps.device_name,
        ctx.caps.driver,
        picked.variant(),
        scene.name,
        if a.full { "every pass (--full)" } else { "frame plan" }
    );
    print!("{}", frame::table(&costs));
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "backend": picked.variant(),
        "scene": scene.name,
        "full": a.full,
        "sizes": costs,
    });
    image_io::write_atomic(&out, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    outln!("wrote {}", out.display());
    finish_validation(ctx)
}
