//! `hybrid-rt bench sweep`: speed against accuracy. Each configuration of the hybrid frame
//! (denoiser, shadow rays, GI bounces, reflection rays, TAA) is rendered on a frozen scene and
//! measured twice over:
//!
//! - **Frame time**: the wall-clock time of one frame from recording to its fence; the median
//!   over the last `timed_frames` of each of `rounds` runs (the first frames include lavapipe's
//!   pipeline compilation and histories that are still filling). The per-pass split comes from GPU
//!   timestamp queries and is kept beside it, with their sum: on a GPU the two agree to within
//!   the recording cost, on lavapipe the timestamps miss most compute passes.
//! - **Error**: HDR-FLIP (and PSNR, SSIM after ACES + sRGB) of the frame after `frames` frames
//!   (static camera, `frame_dt` 0, so the temporal passes converge as far as they do) against
//!   the reference path tracer at the same size.
//!
//! The reference is cached on disk (`CACHE/reference/<scene hash>-<camera>-<WxH>-<spp>spp-
//! <bounces>b.exr` with a JSON sidecar), keyed by a hash of the scene's bytes (the file and the
//! buffers and images it names), the camera, the size, the sample count and the path length.
//! It is the mean of two independent halves (different seeds, spp/2 samples each); the FLIP
//! between the halves is kept as the reference's noise floor: an error near it is not
//! resolved by the reference.
//!
//! Each sweep is also cached for `hybrid-rt render --target-ms / --target-error`
//! (`CACHE/sweep/<scene hash>-<camera>-<WxH>-<backend>-<device>.json`, the latest run wins).
//! A scene lit by the default light (src/render/default_light.rs) has `-daylight` after its
//! hash in both keys, so results with and without it never stand in for each other.

use super::target::{self, Measured, Target};
use super::{median, slug};
use crate::backend::Backend;
use crate::gpu::{Context, ShaderLibrary};
use crate::image_io::{self, CpuImage, Texels};
use crate::metrics::{self, DisplayTransform, HdrFlipOptions};
use crate::passes::pathtrace;
use crate::render::{CameraChoice, Environment, RenderMode, Renderer, Settings, default_light};
use crate::scene::Scene;
use anyhow::{Context as _, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One configuration of the hybrid frame. Its name lists the settings as letter + number,
/// joined by `-`: `d` SVGF à-trous iterations (0 = denoiser off), `s` shadow rays per pixel
/// and area light at most (s_max), `b` GI bounces, `r` reflection rays per pixel, `t0`
/// when TAA is off, and `f1` when every pass runs instead of the scene's frame plan
/// (src/render/plan.rs): a pair differing only in `f` shows what the plan saves and costs. Settings left out of a name take the defaults (`d4-s5-b1-r1`, TAA on:
/// the renderer's defaults, and what `hybrid-rt render` draws).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Config {
    pub denoise_iterations: u32,
    pub shadow_s_max: u32,
    pub gi_bounces: u32,
    pub reflection_rays: u32,
    pub taa: bool,
    /// Every pass (`--full`) instead of the frame plan.
    #[serde(default)]
    pub full: bool,
}

impl Default for Config {
    fn default() -> Self {
        let s = Settings::default();
        Self {
            denoise_iterations: if s.denoiser { s.denoise.iterations } else { 0 },
            shadow_s_max: s.shadows.s_max,
            gi_bounces: s.gi.bounces,
            reflection_rays: s.reflections.rays,
            taa: true,
            full: false,
        }
    }
}

impl std::fmt::Display for Config {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "d{}-s{}-b{}-r{}",
            self.denoise_iterations, self.shadow_s_max, self.gi_bounces, self.reflection_rays
        )?;
        if !self.taa {
            write!(f, "-t0")?;
        }
        if self.full {
            write!(f, "-f1")?;
        }
        Ok(())
    }
}

