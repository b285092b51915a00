//! `hybrid-rt bench ...`: benchmarks. `bench rays` measures both ray backends on the same rays;
//! `bench sweep` measures frame time against error over configurations of the hybrid frame.

use super::{GpuArgs, load_scene, parse_size};
use crate::backend::{Backend, BackendChoice};
use crate::bench::{self, rays, sweep};
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io;
use crate::render::CameraChoice;
use crate::scene::LoadOptions;
use anyhow::{Result, bail};
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
    /// Per-pass time of the default frame at one or more sizes (each pass's own submission,
    /// wall clock, beside its timestamps), with the denoiser's (svgf_*) share.
    Frame(super::bench_frame::FrameArgs),
    /// Many frames of an animated scene (default: 10,000 of the Cornell box at 32x32): host
    /// and device memory sampled every N frames after a warm-up, and frame times.
    Soak(super::soak::SoakArgs),
    /// Frame time (wall clock, submit to fence; per-pass GPU timestamps kept) against error (HDR-FLIP, PSNR, SSIM against a cached
    /// path-traced reference) over configurations of the hybrid frame; writes JSON and a chart
    /// (PNG and SVG) with the Pareto front, and caches the result for `render --target-ms`.
    Sweep(SweepArgs),
    /// Scripted scenes at the known failure points (camera cut, fast pan, ghosting, light lag,
    /// leaking, acne, fireflies, disocclusion), each metric denoised beside the raw frame's
    /// (src/bench/stability.rs).
    Stability(super::stability::StabilityArgs),
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
        BenchCommand::Frame(f) => super::bench_frame::run(f),
        BenchCommand::Soak(s) => super::soak::run(s),
        BenchCommand::Sweep(s) => run_sweep(s),
        BenchCommand::Stability(s) => super::stability::run(s),
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
    let bar = crate::progress::progress_bar(scenes.len() as u64, "scenes");
    let mut results = Vec::new();
    for s in &scenes {
        bar.set_message(s.clone());
        let scene = load_scene(s, &LoadOptions::default())?;
        let progress = |msg: &str| log::info!("{msg}");
        results.push(rays::bench_scene(&ctx, &shaders, scene, &backends, &opts, &progress)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    outln!("device: {} ({})", ctx.caps.device_name, ctx.caps.driver);
    print!("{}", rays::table(&results));
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "options": { "width": width, "height": height, "incoherent": a.incoherent, "repeats": a.repeats },
        "scenes": results,
    });
    image_io::write_atomic(&out, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    outln!("wrote {}", out.display());
    finish_validation(ctx)
}

#[derive(Args)]
struct SweepArgs {
    /// Scenes (.gltf/.glb or builtin:NAME); default: the project's Cornell box.
    scenes: Vec<String>,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Image sizes, WIDTHxHEIGHT, comma-separated; each gets its own reference and chart.
    #[arg(long, value_delimiter = ',', default_value = "320x180")]
    size: Vec<String>,
    /// Configurations, comma-separated, e.g. d4-s5-b1-r1 (d: SVGF iterations, 0 = denoiser off;
    /// s: shadow s_max; b: GI bounces; r: reflection rays; t0: TAA off; c0: radiance cache off).
    /// Default: 18 configurations (see src/bench/sweep/config.rs).
    #[arg(long, value_delimiter = ',')]
    configs: Vec<String>,
    /// Frames per configuration (static camera); the error is measured on the last.
    #[arg(long, default_value_t = 48)]
    frames: u32,
    /// The last this-many frames give the median frame time.
    #[arg(long, default_value_t = 8)]
    timed_frames: u32,
    /// Timing rounds over all configurations; each one's frame time is the median over all
    /// rounds (the error comes from the first).
    #[arg(long, default_value_t = 3)]
    rounds: u32,
    /// Samples per pixel of the reference (even: it is the mean of two independent halves).
    #[arg(long, default_value_t = 512)]
    reference_spp: u32,
    /// Scattering events per reference path at most (Russian roulette ends them earlier).
    #[arg(long, default_value_t = 256)]
    reference_bounces: u32,
    /// The path tracer's curve on the same axes: 1, 2, 4, ... up to this many samples per
    /// pixel, each timed and compared with the reference like the configurations, and on to the
    /// power of two that takes as long as the slowest configuration's frames (up to 1024), so
    /// that each configuration has the path tracer's error at equal time (0: no curve).
    #[arg(long, default_value_t = 64)]
    pt_spp: u32,
    /// Render the reference again even when it is cached (and replace the cached one).
    #[arg(long)]
    fresh_reference: bool,
    /// Seed of the configurations' random streams (the reference's are fixed): one seed's
    /// error moves with any change to what a ray is drawn from, so compare builds over several.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// No default light: scenes without punctual lights or significant emitters stay black but
    /// for their emission (by default a daylight sky lights them, reference and frames alike).
    #[arg(long)]
    no_default_light: bool,
    /// Scene camera by name or index (default: the first camera, or a framing camera).
    #[arg(long)]
    camera: Option<CameraChoice>,
    /// Output folder for sweep.json and the charts (default: out/bench/sweep-<unix time>/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Cache of references and sweep results (`render --target-*` reads out/cache).
    #[arg(long, default_value = "out/cache")]
    cache_dir: PathBuf,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// Compile shaders from this shaders-glsl folder at start-up instead of the embedded ones
    /// (needs a build with `--features shader-compiler`): a shader change measured against
    /// the build's own shaders without rebuilding.
    #[arg(long)]
    shader_dir: Option<PathBuf>,
}

