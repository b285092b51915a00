//! `hybrid-rt render`: renders N frames of a scene and writes the last one; optionally dumps
//! every pass's outputs.

use super::{EnvironmentArgs, GpuArgs, SceneArgs, parse_size};
use crate::backend;
use crate::bench;
use crate::capture::Capture;
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io;
use crate::passes::gi::GiRate;
use crate::render::{self, CameraChoice, Renderer, Settings};
use anyhow::{Result, bail};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360")]
    size: String,
    /// Number of frames to render (animation advances 1/30 s per frame); the last is written.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Output image: .png (tonemapped sRGB) or .exr (linear HDR radiance).
    #[arg(long, default_value = "out/render.png")]
    out: PathBuf,
    /// Scene camera by name or index (default: the first camera, or a framing camera).
    #[arg(long)]
    camera: Option<CameraChoice>,
    /// Write every pass's named outputs (EXR + PNG + manifest.json) into this folder.
    #[arg(long)]
    dump_passes: Option<PathBuf>,
    /// Run every pass, ignoring the frame plan (`hybrid-rt plan` shows what it leaves out).
    #[arg(long)]
    full: bool,
    /// Frames to dump, 1-based, comma-separated (default: the last frame).
    #[arg(long, value_delimiter = ',')]
    dump_frames: Vec<u32>,
    /// Turn temporal anti-aliasing off (it is on by default).
    #[arg(long)]
    no_taa: bool,
    /// Turn the SVGF denoiser off: the raw one-sample-per-pixel signals are composited.
    #[arg(long)]
    no_denoise: bool,
    /// Path vertices the gi pass traces before the radiance cache answers (with the cache
    /// off: the bounces traced).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=8))]
    gi_bounces: Option<u32>,
    /// How many of the pixels gi traces each frame: `full`, `half` (the default: a checkerboard
    /// that alternates every frame) or `quarter` (one pixel of each 2x2 block, each in turn);
    /// the others are filled from their neighbours.
    #[arg(long, value_enum, value_name = "RATE")]
    gi_rate: Option<GiRate>,
    /// Turn the radiance cache off: gi and reflection rays trace a few bounces on instead of
    /// asking the cache where they end.
    #[arg(long)]
    no_radiance_cache: bool,
    /// Radiance-cache cells updated per frame at most.
    #[arg(long, value_name = "CELLS", value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    cache_budget: Option<u32>,
    /// Seed of the frame's random streams (same seed, settings and backend: same image).
    #[arg(long)]
    seed: Option<u32>,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Material model: `gltf` (glTF 2.0 Appendix B) or `coupled` (energy-coupled diffuse).
    #[arg(long, value_enum, default_value_t)]
    brdf: crate::world::brdf::BrdfModel,
    /// Draw the resampled lights (past the four brightest) by power from all of them instead
    /// of from the light grid's cell: unbiased either way, noisier without; to check the grid.
    #[arg(long)]
    no_light_grid: bool,
    /// Resample every emissive triangle in gi instead of giving small plain emissive meshes the
    /// shadows chain's free channels (closed-form light, adaptive soft shadows).
    #[arg(long)]
    no_mesh_lights: bool,
    /// Give the shadows chain's four channels to the lights that emit the most over the whole
    /// scene instead of those that bring the most direct light to the camera's views.
    #[arg(long)]
    chain_by_power: bool,
    /// Exposure multiplier before tonemapping.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// Compile shaders from this shaders-glsl folder at start-up instead of the embedded ones
    /// (needs a build with `--features shader-compiler`).
    #[arg(long)]
    shader_dir: Option<PathBuf>,
    /// Pick the most accurate configuration whose frame time is at most this many ms, from
    /// this scene's speed/accuracy sweep on this machine (`hybrid-rt bench sweep`).
    #[arg(long, value_name = "MS", conflicts_with_all = ["target_error", "no_taa", "no_denoise", "gi_bounces", "gi_rate"])]
    target_ms: Option<f64>,
    /// Pick the fastest configuration whose HDR-FLIP error is at most this, from this scene's
    /// speed/accuracy sweep on this machine (`hybrid-rt bench sweep`).
    #[arg(long, value_name = "FLIP", conflicts_with_all = ["no_taa", "no_denoise", "gi_bounces", "gi_rate"])]
    target_error: Option<f64>,
}