impl std::str::FromStr for Config {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        let mut c = Config::default();
        for part in s.split('-') {
            let (key, value) = part.split_at(part.find(|ch: char| ch.is_ascii_digit()).unwrap_or(part.len()));
            let Ok(n) = value.parse::<u32>() else {
                bail!("configuration '{s}': '{part}' is not a letter followed by a number (e.g. d4-s5-b1-r1)");
            };
            let (slot, range) = match key {
                "d" => (&mut c.denoise_iterations, 0..=8),
                "s" => (&mut c.shadow_s_max, 1..=16),
                "b" => (&mut c.gi_bounces, 1..=8),
                "r" => (&mut c.reflection_rays, 1..=8),
                "t" => {
                    if n > 1 {
                        bail!("configuration '{s}': t takes 0 (TAA off) or 1 (on)");
                    }
                    c.taa = n == 1;
                    continue;
                }
                "f" => {
                    if n > 1 {
                        bail!("configuration '{s}': f takes 0 (frame plan) or 1 (every pass)");
                    }
                    c.full = n == 1;
                    continue;
                }
                _ => bail!(
                    "configuration '{s}': unknown setting '{key}' (d: denoiser iterations, s: shadow s_max, \
                     b: GI bounces, r: reflection rays, t: TAA 0/1, f: every pass 0/1)"
                ),
            };
            if !range.contains(&n) {
                bail!("configuration '{s}': {key}{n} is outside {}..={}", range.start(), range.end());
            }
            *slot = n;
        }
        Ok(c)
    }
}

impl Config {
    /// Sets what this configuration decides in `s`, leaving the rest.
    pub fn apply(&self, s: &mut Settings) {
        s.denoiser = self.denoise_iterations > 0;
        if self.denoise_iterations > 0 {
            s.denoise.iterations = self.denoise_iterations;
        }
        s.shadows.s_max = self.shadow_s_max;
        s.gi.bounces = self.gi_bounces;
        s.reflections.rays = self.reflection_rays;
        s.taa = self.taa;
        s.full = self.full;
    }
}

/// The default configurations: each axis moved away from the renderer's defaults (d4-s5-b1-r1)
/// on its own, once with the denoiser on and once with it off, plus the cheapest and the most
/// expensive corners. 15 configurations take ~5 minutes at 320x180 on a 2-core lavapipe;
/// the full grid (5 x 3 x 2 x 2 x 2 = 120) would take hours and add few new front points.
pub const DEFAULT_CONFIGS: &[&str] = &[
    "d0-s5-b1-r1-t0", // no temporal filtering at all: the raw one-sample frame
    "d0-s1-b1-r1",
    "d0-s5-b1-r1",
    "d1-s5-b1-r1",
    "d2-s5-b1-r1",
    "d4-s5-b1-r1",    // the renderer's defaults
    "d4-s5-b1-r1-f1", // the same with every pass: what the frame plan saves and costs
    "d4-s5-b1-r1-t0",
    "d4-s1-b1-r1",
    "d4-s8-b1-r1",
    "d0-s5-b2-r1",
    "d4-s5-b2-r1",
    "d0-s5-b1-r2",
    "d4-s5-b1-r2",
    "d4-s8-b2-r2",
];

pub fn default_configs() -> Vec<Config> {
    DEFAULT_CONFIGS.iter().map(|s| s.parse().expect("the default configurations parse")).collect()
}

/// How a sweep is run.
#[derive(Clone, Debug)]
pub struct Options {
    pub width: u32,
    pub height: u32,
    pub configs: Vec<Config>,
    /// Frames rendered per configuration; the error is measured on the last.
    pub frames: u32,
    /// The last this-many frames give the median frame time (must be fewer than `frames`).
    pub timed_frames: u32,
    /// Timing rounds: every configuration is run this many times, one round over all of them
    /// after another, and its frame time is the median of all rounds' timed frames. A shared
    /// 2-core machine drifts by tens of percent over minutes; rounds spread the drift over every
    /// configuration instead of charging it to whichever ran at the time. The error comes
    /// from the first round.
    pub rounds: u32,
    pub reference_spp: u32,
    /// Scattering events per reference path at most.
    pub reference_bounces: u32,
    pub camera: CameraChoice,
    /// Where references and sweep results are cached (`out/cache` by default).
    pub cache_dir: PathBuf,
    /// What lights the scene from outside: `Environment::DefaultLight` or black (both the
    /// reference and every configuration).
    pub environment: Environment,
    /// Render the reference again even when a cached one exists (and replace it).
    pub fresh_reference: bool,
}

/// Seeds of the reference's two halves (and nothing else uses them).
const REFERENCE_SEEDS: [u32; 2] = [0x5eed_0001, 0x5eed_0002];

