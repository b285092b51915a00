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
//! <bounces>b-<brdf>.exr` with a JSON sidecar), keyed by a hash of the scene's bytes (the file and
//! the buffers and images it names), the camera, the size, the sample count, the path length
//! and the material model (the default one, which both the reference and the frames use).
//! It is the mean of two independent halves (different seeds, spp/2 samples each); the FLIP
//! between the halves is kept as the reference's noise floor: an error near it is not
//! resolved by the reference.
//!
//! Each sweep is also cached for `hybrid-rt render --target-ms / --target-error`
//! (`CACHE/sweep/<scene hash>-<camera>-<WxH>-<backend>-<device>.json`, the latest run wins).
//! A scene lit by the default light (src/render/default_light.rs) has `-daylight` after its
//! hash in both keys, so results with and without it never stand in for each other.

mod cache;
mod config;
mod report;

pub use cache::{camera_key, lit_scene_key, pick_for_render, scene_hash, sweep_cache_path};
pub use config::{Config, DEFAULT_CONFIGS, default_configs};
pub use report::{path_tracer_flip_at, table};

use super::median;
use super::target::{self, Measured};
use crate::backend::Backend;
use crate::gpu::{Context, ShaderLibrary};
use crate::image_io::{self, CpuImage, Texels};
use crate::metrics::{self, DisplayTransform, HdrFlipOptions};
use crate::passes::pathtrace;
use crate::render::{CameraChoice, Environment, RenderMode, Renderer, Settings, default_light};
use crate::scene::Scene;
use anyhow::{Context as _, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::Instant;

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
    /// The path tracer's curve: 1, 2, 4, ... up to this many spp (0: none).
    pub path_tracer_spp: u32,
    pub camera: CameraChoice,
    /// Where references and sweep results are cached (`out/cache` by default).
    pub cache_dir: PathBuf,
    /// What lights the scene from outside: `Environment::DefaultLight` or black (both the
    /// reference and every configuration).
    pub environment: Environment,
    /// Render the reference again even when a cached one exists (and replace it).
    pub fresh_reference: bool,
    /// The configurations' random streams (`Settings::seed`; the reference's and the path
    /// tracer's are fixed). One seed's error moves with any change to the bits a ray is drawn
    /// from; sweeps with several tell a change from that noise.
    pub seed: u32,
}

/// Seeds of the reference's two halves (and nothing else uses them).
const REFERENCE_SEEDS: [u32; 2] = [0x5eed_0001, 0x5eed_0002];
/// Seed of the path tracer's curve: independent of the reference it is measured against.
const PATH_TRACER_SEED: u32 = 0x5eed_0003;

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
    /// HDR-FLIP of one more frame after a camera cut at the end of the run, the same view:
    /// what the frame shows without SVGF's and TAA's history (the radiance cache keeps its
    /// cells, as it does on a cut). Absent in sweeps cached before it was measured.
    #[serde(default)]
    pub cut_flip: Option<f64>,
    /// HDR-FLIP of the run's first frame: no SVGF or TAA history and an empty radiance cache,
    /// what a renderer started on this view shows. Absent in sweeps cached before it was
    /// measured.
    #[serde(default)]
    pub first_flip: Option<f64>,
    /// Mean luminance over the reference's, lights seen directly left out
    /// ([`metrics::luminance_ratio`]): the light the frame keeps. Absent in sweeps cached
    /// before it was measured.
    #[serde(default)]
    pub luminance_ratio: Option<f64>,
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

/// One point of the path tracer's curve: the mean of `spp` samples per pixel.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PathTracerPoint {
    pub spp: u32,
    /// `spp` times the median wall-clock time of one sample (frames 2.. of the run: the first
    /// includes pipeline compilation), recording to fence like the configurations' frames.
    pub ms: f64,
    /// HDR-FLIP against the reference.
    pub flip: f64,
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
    /// The configurations' seed (`Options::seed`; 0 in sweeps cached before it was an option,
    /// which used 0).
    #[serde(default)]
    pub seed: u32,
    pub reference: ReferenceInfo,
    pub points: Vec<Point>,
    /// The path tracer at 1, 2, 4, ... spp, on the same device, size and reference (empty in
    /// sweeps cached before it was measured).
    #[serde(default)]
    pub path_tracer: Vec<PathTracerPoint>,
    /// Names of the configurations on the Pareto front, fastest first.
    pub pareto_front: Vec<String>,
    /// Wall-clock seconds of the whole sweep, reference included.
    pub seconds: f64,
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
    let brdf = format!("{:?}", crate::world::brdf::BrdfModel::default()).to_lowercase();
    let stem = format!("{scene_hash}-{camera}-{w}x{h}-{}spp-{}b-{brdf}", opts.reference_spp, opts.reference_bounces);
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
    if opts.reference_spp < 2 || !opts.reference_spp.is_multiple_of(2) {
        bail!("--reference-spp {}: must be even and at least 2 (the reference is two halves)", opts.reference_spp);
    }
    let half = opts.reference_spp / 2;
    let bar = crate::progress::progress_bar(opts.reference_spp as u64, "reference spp");
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

