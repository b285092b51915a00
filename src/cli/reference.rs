//! `hybrid-rt reference`: the ground truth. Renders a scene with the progressive path tracer
//! (the `pathtrace` pass), one sample per pixel per submission so that no single GPU call runs
//! long on a slow device, and writes the mean as linear EXR.

use super::{EnvironmentArgs, GpuArgs, SceneArgs, parse_size};
use crate::backend;
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io::{self, Texels};
use crate::passes::pathtrace;
use crate::render::{CameraChoice, RenderMode, Renderer, Settings};
use anyhow::{Result, bail};
use clap::Args;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Samples per pixel (one frame each).
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360")]
    size: String,
    /// Output image, linear HDR radiance (.exr).
    #[arg(long, default_value = "out/reference.exr")]
    out: PathBuf,
    /// Seed of the random streams: the same seed gives the same image, bit for bit.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Scene camera by name or index (default: the first camera, or a framing camera).
    #[arg(long)]
    camera: Option<CameraChoice>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Material model: `gltf` (glTF 2.0 Appendix B) or `coupled` (energy-coupled diffuse).
    #[arg(long, value_enum, default_value_t)]
    brdf: crate::world::brdf::BrdfModel,
    /// Draw the resampled lights (past the four brightest) by power from all of them instead
    /// of from the light grid's cell: unbiased either way, noisier without; to check the grid.
    #[arg(long)]
    no_light_grid: bool,
    /// Scattering events per path at most; 1 renders direct light only. Russian roulette ends
    /// paths well before the default, which only guards against endless paths.
    #[arg(long, default_value_t = 256)]
    max_bounces: u32,
    /// Also write a tonemapped sRGB preview of the result to this .png file.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Animation time of the pose to render, seconds.
    #[arg(long, default_value_t = 0.0)]
    time: f32,
}

pub fn run(a: &ReferenceArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    if a.spp == 0 {
        bail!("--spp must be at least 1");
    }
    let is_exr = a.out.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        bail!("{}: the reference is linear HDR; the output must end in .exr", a.out.display());
    }
    image_io::check_overwrite(&a.out, a.force)?;
    if let Some(p) = &a.preview {
        if !p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            bail!("{}: the preview must end in .png", p.display());
        }
        image_io::check_overwrite(p, a.force)?;
    }
    let environment = a.environment.environment();
    let scene = a.scene.load()?;
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (picked, why) = backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", picked.variant());
    let settings = Settings {
        width,
        height,
        start_time: a.time,
        environment,
        mode: RenderMode::Reference { seed: a.seed, max_bounces: a.max_bounces },
        brdf: a.brdf,
        light_grid: !a.no_light_grid,
        ..Default::default()
    };
    let camera = a.camera.clone().unwrap_or_default();
    let mut renderer = Renderer::new(&ctx, &ShaderLibrary::embedded(), scene, settings, &camera, picked)?;

    let bar = crate::progress::progress_bar(a.spp as u64, "spp");
    let start = Instant::now();
    let mut last_report = (start, 0u64);
    let mut rays = 0u64;
    for n in 1..=a.spp {
        renderer.render_frame()?;
        bar.inc(1);
        // Reading the ray counts back costs a submission: about once a second is enough.
        if n == a.spp || last_report.0.elapsed() >= Duration::from_secs(1) {
            rays = rays_traced(&mut renderer)?;
            let now = Instant::now();
            let rate = (rays - last_report.1) as f64 / (now - last_report.0).as_secs_f64().max(1e-9);
            bar.set_message(format!("{:.2} Mrays/s", rate * 1e-6));
            last_report = (now, rays);
        }
    }
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();

    let img = renderer.read_output(pathtrace::COLOR)?;
    image_io::write_exr(&a.out, &img, image_io::channel_names(img.channels))?;
    if let Some(p) = &a.preview {
        let img = renderer.read_output(crate::render::DISPLAY_OUTPUT)?;
        let rgba: Vec<u8> = img.as_f32().unwrap_or(&[]).iter().map(|v| (v * 255.0).round() as u8).collect();
        image_io::write_png_rgba8(p, width, height, &rgba)?;
    }
    outln!(
        "wrote {} ({width}x{height}, {} spp, seed {}, {} backend, {seconds:.1} s, {:.2} Mrays/s on {})",
        a.out.display(),
        a.spp,
        a.seed,
        picked.variant(),
        rays as f64 / seconds.max(1e-9) * 1e-6,
        ctx.caps.device_name
    );
    drop(renderer);
    finish_validation(ctx)
}

/// Rays traced so far over the whole image.
fn rays_traced(r: &mut Renderer) -> Result<u64> {
    match r.read_output(pathtrace::RAYS)?.texels {
        Texels::U32(v) => Ok(v.iter().map(|&n| n as u64).sum()),
        Texels::F32(_) => bail!("{} is not an integer image", pathtrace::RAYS),
    }
}