/// What the reference's sidecar records: what it was made from and by whom.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceMade {
    pub scene: String,
    pub scene_hash: String,
    pub camera: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_bounces: u32,
    pub seeds: [u32; 2],
    /// HDR-FLIP between the two halves (spp/2 each): the noise of a reference with half the
    /// samples; the full reference's own error is lower.
    pub noise_flip: f64,
    /// Wall-clock seconds the reference took to render.
    pub render_seconds: f64,
    pub backend: String,
    pub device: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub path: String,
    /// Taken from the cache (not rendered by this run).
    pub cached: bool,
    /// Seconds this run spent getting it (rendering it, or reading it from the cache).
    pub seconds: f64,
    #[serde(flatten)]
    pub made: ReferenceMade,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassMs {
    pub pass: String,
    /// Median GPU ms over the timed frames.
    pub ms: f64,
}

/// One measured configuration.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Point {
    pub name: String,
    pub config: Config,
    /// Median over the timed frames of the frame's wall-clock time, recording to fence
    /// (`Renderer::last_frame_wall_ms` says why not the timestamps).
    pub frame_ms: f64,
    /// The wall-clock time of each timed frame.
    pub frame_ms_samples: Vec<f64>,
    /// Median of the summed per-pass GPU timestamps (what the driver reports; on lavapipe it
    /// misses most compute passes).
    #[serde(default)]
    pub timestamp_ms: f64,
    pub passes: Vec<PassMs>,
    /// HDR-FLIP against the reference (mean over pixels; 0 = identical).
    pub flip: f64,
    /// PSNR (dB) after ACES + sRGB; absent when the images are identical (infinite).
    pub psnr_db: Option<f64>,
    /// SSIM after ACES + sRGB.
    pub ssim: f64,
    /// On the Pareto front of frame time against FLIP.
    pub pareto: bool,
    /// Wall-clock seconds this configuration took to measure.
    pub seconds: f64,
}

impl Point {
    pub fn measured(&self) -> Measured {
        Measured { ms: self.frame_ms, error: self.flip }
    }
}

/// The sweep of one scene at one size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneSweep {
    /// The scene as given (a path or builtin:NAME).
    pub scene: String,
    pub scene_name: String,
    pub scene_hash: String,
    pub camera: String,
    pub width: u32,
    pub height: u32,
    pub backend: String,
    pub device: String,
    pub driver: String,
    pub frames: u32,
    pub timed_frames: u32,
    /// Timing rounds (see `Options::rounds`; 0 in sweeps cached before rounds existed).
    #[serde(default)]
    pub rounds: u32,
    pub reference: ReferenceInfo,
    pub points: Vec<Point>,
    /// Names of the configurations on the Pareto front, fastest first.
    pub pareto_front: Vec<String>,
    /// Wall-clock seconds of the whole sweep, reference included.
    pub seconds: f64,
}

/// 64-bit FNV-1a: a stable hash (unlike std's) for cache keys; collisions are not a concern.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The URIs of buffers and images that a glTF (JSON, or the JSON chunk of a GLB) names outside
/// itself (not `data:`).
fn external_uris(bytes: &[u8]) -> Vec<String> {
    let json = if bytes.starts_with(b"glTF") && bytes.len() >= 20 {
        let len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
        bytes.get(20..20 + len).unwrap_or(&[])
    } else {
        bytes
    };
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(json) else { return Vec::new() };
    ["buffers", "images"]
        .iter()
        .filter_map(|k| doc.get(k).and_then(|v| v.as_array()))
        .flatten()
        .filter_map(|item| item.get("uri").and_then(|u| u.as_str()))
        .filter(|u| !u.starts_with("data:"))
        .map(str::to_string)
        .collect()
}

/// A hash of the scene's content: the bytes of the file and of the buffers and images it
/// names (a built-in scene: its name). Renaming or moving a scene keeps its cached results;
/// editing any of its files drops them.
pub fn scene_hash(spec: &str) -> Result<String> {
    let mut h = Fnv::new();
    if let Some(name) = spec.strip_prefix("builtin:") {
        h.write(b"builtin:");
        h.write(name.as_bytes());
    } else {
        let path = Path::new(spec);
        let bytes = std::fs::read(path).with_context(|| format!("{spec}: cannot read the scene file"))?;
        h.write(&bytes);
        let dir = path.parent().unwrap_or(Path::new("."));
        for uri in external_uris(&bytes) {
            // A file the loader could not read has already failed the load; skip it here.
            if let Ok(b) = std::fs::read(dir.join(&uri)) {
                h.write(uri.as_bytes());
                h.write(&b);
            }
        }
    }
    Ok(format!("{:016x}", h.0))
}