/// The path tracer's curve: one progressive run of `opts.path_tracer_spp` samples, its error
/// measured at each power of two against `reference`, and on past them to the power of two
/// whose time covers `cover_ms` (the slowest configuration's frames, so that each has the path
/// tracer's error at equal time on the curve; at most MAX_PATH_TRACER_SPP).
#[allow(clippy::too_many_arguments)]
fn path_tracer_curve(
    ctx: &std::sync::Arc<Context>,
    shaders: &ShaderLibrary,
    scene: &Scene,
    backend: Backend,
    opts: &Options,
    reference: &CpuImage,
    cover_ms: f64,
) -> Result<Vec<PathTracerPoint>> {
    if opts.path_tracer_spp == 0 {
        return Ok(Vec::new());
    }
    let settings = Settings {
        width: opts.width,
        height: opts.height,
        mode: RenderMode::Reference { seed: PATH_TRACER_SEED, max_bounces: opts.reference_bounces },
        environment: opts.environment.clone(),
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, shaders, scene.clone(), settings, &opts.camera, backend)?;
    let bar = crate::progress::progress_bar(opts.path_tracer_spp as u64, "path tracer spp");
    let (mut sample_ms, mut measured) = (Vec::new(), Vec::new());
    let mut last = opts.path_tracer_spp;
    let mut spp = 0;
    while spp < last {
        spp += 1;
        r.render_frame()?;
        bar.inc(1);
        if spp > 1 {
            sample_ms.push(r.last_frame_wall_ms);
        }
        if spp.is_power_of_two() || spp == last {
            let img = r.read_output(pathtrace::COLOR)?;
            let flip = metrics::hdr_flip(reference, &img, &HdrFlipOptions::default())
                .with_context(|| format!("path tracer at {spp} spp: FLIP"))?;
            measured.push((spp, flip.mean));
        }
        if spp == last && !sample_ms.is_empty() {
            // Short of the slowest configuration's time: on to the next power of two.
            let covered = spp as f64 * median(&sample_ms);
            if covered < cover_ms && spp < MAX_PATH_TRACER_SPP {
                last = (spp + 1).next_power_of_two().min(MAX_PATH_TRACER_SPP);
                bar.set_length(last as u64);
            }
        }
    }
    bar.finish_and_clear();
    // With one sample there is no warm frame to time: the first one stands in.
    let per_sample = if sample_ms.is_empty() { r.last_frame_wall_ms } else { median(&sample_ms) };
    Ok(measured.into_iter().map(|(spp, flip)| PathTracerPoint { spp, ms: spp as f64 * per_sample, flip }).collect())
}

/// The most samples the path tracer's curve goes on to, covering a slow configuration.
const MAX_PATH_TRACER_SPP: u32 = 1024;

/// What one run of a configuration timed, and its last frame.
struct Run {
    totals: Vec<f64>,
    stamps: Vec<f64>,
    per_pass: Vec<(String, Vec<f64>)>,
    last_frame: CpuImage,
    /// With `cut`: the run's first frame (empty cache, no history).
    first_frame: Option<CpuImage>,
    /// With `cut`: the frame after a camera cut that follows the run.
    after_cut: Option<CpuImage>,
}

