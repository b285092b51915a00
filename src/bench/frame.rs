//! `hybrid-rt bench frame`: where a frame's time goes, per pass, at chosen sizes, with the
//! denoiser's share (every svgf_* stage) called out.
//!
//! Each pass is timed twice: by timestamp queries around it in the normal one-submission frame,
//! and by wall clock around its own submission in a profiled frame (`Renderer::profile_passes`).
//! Shares come from the wall clock: inside a frame, lavapipe's timestamps miss most compute
//! passes (0.02-0.04 ms for passes whose own submission takes 15-240 ms at 640x360), while on
//! a CPU device a pass's submission-to-fence time is its cost. The profiled passes' sum came
//! within 1% of the unprofiled frame's wall clock (1162.7 against 1155.4 ms at 640x360), so
//! splitting the frame costs little. On a GPU the two columns should agree.

use super::median;
use crate::backend::Backend;
use crate::gpu::{Context, ShaderLibrary};
use crate::render::{CameraChoice, Renderer, Settings};
use crate::scene::Scene;
use anyhow::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct PassCost {
    pub pass: String,
    /// Median wall-clock time of the pass's own submission over the profiled frames.
    pub ms: f64,
    /// Of the profiled passes' total.
    pub share: f64,
    /// Median timestamp-query time over the unprofiled frames.
    pub gpu_ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameCost {
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    /// Frames rendered before measuring (at least `--warmup`, and on for WARMUP_MIN_SECONDS).
    pub warmup_frames: u32,
    /// Sum of the passes' profiled wall-clock times.
    pub total_ms: f64,
    /// Sum of the passes' timestamp times.
    pub timestamps_ms: f64,
    pub passes: Vec<PassCost>,
    /// All svgf_* passes together.
    pub svgf_ms: f64,
    pub svgf_share: f64,
    /// Median wall-clock time of an unprofiled frame, recording to fence (see
    /// `Renderer::last_frame_wall_ms`).
    pub wall_ms: f64,
}

/// A warm-up lasts at least this long, whatever the number of frames asked for: a GPU raises its
/// clocks over the first frames. On an NVIDIA H200 the first `bench frame` of a process
/// summed 640x360's passes to 12.9 ms after 4 warm-up frames, and the next one, on the warmed
/// GPU, to 3.3 ms; on lavapipe 4 frames take longer than this anyway.
const WARMUP_MIN_SECONDS: f64 = 1.0;

/// Renders at least `warmup` frames of `scene` with `settings` (`bench frame`: the default
/// frame, TAA and denoiser on, the frame plan unless `--full`), and on for at least
/// WARMUP_MIN_SECONDS, then `frames` more of each kind, unprofiled and profiled, and takes the
/// medians.
pub fn measure(
    ctx: &Arc<Context>,
    shaders: &ShaderLibrary,
    scene: Scene,
    backend: Backend,
    settings: Settings,
    (warmup, frames): (u32, u32),
) -> Result<FrameCost> {
    let (width, height) = (settings.width, settings.height);
    let mut r = Renderer::new(ctx, shaders, scene, settings, &CameraChoice::Default, backend)?;
    let start = std::time::Instant::now();
    let mut warmup_frames = 0;
    while warmup_frames < warmup || start.elapsed().as_secs_f64() < WARMUP_MIN_SECONDS {
        r.render_frame()?;
        warmup_frames += 1;
    }
    let mut stamps: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut walls: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut order = Vec::new();
    let mut frame_wall = Vec::new();
    for profiled in [false, true] {
        r.profile_passes = profiled;
        for _ in 0..frames.max(1) {
            r.render_frame()?;
            if !profiled {
                frame_wall.push(r.last_frame_wall_ms);
            }
            for t in &r.last_pass_times {
                if !order.contains(&t.pass) {
                    order.push(t.pass.clone());
                }
                match t.wall_ms {
                    Some(ms) => walls.entry(t.pass.clone()).or_default().push(ms),
                    None => stamps.entry(t.pass.clone()).or_default().push(t.gpu_ms),
                }
            }
        }
    }
    let of = |m: &BTreeMap<String, Vec<f64>>, p: &str| m.get(p).map(|v| median(v)).unwrap_or(0.0);
    let passes: Vec<(String, f64, f64)> = order.iter().map(|p| (p.clone(), of(&walls, p), of(&stamps, p))).collect();
    let total_ms: f64 = passes.iter().map(|(_, ms, _)| ms).sum();
    let share = |ms: f64| if total_ms > 0.0 { ms / total_ms } else { 0.0 };
    let svgf_ms: f64 = passes.iter().filter(|(p, _, _)| p.starts_with("svgf_")).map(|(_, ms, _)| ms).sum();
    Ok(FrameCost {
        width,
        height,
        frames: frames.max(1),
        warmup_frames,
        total_ms,
        timestamps_ms: passes.iter().map(|(_, _, gpu)| gpu).sum(),
        passes: passes.into_iter().map(|(pass, ms, gpu_ms)| PassCost { pass, ms, share: share(ms), gpu_ms }).collect(),
        svgf_ms,
        svgf_share: share(svgf_ms),
        wall_ms: median(&frame_wall),
    })
}

/// The terminal table: per size, each pass's wall-clock ms (share) and timestamp ms.
pub fn table(costs: &[FrameCost]) -> String {
    // The widest pass name (`svgf_atrous_diffuse_specular_0`) and a space.
    const NAME: usize = 32;
    let mut s = format!("{:<NAME$}", "pass");
    for c in costs {
        s.push_str(&format!(" {:>22} {:>10}", format!("{}x{} ms (share)", c.width, c.height), "timestamp"));
    }
    s.push('\n');
    let passes: Vec<&str> =
        costs.first().map(|c| c.passes.iter().map(|p| p.pass.as_str()).collect()).unwrap_or_default();
    for p in passes {
        s.push_str(&format!("{p:<NAME$}"));
        for c in costs {
            let cost = c.passes.iter().find(|x| x.pass == p);
            let cell = cost.map(|x| format!("{:.2} ({:.1}%)", x.ms, 100.0 * x.share)).unwrap_or_default();
            let stamp = cost.map(|x| format!("{:.2}", x.gpu_ms)).unwrap_or_default();
            s.push_str(&format!(" {cell:>22} {stamp:>10}"));
        }
        s.push('\n');
    }
    s.push_str(&format!("{:<NAME$}", "svgf_* (denoiser) total"));
    for c in costs {
        s.push_str(&format!(" {:>22} {:>10}", format!("{:.2} ({:.1}%)", c.svgf_ms, 100.0 * c.svgf_share), ""));
    }
    s.push('\n');
    s.push_str(&format!("{:<NAME$}", "passes total"));
    for c in costs {
        s.push_str(&format!(" {:>22} {:>10}", format!("{:.2}", c.total_ms), format!("{:.2}", c.timestamps_ms)));
    }
    s.push('\n');
    s.push_str(&format!("{:<NAME$}", "frame (one submission)"));
    for c in costs {
        s.push_str(&format!(" {:>22} {:>10}", format!("{:.2}", c.wall_ms), ""));
    }
    s.push('\n');
    s.push_str(&format!("{:<NAME$}", "after warm-up frames"));
    for c in costs {
        s.push_str(&format!(" {:>22} {:>10}", c.warmup_frames, ""));
    }
    s.push('\n');
    s
}