/// The scene as it appears in cache keys: its content hash, marked when the default light
/// lights it.
pub fn lit_scene_key(hash: String, default_light: bool) -> String {
    if default_light { format!("{hash}-daylight") } else { hash }
}

/// The camera as it appears in cache keys.
pub fn camera_key(c: &CameraChoice) -> String {
    match c {
        CameraChoice::Default => "default".into(),
        CameraChoice::Index(i) => format!("camera{i}"),
        CameraChoice::Name(n) => format!("camera-{}", slug(n)),
    }
}

/// The file `render --target-*` reads for a scene, camera, size, backend and device.
pub fn sweep_cache_path(
    cache_dir: &Path,
    scene_hash: &str,
    camera: &str,
    (width, height): (u32, u32),
    backend: Backend,
    device: &str,
) -> PathBuf {
    cache_dir.join("sweep").join(format!(
        "{scene_hash}-{camera}-{width}x{height}-{}-{}.json",
        backend.variant(),
        slug(device)
    ))
}

/// Renders the reference (or reads it from the cache).
fn reference(
    ctx: &std::sync::Arc<Context>,
    shaders: &ShaderLibrary,
    spec: &str,
    scene: &Scene,
    backend: Backend,
    opts: &Options,
    scene_hash: &str,
) -> Result<(CpuImage, ReferenceInfo)> {
    let start = Instant::now();
    let (w, h) = (opts.width, opts.height);
    let camera = camera_key(&opts.camera);
    let stem = format!("{scene_hash}-{camera}-{w}x{h}-{}spp-{}b", opts.reference_spp, opts.reference_bounces);
    let dir = opts.cache_dir.join("reference");
    let (exr, sidecar) = (dir.join(format!("{stem}.exr")), dir.join(format!("{stem}.json")));
    let info = |cached, made| ReferenceInfo {
        path: exr.display().to_string(),
        cached,
        seconds: start.elapsed().as_secs_f64(),
        made,
    };
    if !opts.fresh_reference && exr.is_file() && sidecar.is_file() {
        let made: ReferenceMade = serde_json::from_slice(&std::fs::read(&sidecar)?)
            .with_context(|| format!("{}: not a reference sidecar", sidecar.display()))?;
        let img = image_io::read_exr_channels(&exr)?;
        if (img.width, img.height) != (w, h) {
            bail!(
                "{}: {}x{} instead of {w}x{h}; delete it or pass --fresh-reference",
                exr.display(),
                img.width,
                img.height
            );
        }
        log::info!("reference from the cache: {}", exr.display());
        return Ok((img, info(true, made)));
    }
    if opts.reference_spp < 2 || opts.reference_spp % 2 != 0 {
        bail!("--reference-spp {}: must be even and at least 2 (the reference is two halves)", opts.reference_spp);
    }
    let half = opts.reference_spp / 2;
    let bar = crate::cli::progress_bar(opts.reference_spp as u64, "reference spp");
    bar.set_message(format!("{}x{} {}", w, h, scene.name));
    let mut halves = Vec::new();
    for seed in REFERENCE_SEEDS {
        let settings = Settings {
            width: w,
            height: h,
            mode: RenderMode::Reference { seed, max_bounces: opts.reference_bounces },
            environment: opts.environment.clone(),
            ..Default::default()
        };
        let mut r = Renderer::new(ctx, shaders, scene.clone(), settings, &opts.camera, backend)?;
        for _ in 0..half {
            r.render_frame()?;
            bar.inc(1);
        }
        halves.push(r.read_output(pathtrace::COLOR)?);
    }
    bar.finish_and_clear();
    let render_seconds = start.elapsed().as_secs_f64();
    let noise_flip = metrics::hdr_flip(&halves[0], &halves[1], &HdrFlipOptions::default())
        .context("FLIP between the reference's halves")?
        .mean;
    let mut img = halves.swap_remove(0);
    if let (Texels::F32(a), Texels::F32(b)) = (&mut img.texels, &halves[0].texels) {
        for (x, y) in a.iter_mut().zip(b) {
            *x = 0.5 * (*x + y);
        }
    }
    let made = ReferenceMade {
        scene: spec.to_string(),
        scene_hash: scene_hash.to_string(),
        camera,
        width: w,
        height: h,
        spp: opts.reference_spp,
        max_bounces: opts.reference_bounces,
        seeds: REFERENCE_SEEDS,
        noise_flip,
        render_seconds,
        backend: backend.variant().into(),
        device: ctx.caps.device_name.clone(),
    };
    image_io::write_exr(&exr, &img, image_io::channel_names(img.channels))?;
    image_io::write_atomic(&sidecar, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&made)?)?))?;
    Ok((img, info(false, made)))
}

