//! The command line: `hybrid-rt render | info | ...`. Each subcommand lives in its own file;
//! this one holds the shared arguments and turns errors into a message and a non-zero exit.

/// `println!` for what the command line prints: a pipe closed early (`hybrid-rt plan | head`)
/// becomes an error that `run` ends quietly, where `println!` panics. Returns from the calling
/// function, which must return `anyhow::Result`.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

mod bench;
mod bench_frame;
mod info;
mod plan;
mod reference;
mod render;
mod soak;
mod stability;
mod view;

use crate::backend::BackendChoice;
use crate::scene::{self, Limits, LoadOptions, Scene};
use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "hybrid-rt", version, about = "A Vulkan hybrid ray-tracing renderer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render frames of a scene to a PNG (tonemapped sRGB) or EXR (linear HDR) image.
    Render(render::RenderArgs),
    /// Show the Vulkan device, its ray-tracing capabilities and the backend `auto` picks.
    Info(info::InfoArgs),
    /// Show which passes the frame runs for a scene and why (no more work than it needs).
    Plan(plan::PlanArgs),
    /// Benchmarks (see `hybrid-rt bench --help`).
    Bench(bench::BenchArgs),
    /// Render the ground truth with the progressive path tracer to a linear EXR.
    Reference(reference::ReferenceArgs),
    /// Open a window on the hybrid frame: camera, overlay, any pass output, hot reload.
    View(view::ViewArgs),
}

/// Arguments every GPU command takes.
#[derive(Args, Clone, Debug)]
pub struct GpuArgs {
    /// Ray backend for the ray-traced passes.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// Run with the Khronos validation layer (synchronization validation on); any message it
    /// prints makes the command fail.
    #[arg(long)]
    pub validate: bool,
}

/// Arguments of commands that load a scene.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// A .gltf or .glb file, or `builtin:NAME`; the project's Cornell box when omitted.
    pub scene: Option<String>,
    /// Allow the scene's URIs to reach files outside the scene's folder.
    #[arg(long)]
    pub allow_outside_uris: bool,
    #[command(flatten)]
    pub limits: LimitArgs,
}

const LIMITS: &str = "Scene limits";

/// What a scene file may make the renderer allocate (scene files are untrusted). The flag
/// names are the ones `scene::limits::FLAGS` puts in the error when a limit is exceeded.
#[derive(Args, Clone, Debug)]
pub struct LimitArgs {
    /// Most triangles over all meshes.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_triangles)]
    pub max_triangles: u64,
    /// Most vertices over all meshes; also the most elements of any one accessor.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_vertices)]
    pub max_vertices: u64,
    /// Largest width or height of any one image, in pixels.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_texture_dimension)]
    pub max_texture_size: u32,
    /// Most pixels over all images.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_texture_pixels_total)]
    pub max_texture_pixels: u64,
    /// Largest buffer, image file or scene file, in MiB.
    #[arg(long, help_heading = LIMITS, value_name = "MIB", default_value_t = Limits::default().max_buffer_bytes >> 20)]
    pub max_buffer_mib: u64,
    /// Most MiB of all buffers and images loaded from URIs together.
    #[arg(long, help_heading = LIMITS, value_name = "MIB", default_value_t = Limits::default().max_total_bytes >> 20)]
    pub max_total_mib: u64,
    /// Deepest node hierarchy (roots are at depth 1).
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_node_depth)]
    pub max_node_depth: u32,
    /// Most nodes, including those made for EXT_mesh_gpu_instancing copies.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_nodes)]
    pub max_nodes: u32,
    /// Longest `data:` URI, in MiB of encoded text.
    #[arg(
        long,
        help_heading = LIMITS,
        value_name = "MIB",
        default_value_t = Limits::default().max_data_uri_bytes >> 20
    )]
    pub max_data_uri_mib: u64,
    /// Most mesh instances (one per primitive of each node drawing a mesh).
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_instances)]
    pub max_instances: u64,
    /// Most keyframe times and values over all animations.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_animation_keys)]
    pub max_animation_keys: u64,
    /// Most skin joints over all skins.
    #[arg(long, help_heading = LIMITS, value_name = "N", default_value_t = Limits::default().max_joints)]
    pub max_joints: u64,
}