/// Renders `opts.frames` frames of one configuration, timing the last `timed_frames`; with
/// `cut`, keeps the first frame too, then makes a camera cut and renders one frame more
/// (untimed).
#[allow(clippy::too_many_arguments)]
fn run_config(
    ctx: &std::sync::Arc<Context>,
    shaders: &ShaderLibrary,
    scene: &Scene,
    backend: Backend,
    opts: &Options,
    config: Config,
    cut: bool,
    bar: &indicatif::ProgressBar,
) -> Result<Run> {
    let mut settings = Settings {
        width: opts.width,
        height: opts.height,
        frame_dt: 0.0,
        environment: opts.environment.clone(),
        seed: opts.seed,
        ..Default::default()
    };
    config.apply(&mut settings);
    let mut r = Renderer::new(ctx, shaders, scene.clone(), settings, &opts.camera, backend)?;
    let mut totals = Vec::new();
    let mut stamps = Vec::new();
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    let mut first_frame = None;
    for n in 0..opts.frames {
        r.render_frame()?;
        bar.inc(1);
        if n == 0 && cut {
            first_frame = Some(r.read_output(r.hdr_output())?);
        }
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
    let last_frame = r.read_output(r.hdr_output())?;
    let after_cut = if cut {
        r.camera_cut();
        r.render_frame()?;
        Some(r.read_output(r.hdr_output())?)
    } else {
        None
    };
    Ok(Run { totals, stamps, per_pass, last_frame, first_frame, after_cut })
}

/// Measures one configuration's error (and first round's times) from its first run.
fn measure(config: Config, run: Run, reference: &CpuImage, seconds: f64) -> Result<Point> {
    let Run { totals, stamps, per_pass, last_frame: img, first_frame, after_cut } = run;
    let name = config.to_string();
    let flip =
        metrics::hdr_flip(reference, &img, &HdrFlipOptions::default()).with_context(|| format!("{name}: FLIP"))?;
    let cut_flip = after_cut
        .map(|cut| metrics::hdr_flip(reference, &cut, &HdrFlipOptions::default()))
        .transpose()
        .with_context(|| format!("{name}: FLIP after the cut"))?;
    let first_flip = first_frame
        .map(|first| metrics::hdr_flip(reference, &first, &HdrFlipOptions::default()))
        .transpose()
        .with_context(|| format!("{name}: FLIP of the first frame"))?;
    let luminance_ratio = metrics::luminance_ratio(reference, &img)
        .with_context(|| format!("{name}: luminance against the reference"))?;
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
        cut_flip: cut_flip.map(|f| f.mean),
        first_flip: first_flip.map(|f| f.mean),
        luminance_ratio: Some(luminance_ratio),
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
    let camera = crate::render::camera::start_position(scene, &opts.camera)?;
    let lit = default_light::choose(&opts.environment, scene, camera).default_light;
    let hash = lit_scene_key(scene_hash(spec)?, lit);
    let (reference, reference_info) = reference(ctx, shaders, spec, scene, backend, opts, &hash)?;
    let rounds = opts.rounds.max(1);
    let bar = crate::progress::progress_bar(opts.configs.len() as u64 * opts.frames as u64 * rounds as u64, "frames");
    let mut points: Vec<Point> = Vec::new();
    for round in 0..rounds {
        for (i, &config) in opts.configs.iter().enumerate() {
            bar.set_message(format!("{config} (round {}/{rounds})", round + 1));
            let run_start = Instant::now();
            let run = run_config(ctx, shaders, scene, backend, opts, config, round == 0, &bar)?;
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
    let slowest = points.iter().map(|p| p.frame_ms * opts.frames as f64).fold(0.0, f64::max);
    let path_tracer = path_tracer_curve(ctx, shaders, scene, backend, opts, &reference, slowest)?;
    for p in &path_tracer {
        log::info!("path tracer {} spp: {:.2} ms, FLIP {:.4}", p.spp, p.ms, p.flip);
    }
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
        seed: opts.seed,
        reference: reference_info,
        pareto_front: front.iter().map(|&i| points[i].name.clone()).collect(),
        points,
        path_tracer,
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

/// A made-up sweep for the unit tests of what reads one (chart, report).
#[cfg(test)]
pub(crate) mod testing {
    use super::*;

    /// A sweep of `points` (name, frame ms, FLIP, on the front) with a path-tracer curve of
    /// 1 to 8 spp, its 1-spp FLIP 0.5.
    pub fn sweep(points: &[(&str, f64, f64, bool)]) -> SceneSweep {
        let made = ReferenceMade {
            scene: "s.gltf".into(),
            scene_hash: "0".into(),
            camera: "default".into(),
            width: 320,
            height: 180,
            spp: 512,
            max_bounces: 256,
            seeds: [1, 2],
            noise_flip: 0.021,
            render_seconds: 1.0,
            backend: "compute".into(),
            device: "test device".into(),
        };
        let points: Vec<Point> = points
            .iter()
            .map(|&(name, frame_ms, flip, pareto)| Point {
                name: name.into(),
                config: name.parse().unwrap(),
                frame_ms,
                frame_ms_samples: vec![frame_ms],
                timestamp_ms: frame_ms,
                passes: Vec::new(),
                flip,
                cut_flip: None,
                first_flip: None,
                luminance_ratio: None,
                psnr_db: Some(30.0),
                ssim: 0.9,
                pareto,
                seconds: 1.0,
            })
            .collect();
        SceneSweep {
            scene: "s.gltf".into(),
            scene_name: "test scene".into(),
            scene_hash: "0".into(),
            camera: "default".into(),
            width: 320,
            height: 180,
            backend: "compute".into(),
            device: "test device".into(),
            driver: "test driver".into(),
            frames: 48,
            timed_frames: 8,
            rounds: 1,
            seed: 0,
            reference: ReferenceInfo { path: "r.exr".into(), cached: false, seconds: 1.0, made },
            pareto_front: points.iter().filter(|p| p.pareto).map(|p| p.name.clone()).collect(),
            points,
            path_tracer: [(1, 9.0, 0.5), (2, 18.0, 0.36), (4, 36.0, 0.25), (8, 72.0, 0.18)]
                .iter()
                .map(|&(spp, ms, flip)| PathTracerPoint { spp, ms, flip })
                .collect(),
            seconds: 1.0,
        }
    }
}