/// What one run of a configuration timed, and its last frame.
struct Run {
    totals: Vec<f64>,
    stamps: Vec<f64>,
    per_pass: Vec<(String, Vec<f64>)>,
    last_frame: CpuImage,
}

/// Renders `opts.frames` frames of one configuration, timing the last `timed_frames`.
fn run_config(
    ctx: &std::sync::Arc<Context>,
    shaders: &ShaderLibrary,
    scene: &Scene,
    backend: Backend,
    opts: &Options,
    config: Config,
    bar: &indicatif::ProgressBar,
) -> Result<Run> {
    let mut settings = Settings {
        width: opts.width,
        height: opts.height,
        frame_dt: 0.0,
        environment: opts.environment.clone(),
        ..Default::default()
    };
    config.apply(&mut settings);
    let mut r = Renderer::new(ctx, shaders, scene.clone(), settings, &opts.camera, backend)?;
    let mut totals = Vec::new();
    let mut stamps = Vec::new();
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    for n in 0..opts.frames {
        r.render_frame()?;
        bar.inc(1);
        if n < opts.frames - opts.timed_frames {
            continue;
        }
        totals.push(r.last_frame_wall_ms);
        stamps.push(r.last_pass_times.iter().map(|t| t.gpu_ms).sum());
        if per_pass.is_empty() {
            per_pass = r.last_pass_times.iter().map(|t| (t.pass.clone(), Vec::new())).collect();
        }
        for ((_, v), t) in per_pass.iter_mut().zip(&r.last_pass_times) {
            v.push(t.gpu_ms);
        }
    }
    let out = r.hdr_output().to_string();
    let last_frame = r.read_output(&out)?;
    Ok(Run { totals, stamps, per_pass, last_frame })
}

/// Measures one configuration's error (and first round's times) from its first run.
fn measure(config: Config, run: Run, reference: &CpuImage, seconds: f64) -> Result<Point> {
    let Run { totals, stamps, per_pass, last_frame: img } = run;
    let name = config.to_string();
    let flip =
        metrics::hdr_flip(reference, &img, &HdrFlipOptions::default()).with_context(|| format!("{name}: FLIP"))?;
    let display = DisplayTransform::AcesSrgb { exposure: 0.0 };
    let psnr = metrics::psnr_display(reference, &img, display).with_context(|| format!("{name}: PSNR"))?;
    let ssim = metrics::ssim_with(reference, &img, display).with_context(|| format!("{name}: SSIM"))?;
    Ok(Point {
        name,
        config,
        frame_ms: median(&totals),
        frame_ms_samples: totals,
        timestamp_ms: median(&stamps),
        passes: per_pass.into_iter().map(|(pass, v)| PassMs { pass, ms: median(&v) }).collect(),
        flip: flip.mean,
        psnr_db: psnr.is_finite().then_some(psnr),
        ssim,
        pareto: false,
        seconds,
    })
}

