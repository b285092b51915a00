//! `hybrid-rt bench soak`: renders many frames of an animated scene and watches for growth:
//! host memory (the process's resident set, VmRSS) and device memory (what gpu-allocator
//! holds), sampled every N frames after a warm-up, and the frame time. The soak test
//! (tests/soak.rs) runs it with the validation layer on and bounds the growth.
//!
//! On lavapipe device memory is host memory, so it shows in both series; gpu-allocator's
//! numbers tell the two apart.

use super::median;
use crate::gpu::MemoryUsage;
use crate::render::Renderer;
use anyhow::{Context as _, Result, bail};
use serde::Serialize;
use std::time::Instant;

#[derive(Clone, Debug, Serialize)]
pub struct Options {
    /// Frames rendered in all, warm-up included.
    pub frames: u32,
    /// Frames rendered before the baseline sample: first-use costs (shader JIT on lavapipe,
    /// the validation layer's caches, allocator blocks) land here.
    pub warmup: u32,
    /// Frames between samples after the baseline.
    pub every: u32,
}

impl Default for Options {
    fn default() -> Self {
        Self { frames: 10_000, warmup: 500, every: 500 }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    /// Frames rendered when the sample was taken.
    pub frame: u32,
    pub host_rss_bytes: u64,
    pub gpu: MemoryUsage,
    /// Wall-clock time of the frames since the previous sample (render, submit and wait).
    pub frame_ms_median: f64,
    pub frame_ms_max: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct SoakResult {
    pub options: Options,
    pub seconds: f64,
    /// The first sample is the baseline, taken after the warm-up.
    pub samples: Vec<Sample>,
    /// Largest resident set after the baseline minus the baseline's.
    pub host_growth_bytes: i64,
    /// Largest live device allocation after the baseline minus the baseline's.
    pub gpu_growth_bytes: i64,
    /// Largest device block capacity after the baseline minus the baseline's.
    pub gpu_capacity_growth_bytes: i64,
    /// Frame times after the warm-up.
    pub frame_ms_median: f64,
    pub frame_ms_p99: f64,
    pub frame_ms_max: f64,
}

/// The process's resident set in bytes (Linux: VmRSS of /proc/self/status).
pub fn resident_bytes() -> Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status").context("/proc/self/status")?;
    let kib = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().strip_suffix("kB"))
        .and_then(|v| v.trim().parse::<u64>().ok());
    match kib {
        Some(k) => Ok(k * 1024),
        None => bail!("/proc/self/status has no VmRSS line"),
    }
}

/// Renders `opts.frames` frames, sampling memory after the warm-up and every `opts.every`
/// frames (and after the last); `progress` hears the number of frames rendered after each.
pub fn run(r: &mut Renderer, opts: &Options, progress: &dyn Fn(u32)) -> Result<SoakResult> {
    if opts.warmup == 0 || opts.every == 0 || opts.warmup >= opts.frames {
        bail!("soak: need 0 < warm-up < frames and a sampling interval > 0 (got {opts:?})");
    }
    // Every frame time is kept, allocated and touched here, before the baseline, so that the
    // series itself cannot look like growth (8 bytes a frame).
    let mut times = vec![f64::NAN; opts.frames as usize];
    let mut samples: Vec<Sample> = Vec::with_capacity((opts.frames / opts.every) as usize + 2);
    let mut last_sample = 0usize;
    let start = Instant::now();
    for n in 1..=opts.frames {
        let t = Instant::now();
        r.render_frame()?;
        times[n as usize - 1] = t.elapsed().as_secs_f64() * 1e3;
        progress(n);
        let due = n == opts.warmup || n == opts.frames || (n > opts.warmup && (n - opts.warmup) % opts.every == 0);
        if due {
            let interval = &times[last_sample..n as usize];
            samples.push(Sample {
                frame: n,
                host_rss_bytes: resident_bytes()?,
                gpu: r.ctx.memory_usage()?,
                frame_ms_median: median(interval),
                frame_ms_max: interval.iter().copied().fold(0.0, f64::max),
            });
            last_sample = n as usize;
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let base = &samples[0];
    let growth = |f: &dyn Fn(&Sample) -> u64| samples.iter().map(|s| f(s) as i64 - f(base) as i64).max().unwrap_or(0);
    let after = &times[opts.warmup as usize..];
    let mut sorted = after.to_vec();
    sorted.sort_by(f64::total_cmp);
    let p99 = sorted[((sorted.len() - 1) as f64 * 0.99).round() as usize];
    Ok(SoakResult {
        host_growth_bytes: growth(&|s| s.host_rss_bytes),
        gpu_growth_bytes: growth(&|s| s.gpu.allocated_bytes),
        gpu_capacity_growth_bytes: growth(&|s| s.gpu.capacity_bytes),
        frame_ms_median: median(after),
        frame_ms_p99: p99,
        frame_ms_max: sorted.last().copied().unwrap_or(0.0),
        options: opts.clone(),
        seconds,
        samples,
    })
}

/// The terminal table: one row per sample, growth against the baseline.
pub fn table(r: &SoakResult) -> String {
    let mib = |b: f64| b / (1 << 20) as f64;
    let base = &r.samples[0];
    let mut s = format!(
        "{:>7} {:>10} {:>10} {:>11} {:>10} {:>7} {:>7} {:>10} {:>9}\n",
        "frame", "host MiB", "host +KiB", "GPU MiB", "GPU +B", "allocs", "blocks", "median ms", "max ms"
    );
    for x in &r.samples {
        s.push_str(&format!(
            "{:>7} {:>10.2} {:>10.0} {:>11.3} {:>10} {:>7} {:>7} {:>10.3} {:>9.3}\n",
            x.frame,
            mib(x.host_rss_bytes as f64),
            (x.host_rss_bytes as f64 - base.host_rss_bytes as f64) / 1024.0,
            mib(x.gpu.allocated_bytes as f64),
            x.gpu.allocated_bytes as i64 - base.gpu.allocated_bytes as i64,
            x.gpu.allocations,
            x.gpu.blocks,
            x.frame_ms_median,
            x.frame_ms_max
        ));
    }
    s.push_str(&format!(
        "after the warm-up ({} frames): host memory grew at most {:.1} KiB, device allocations {} bytes, \
         device blocks {} bytes; frame time median {:.3} ms, p99 {:.3} ms, max {:.3} ms; {:.1} s in all\n",
        r.options.warmup,
        r.host_growth_bytes as f64 / 1024.0,
        r.gpu_growth_bytes,
        r.gpu_capacity_growth_bytes,
        r.frame_ms_median,
        r.frame_ms_p99,
        r.frame_ms_max,
        r.seconds
    ));
    s
}
