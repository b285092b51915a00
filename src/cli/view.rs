//! `hybrid-rt view`: the desktop viewer (see src/app/).

use super::{EnvironmentArgs, GpuArgs, SceneArgs, parse_size};
use crate::app::{self, ViewOptions, script};
use crate::gpu::ShaderLibrary;
use crate::render::{CameraChoice, Settings};
use anyhow::{Context as _, Result, bail};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Render size and first window size, WIDTHxHEIGHT (the render size then follows the
    /// window, except in scripted runs).
    #[arg(long, default_value = "640x360")]
    size: String,
    /// Scene camera by name or index (default: the first camera, or a framing camera).
    #[arg(long)]
    camera: Option<CameraChoice>,
    /// The pass output shown first (any name `render --dump-passes` writes; default: the
    /// tonemapped image).
    #[arg(long)]
    view: Option<String>,
    /// Turn temporal anti-aliasing off (it is on by default, as in `render`).
    #[arg(long)]
    no_taa: bool,
    /// Exposure multiplier before tonemapping.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Present without waiting for the display's refresh (toggle with V).
    #[arg(long)]
    no_vsync: bool,
    /// Start with the overlay hidden (toggle with H or F1).
    #[arg(long)]
    hide_ui: bool,
    /// Compile shaders from this shaders-glsl folder at start-up, and hot-reload it (needs a
    /// build with `--features shader-compiler`).
    #[arg(long, conflicts_with = "watch_shaders")]
    shader_dir: Option<PathBuf>,
    /// Start with the embedded shaders and hot-reload this folder when it changes (default:
    /// the source tree's shaders-glsl, when it exists, for interactive runs of a build with
    /// `--features shader-compiler`).
    #[arg(long)]
    watch_shaders: Option<PathBuf>,
    /// No hot reload.
    #[arg(long, conflicts_with_all = ["watch_shaders"])]
    no_watch: bool,
    /// Commands to run, e.g. "frames=8,view=gbuffer.normal,screenshot=shot.png,quit", or
    /// @FILE (see src/app/script.rs). Scripted runs render at --size whatever the window.
    #[arg(long)]
    script: Option<String>,
    /// Where the overlay's screenshots and capture dumps go.
    #[arg(long, default_value = "out")]
    out_dir: PathBuf,
    /// Replace existing screenshots and capture folders.
    #[arg(long)]
    force: bool,
}

pub fn run(a: &ViewArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    if !(a.exposure.is_finite() && a.exposure > 0.0) {
        bail!("--exposure {}: expected a positive number", a.exposure);
    }
    let script = a.script.as_deref().map(script::load).transpose()?;
    let scene = a.scene.load()?;
    let default_watch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("shaders-glsl");
    // Scripts must be reproducible: they reload only when told to (`reload`), from a folder
    // named on the command line. A build without the runtime compiler watches nothing unless
    // asked, and then says how to get one before opening a window.
    let watch = if a.no_watch {
        None
    } else if let Some(dir) = a.shader_dir.clone().or_else(|| a.watch_shaders.clone()) {
        ShaderLibrary::runtime_compiler().with_context(|| format!("{}: cannot compile shaders", dir.display()))?;
        Some(dir)
    } else if script.is_none() && default_watch.is_dir() && ShaderLibrary::runtime_compiler().is_ok() {
        Some(default_watch)
    } else {
        None
    };
    let settings = Settings {
        width,
        height,
        exposure: a.exposure,
        taa: !a.no_taa,
        environment: a.environment.environment(),
        ..Default::default()
    };
    app::run(ViewOptions {
        scene,
        settings,
        backend: a.gpu.backend,
        validate: a.gpu.validate,
        camera: a.camera.clone().unwrap_or_default(),
        shader_dir: a.shader_dir.clone(),
        watch,
        script,
        vsync: !a.no_vsync,
        view: a.view.clone(),
        ui: !a.hide_ui,
        out_dir: a.out_dir.clone(),
        force: a.force,
    })
}