/// Sweeps every configuration of `opts` over one scene (`spec` as the user named it) and caches
/// the result for `render --target-*`.
pub fn sweep_scene(
    ctx: &std::sync::Arc<Context>,
    shaders: &ShaderLibrary,
    spec: &str,
    scene: &Scene,
    backend: Backend,
    opts: &Options,
) -> Result<SceneSweep> {
    if opts.configs.is_empty() {
        bail!("no configurations to sweep");
    }
    if opts.timed_frames == 0 || opts.timed_frames >= opts.frames {
        bail!(
            "--timed-frames {} must be at least 1 and fewer than --frames {} (the first frame warms up)",
            opts.timed_frames,
            opts.frames
        );
    }
    let start = Instant::now();
    let hash = lit_scene_key(scene_hash(spec)?, default_light::choose(&opts.environment, scene).default_light);
    let (reference, reference_info) = reference(ctx, shaders, spec, scene, backend, opts, &hash)?;
    let rounds = opts.rounds.max(1);
    let bar = crate::cli::progress_bar(opts.configs.len() as u64 * opts.frames as u64 * rounds as u64, "frames");
    let mut points: Vec<Point> = Vec::new();
    for round in 0..rounds {
        for (i, &config) in opts.configs.iter().enumerate() {
            bar.set_message(format!("{config} (round {}/{rounds})", round + 1));
            let run_start = Instant::now();
            let run = run_config(ctx, shaders, scene, backend, opts, config, &bar)?;
            if round == 0 {
                let p = measure(config, run, &reference, run_start.elapsed().as_secs_f64())?;
                log::info!("{}: {:.2} ms, FLIP {:.4}", p.name, p.frame_ms, p.flip);
                points.push(p);
            } else {
                let p = &mut points[i];
                p.frame_ms_samples.extend(run.totals);
                p.frame_ms = median(&p.frame_ms_samples);
                p.seconds += run_start.elapsed().as_secs_f64();
            }
        }
    }
    bar.finish_and_clear();
    let measured: Vec<Measured> = points.iter().map(Point::measured).collect();
    let front = target::pareto_front(&measured);
    for &i in &front {
        points[i].pareto = true;
    }
    let sweep = SceneSweep {
        scene: spec.to_string(),
        scene_name: scene.name.clone(),
        scene_hash: hash,
        camera: camera_key(&opts.camera),
        width: opts.width,
        height: opts.height,
        backend: backend.variant().into(),
        device: ctx.caps.device_name.clone(),
        driver: ctx.caps.driver.clone(),
        frames: opts.frames,
        timed_frames: opts.timed_frames,
        rounds,
        reference: reference_info,
        pareto_front: front.iter().map(|&i| points[i].name.clone()).collect(),
        points,
        seconds: start.elapsed().as_secs_f64(),
    };
    let cache = sweep_cache_path(
        &opts.cache_dir,
        &sweep.scene_hash,
        &sweep.camera,
        (sweep.width, sweep.height),
        backend,
        &sweep.device,
    );
    image_io::write_atomic(&cache, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&sweep)?)?))?;
    Ok(sweep)
}

/// A table of a sweep's points for the terminal; `*` marks the Pareto front.
pub fn table(s: &SceneSweep) -> String {
    let mut t = format!(
        "{} ({}x{}, {} backend, {} frames, {} timing round(s), reference {} spp{}; reference noise FLIP {:.4})\n",
        s.scene_name,
        s.width,
        s.height,
        s.backend,
        s.frames,
        s.rounds.max(1),
        s.reference.made.spp,
        if s.reference.cached { ", cached" } else { "" },
        s.reference.made.noise_flip
    );
    t += &format!(
        "  {:<16} {:>9} {:>9} {:>8} {:>9} {:>7}\n",
        "configuration", "frame ms", "stamp ms", "FLIP", "PSNR dB", "SSIM"
    );
    let mut order: Vec<&Point> = s.points.iter().collect();
    order.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    for p in order {
        let psnr = p.psnr_db.map_or("inf".to_string(), |v| format!("{v:.2}"));
        t += &format!(
            "{} {:<16} {:>9.2} {:>9.2} {:>8.4} {:>9} {:>7.4}\n",
            if p.pareto { "*" } else { " " },
            p.name,
            p.frame_ms,
            p.timestamp_ms,
            p.flip,
            psnr,
            p.ssim
        );
    }
    for full in s.points.iter().filter(|p| p.config.full) {
        let planned = Config { full: false, ..full.config };
        if let Some(p) = s.points.iter().find(|p| p.config == planned) {
            let pass_names = |x: &Point| x.passes.iter().map(|m| m.pass.clone()).collect::<Vec<_>>();
            // Where the plan leaves nothing out the two run the same passes, and any
            // difference is the machine's noise.
            let note = if pass_names(p) == pass_names(full) {
                " (the plan leaves nothing out on this scene: the same passes ran, so this is noise)"
            } else {
                ""
            };
            t += &format!(
                "  frame plan ({}) against every pass ({}): {:+.1}% frame time, FLIP {:+.4}{note}\n",
                p.name,
                full.name,
                100.0 * (p.frame_ms / full.frame_ms - 1.0),
                p.flip - full.flip
            );
        }
    }
    t
}