pub fn run(a: &RenderArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    if a.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let ext = a.out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("png") | Some("exr")) {
        bail!("{}: the output must end in .png or .exr", a.out.display());
    }
    image_io::check_overwrite(&a.out, a.force)?;
    if let Some(bad) = a.dump_frames.iter().find(|&&f| f == 0 || f > a.frames) {
        bail!("--dump-frames {bad}: frames are numbered 1..={}", a.frames);
    }
    let scene = a.scene.load()?;
    let shaders = ShaderLibrary::from_dir_or_embedded(a.shader_dir.as_deref())?;
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (picked, why) = backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", picked.variant());
    let scene_name = scene.name.clone();
    let mut settings = Settings {
        width,
        height,
        exposure: a.exposure,
        taa: !a.no_taa,
        denoiser: !a.no_denoise,
        full: a.full,
        environment: a.environment.environment(),
        brdf: a.brdf,
        light_grid: !a.no_light_grid,
        mesh_lights: !a.no_mesh_lights,
        chain_by_view: !a.chain_by_power,
        ..Default::default()
    };
    if let Some(b) = a.gi_bounces {
        settings.gi.bounces = b;
    }
    if let Some(rate) = a.gi_rate {
        settings.gi.rate = rate;
    }
    settings.radiance_cache.enabled = !a.no_radiance_cache;
    if let Some(b) = a.cache_budget {
        settings.radiance_cache.budget = b;
    }
    if let Some(seed) = a.seed {
        settings.seed = seed;
    }
    let camera = a.camera.clone().unwrap_or_default();
    let target = match (a.target_ms, a.target_error) {
        (Some(t), _) => Some(bench::target::Target::Ms(t)),
        (_, Some(e)) => Some(bench::target::Target::Error(e)),
        _ => None,
    };
    if let Some(target) = target {
        let spec = a.scene.scene.clone().unwrap_or_else(|| super::default_scene_path().to_string_lossy().into_owned());
        let cache = std::path::Path::new("out/cache");
        let (config, why) = bench::sweep::pick_for_render(
            cache,
            (&spec, &scene, &settings.environment),
            &camera,
            (width, height),
            picked,
            &ctx.caps.device_name,
            target,
        )?;
        config.apply(&mut settings);
        outln!("configuration {why}");
    }
    let mut renderer = Renderer::new(&ctx, &shaders, scene, settings, &camera, picked)?;

    let mut capture = match &a.dump_passes {
        Some(dir) => Some(Capture::new(dir, !a.dump_frames.is_empty(), a.force, &scene_name, &ctx.caps.device_name)?),
        None => None,
    };
    let bar = crate::progress::progress_bar(a.frames as u64, "frames");
    for n in 1..=a.frames {
        renderer.render_frame()?;
        if log::log_enabled!(log::Level::Debug) {
            log::debug!("frame {n}: radiance cache {:?}", renderer.radiance_cache_stats());
        }
        let dump_now = if a.dump_frames.is_empty() { n == a.frames } else { a.dump_frames.contains(&n) };
        if let (Some(c), true) = (capture.as_mut(), dump_now) {
            c.dump(&mut renderer)?;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();

    if ext.as_deref() == Some("exr") {
        let img = renderer.read_output(renderer.hdr_output())?;
        image_io::write_exr(&a.out, &img, image_io::channel_names(img.channels))?;
    } else {
        let img = renderer.read_output(render::DISPLAY_OUTPUT)?;
        let rgba: Vec<u8> = img.as_f32().unwrap_or(&[]).iter().map(|v| (v * 255.0).round() as u8).collect();
        image_io::write_png_rgba8(&a.out, width, height, &rgba)?;
    }
    // Wall clock: timestamps can miss compute passes (lavapipe), see `bench frame`.
    let frame_ms = renderer.last_frame_wall_ms;
    outln!(
        "wrote {} ({width}x{height}, {} frame(s), {} backend, last frame {frame_ms:.2} ms on {})",
        a.out.display(),
        a.frames,
        picked.variant(),
        ctx.caps.device_name
    );
    if let Some(c) = &capture {
        outln!("pass dumps in {} (manifest.json)", c.dir.display());
    }
    drop(renderer);
    finish_validation(ctx)
}
