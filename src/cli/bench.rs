//! `hybrid-rt bench ...`: benchmarks. `bench rays` measures both ray backends on the same rays.

use super::{GpuArgs, finish_validation, load_scene, parse_size};
use crate::backend::{Backend, BackendChoice};
use crate::bench::{self, rays};
use crate::gpu::{Context, ContextOptions, ShaderLibrary};
use crate::image_io;
use crate::scene::LoadOptions;
use anyhow::Result;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchCommand,
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Build time, memory and rays/s of both ray backends on the same primary, shadow and
    /// incoherent rays (the definition is in src/bench/rays.rs).
    Rays(RaysArgs),
}

#[derive(Args)]
struct RaysArgs {
    /// Scenes (.gltf/.glb or builtin:NAME); default: MetalRoughSpheresNoTextures, DamagedHelmet
    /// (from ../shared/scenes) and the project's Cornell box.
    scenes: Vec<String>,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Primary rays: WIDTHxHEIGHT through pixel centres.
    #[arg(long, default_value = "1024x1024")]
    size: String,
    /// Number of incoherent rays.
    #[arg(long, default_value_t = 1 << 20)]
    incoherent: usize,
    /// Traces of each set per backend; the median time is reported.
    #[arg(long, default_value_t = 3)]
    repeats: u32,
    /// JSON output (default: out/bench/rays-<unix time>.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

pub fn run(a: &BenchArgs) -> Result<()> {
    match &a.what {
        BenchCommand::Rays(r) => run_rays(r),
    }
}

fn default_scenes() -> Vec<String> {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/khronos");
    vec![
        shared.join("MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb").to_string_lossy().into_owned(),
        shared.join("DamagedHelmet/DamagedHelmet.glb").to_string_lossy().into_owned(),
        super::default_scene_path().to_string_lossy().into_owned(),
    ]
}

fn run_rays(a: &RaysArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    let out = a.out.clone().unwrap_or_else(|| bench::default_output("rays"));
    image_io::check_overwrite(&out, a.force)?;
    let scenes = if a.scenes.is_empty() { default_scenes() } else { a.scenes.clone() };
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    // The compute backend always runs: its primary hits define the shadow rays.
    let backends = match a.gpu.backend {
        BackendChoice::Compute => vec![Backend::Compute],
        BackendChoice::Rayquery => {
            crate::backend::resolve(&ctx.caps, BackendChoice::Rayquery)?;
            vec![Backend::Compute, Backend::RayQuery]
        }
        BackendChoice::Auto if ctx.caps.supports_ray_query() => vec![Backend::Compute, Backend::RayQuery],
        BackendChoice::Auto => {
            eprintln!("ray query unavailable on {}: measuring the compute backend only", ctx.caps.device_name);
            vec![Backend::Compute]
        }
    };
    let opts = rays::Options { width, height, incoherent: a.incoherent, repeats: a.repeats };
    let shaders = ShaderLibrary::embedded();
    let bar = super::progress_bar(scenes.len() as u64, "scenes");
    let mut results = Vec::new();
    for s in &scenes {
        bar.set_message(s.clone());
        let scene = load_scene(s, &LoadOptions::default())?;
        let progress = |msg: &str| log::info!("{msg}");
        results.push(rays::bench_scene(&ctx, &shaders, scene, &backends, &opts, &progress)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!("device: {} ({})", ctx.caps.device_name, ctx.caps.driver);
    print!("{}", rays::table(&results));
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "options": { "width": width, "height": height, "incoherent": a.incoherent, "repeats": a.repeats },
        "scenes": results,
    });
    image_io::write_atomic(&out, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    println!("wrote {}", out.display());
    finish_validation(ctx)
}