/// For `render --target-ms / --target-error`: the configuration picked from the cached sweep
/// of this scene (as named on the command line, loaded, and lit by `environment`), camera,
/// size, backend and device, and why.
pub fn pick_for_render(
    cache_dir: &Path,
    (spec, scene, environment): (&str, &Scene, &Environment),
    camera: &CameraChoice,
    size: (u32, u32),
    backend: Backend,
    device: &str,
    goal: Target,
) -> Result<(Config, String)> {
    let lit = default_light::choose(environment, scene).default_light;
    let hash = lit_scene_key(scene_hash(spec)?, lit);
    let cam = camera_key(camera);
    let path = sweep_cache_path(cache_dir, &hash, &cam, size, backend, device);
    if !path.is_file() {
        let (w, h) = size;
        let mut camera_arg =
            if matches!(camera, CameraChoice::Default) { String::new() } else { format!(" --camera {cam}") };
        if !lit && default_light::choose(&Environment::DefaultLight, scene).default_light {
            camera_arg += " --no-default-light";
        }
        let mut msg = format!(
            "no speed/accuracy sweep of {spec} at {w}x{h} ({} backend, {cam} camera) on {device} in {}; \
             make one with: hybrid-rt bench sweep {spec} --size {w}x{h}{camera_arg} --backend {}",
            backend.variant(),
            cache_dir.join("sweep").display(),
            backend.variant()
        );
        let other = other_sizes(cache_dir, &hash, &cam, backend, device);
        if !other.is_empty() {
            msg += &format!(" (sweeps exist at {}: pass one as --size)", other.join(", "));
        }
        bail!(msg);
    }
    let sweep: SceneSweep = serde_json::from_slice(&std::fs::read(&path)?)
        .with_context(|| format!("{}: not a sweep result; delete it and run the sweep again", path.display()))?;
    let measured: Vec<Measured> = sweep.points.iter().map(Point::measured).collect();
    let pick = target::select(&measured, goal)?;
    let p = &sweep.points[pick.index];
    let why = format!(
        "{}: {} (sweep of {} configurations, error after {} frames, {})",
        p.name,
        pick.why,
        sweep.points.len(),
        sweep.frames,
        path.display()
    );
    Ok((p.config, why))
}

/// Sizes at which a sweep of this scene, camera, backend and device is cached.
fn other_sizes(cache_dir: &Path, hash: &str, camera: &str, backend: Backend, device: &str) -> Vec<String> {
    let prefix = format!("{hash}-{camera}-");
    let suffix = format!("-{}-{}.json", backend.variant(), slug(device));
    let Ok(entries) = std::fs::read_dir(cache_dir.join("sweep")) else { return Vec::new() };
    let mut sizes: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| Some(n.strip_prefix(&prefix)?.strip_suffix(&suffix)?.to_string()))
        .collect();
    sizes.sort();
    sizes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_names_round_trip() {
        for s in DEFAULT_CONFIGS {
            assert_eq!(s.parse::<Config>().unwrap().to_string(), *s);
        }
        let c: Config = "d2".parse().unwrap();
        assert_eq!(c, Config { denoise_iterations: 2, ..Default::default() });
        assert_eq!("s8-t0".parse::<Config>().unwrap().to_string(), "d4-s8-b1-r1-t0");
        for bad in ["x3", "d", "d-1", "s0", "d9", "t2", "", "d4s5"] {
            assert!(bad.parse::<Config>().is_err(), "{bad} should not parse");
        }
    }

    #[test]
    fn config_applies_to_settings() {
        let mut s = Settings::default();
        "d0-s8-b2-r2-t0".parse::<Config>().unwrap().apply(&mut s);
        assert!(!s.denoiser && !s.taa);
        assert_eq!((s.shadows.s_max, s.gi.bounces, s.reflections.rays), (8, 2, 2));
        "d2".parse::<Config>().unwrap().apply(&mut s);
        assert!(s.denoiser && s.taa);
        assert_eq!(s.denoise.iterations, 2);
    }

    #[test]
    fn glb_and_gltf_uris() {
        let json = br#"{"buffers":[{"uri":"a.bin"},{"uri":"data:x"}],"images":[{"uri":"t.png"}]}"#;
        assert_eq!(external_uris(json), vec!["a.bin", "t.png"]);
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&0u32.to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(json);
        assert_eq!(external_uris(&glb), vec!["a.bin", "t.png"]);
        assert!(external_uris(b"\x00\x01").is_empty());
        assert_ne!(scene_hash("builtin:a").unwrap(), scene_hash("builtin:b").unwrap());
    }
}