impl LimitArgs {
    pub fn limits(&self) -> Limits {
        // A MiB count too large for a byte count in u64 is no limit at all.
        let mib = |n: u64| n.saturating_mul(1 << 20);
        Limits {
            max_triangles: self.max_triangles,
            max_vertices: self.max_vertices,
            max_texture_dimension: self.max_texture_size,
            max_texture_pixels_total: self.max_texture_pixels,
            max_buffer_bytes: mib(self.max_buffer_mib),
            max_total_bytes: mib(self.max_total_mib),
            max_node_depth: self.max_node_depth,
            max_nodes: self.max_nodes,
            max_data_uri_bytes: mib(self.max_data_uri_mib),
            max_instances: self.max_instances,
            max_animation_keys: self.max_animation_keys,
            max_joints: self.max_joints,
        }
    }
}

impl SceneArgs {
    pub fn load(&self) -> Result<Scene> {
        let opts = LoadOptions { allow_outside_uris: self.allow_outside_uris, limits: self.limits.limits() };
        match &self.scene {
            Some(s) => load_scene(s, &opts),
            None => load_scene(&default_scene_path().to_string_lossy(), &opts),
        }
    }
}

/// What lights the scene from outside (render, reference, view, plan and the benches take the
/// same flags, so a hybrid frame can be compared with its reference). Without any, a scene
/// that brings no light of its own gets the default light (src/render/default_light.rs).
#[derive(Args, Clone, Debug)]
pub struct EnvironmentArgs {
    /// Equirectangular environment map (.exr or .hdr; row 0 is straight up) lighting the scene,
    /// in place of the default light.
    #[arg(long, conflicts_with_all = ["sky", "no_default_light"])]
    env: Option<PathBuf>,
    /// Multiplier on the environment map's radiance.
    #[arg(long, default_value_t = 1.0, requires = "env")]
    env_intensity: f32,
    /// Constant environment radiance R,G,B, in place of the default light.
    #[arg(long, value_parser = parse_rgb, conflicts_with = "no_default_light")]
    sky: Option<glam::Vec3>,
    /// No default light: a scene without punctual lights or significant emitters stays black
    /// but for its emission (by default such a scene is lit by a daylight sky with a sun).
    #[arg(long)]
    no_default_light: bool,
}

impl EnvironmentArgs {
    pub fn environment(&self) -> crate::render::Environment {
        use crate::render::Environment;
        match (&self.env, self.sky) {
            (Some(path), _) => Environment::Map(path.clone(), self.env_intensity),
            (None, Some(c)) => Environment::Constant(c),
            (None, None) if self.no_default_light => Environment::Constant(glam::Vec3::ZERO),
            (None, None) => Environment::DefaultLight,
        }
    }
}

/// Parses `R,G,B` (three non-negative numbers).
fn parse_rgb(s: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<Option<f32>> = s.split(',').map(|p| p.trim().parse::<f32>().ok()).collect();
    match parts.as_slice() {
        [Some(r), Some(g), Some(b)] if [r, g, b].iter().all(|c| c.is_finite() && **c >= 0.0) => {
            Ok(glam::Vec3::new(*r, *g, *b))
        }
        _ => Err(format!("{s}: expected R,G,B with three non-negative numbers, e.g. 0.5,0.6,0.8")),
    }
}

/// The built-in default scene (assets/default/cornell.gltf).
pub fn default_scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default/cornell.gltf")
}

/// Loads a scene file or a built-in scene (`builtin:NAME`).
pub fn load_scene(spec: &str, opts: &LoadOptions) -> Result<Scene> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        return scene::builtin::by_name(name);
    }
    let scene = scene::load_gltf(Path::new(spec), opts)?;
    Ok(scene)
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let parsed = s.split_once(['x', 'X']).and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => bail!("--size {s}: expected WIDTHxHEIGHT with positive integers, e.g. 640x360"),
    }
}

pub fn main() -> ExitCode {
    run(Cli::parse())
}

/// Runs the command line given as a list of arguments (benches use this).
pub fn main_with<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    run(Cli::parse_from(args))
}

fn run(cli: Cli) -> ExitCode {
    let result = match cli.command {
        Command::Render(a) => render::run(&a),
        Command::Info(a) => info::run(&a),
        Command::Plan(a) => plan::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Reference(a) => reference::run(&a),
        Command::View(a) => view::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // Whoever read the output stopped (`| head`): nothing went wrong here.
        Err(e) if e.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) => {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            if e.chain().any(|c| c.is::<crate::gpu::OutOfDeviceMemory>()) {
                // Frame-sized images are most of what the renderer allocates.
                eprintln!("hint: the device is out of memory; a smaller --size needs less");
            }
            ExitCode::FAILURE
        }
    }
}