/// The name of each scene's charts: its file's stem, or, where another scene of the sweep has
/// the same stem (`tests/mitsuba/*/scene.gltf`), its folder's name and the stem.
fn chart_names(scenes: &[String]) -> Result<Vec<String>> {
    let part = |p: Option<&std::ffi::OsStr>| bench::slug(&p.map(|f| f.to_string_lossy()).unwrap_or_default());
    let stems: Vec<String> = scenes.iter().map(|s| part(Path::new(s).file_stem())).collect();
    let names: Vec<String> = scenes
        .iter()
        .zip(&stems)
        .map(|(s, stem)| {
            if stems.iter().filter(|&other| other == stem).count() == 1 {
                return stem.clone();
            }
            let folder = part(Path::new(s).parent().and_then(Path::file_name));
            if folder.is_empty() { stem.clone() } else { format!("{folder}-{stem}") }
        })
        .collect();
    if let Some(twice) = names.iter().enumerate().find(|&(i, n)| names[..i].contains(n)) {
        bail!(
            "two scenes would write the charts named {}: their charts would overwrite each other; sweep them separately",
            twice.1
        );
    }
    Ok(names)
}

fn run_sweep(a: &SweepArgs) -> Result<()> {
    let sizes = a.size.iter().map(|s| parse_size(s)).collect::<Result<Vec<_>>>()?;
    let configs = if a.configs.is_empty() {
        sweep::default_configs()
    } else {
        a.configs.iter().map(|c| c.parse()).collect::<Result<Vec<sweep::Config>>>()?
    };
    let scenes = if a.scenes.is_empty() {
        vec![super::default_scene_path().to_string_lossy().into_owned()]
    } else {
        a.scenes.clone()
    };
    let out = a.out.clone().unwrap_or_else(|| bench::default_output("sweep").with_extension(""));
    let json_path = out.join("sweep.json");
    // Every output is checked before hours of rendering, not after.
    let charts: Vec<(PathBuf, PathBuf)> = chart_names(&scenes)?
        .into_iter()
        .flat_map(|name| {
            let out = &out;
            sizes
                .iter()
                .map(move |(w, h)| (out.join(format!("{name}-{w}x{h}.png")), out.join(format!("{name}-{w}x{h}.svg"))))
        })
        .collect();
    image_io::check_overwrite(&json_path, a.force)?;
    for (png, svg) in &charts {
        image_io::check_overwrite(png, a.force)?;
        image_io::check_overwrite(svg, a.force)?;
    }
    let loaded = scenes.iter().map(|s| load_scene(s, &LoadOptions::default())).collect::<Result<Vec<_>>>()?;
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (backend, why) = crate::backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", backend.variant());
    let shaders = ShaderLibrary::from_dir_or_embedded(a.shader_dir.as_deref())?;
    let start = std::time::Instant::now();
    let mut sweeps = Vec::new();
    let mut chart = charts.iter();
    for (spec, scene) in scenes.iter().zip(&loaded) {
        for &(width, height) in &sizes {
            let opts = sweep::Options {
                width,
                height,
                configs: configs.clone(),
                frames: a.frames,
                timed_frames: a.timed_frames,
                rounds: a.rounds,
                reference_spp: a.reference_spp,
                reference_bounces: a.reference_bounces,
                path_tracer_spp: a.pt_spp,
                camera: a.camera.clone().unwrap_or_default(),
                cache_dir: a.cache_dir.clone(),
                fresh_reference: a.fresh_reference,
                seed: a.seed,
                environment: if a.no_default_light {
                    crate::render::Environment::Constant(glam::Vec3::ZERO)
                } else {
                    crate::render::Environment::DefaultLight
                },
            };
            let s = sweep::sweep_scene(&ctx, &shaders, spec, scene, backend, &opts)?;
            let (png, svg) = chart.next().expect("one chart per scene and size");
            crate::bench::chart::write(&s, png, svg)?;
            print!("{}", sweep::table(&s));
            outln!("chart: {} and {}", png.display(), svg.display());
            sweeps.push(s);
        }
    }
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "backend": backend.variant(),
        "seconds": start.elapsed().as_secs_f64(),
        "sweeps": sweeps,
    });
    image_io::write_atomic(&json_path, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    outln!("wrote {}", json_path.display());
    finish_validation(ctx)
}

#[cfg(test)]
mod tests {
    use super::chart_names;

    fn names(scenes: &[&str]) -> anyhow::Result<Vec<String>> {
        chart_names(&scenes.iter().map(|s| s.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn scenes_of_one_file_name_are_told_apart_by_their_folders() {
        let got = names(&[
            "tests/mitsuba/diffuse_box/scene.gltf",
            "tests/mitsuba/glossy_blocks/scene.gltf",
            "assets/cornell.gltf",
        ])
        .unwrap();
        assert_eq!(got, ["diffuse-box-scene", "glossy-blocks-scene", "cornell"]);
        assert_eq!(names(&["builtin:many-lights"]).unwrap(), ["builtin-many-lights"]);
    }

    #[test]
    fn the_same_scene_twice_is_refused() {
        let err = names(&["a/scene.gltf", "a/scene.gltf"]).unwrap_err().to_string();
        assert!(err.contains("a-scene"), "{err}");
    }
}
