//! `hybrid-rt bench frame`: where a frame's GPU time goes, per pass, at chosen sizes, with the
//! denoiser's share (every svgf_* stage) called out.

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
    /// Median GPU time over the measured frames.
    pub ms: f64,
    /// Of the frame's total.
    pub share: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameCost {
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub total_ms: f64,
    pub passes: Vec<PassCost>,
    /// All svgf_* passes together.
    pub svgf_ms: f64,
    pub svgf_share: f64,
    /// Median wall-clock frame time, recording to fence (see `Renderer::last_frame_wall_ms`).
    pub wall_ms: f64,
}

/// Renders `warmup + frames` frames of `scene` (the default frame: TAA and denoiser on; the
/// frame plan unless `full`) and takes the median GPU time of every pass over the last `frames`.
pub fn measure(
    ctx: &Arc<Context>,
    shaders: &ShaderLibrary,
    scene: Scene,
    backend: Backend,
    (width, height): (u32, u32),
    full: bool,
    (warmup, frames): (u32, u32),
) -> Result<FrameCost> {
    let settings = Settings { width, height, taa: true, full, ..Default::default() };
    let mut r = Renderer::new(ctx, shaders, scene, settings, &CameraChoice::Default, backend)?;
    for _ in 0..warmup {
        r.render_frame()?;
    }
    let mut samples: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut order = Vec::new();
    let mut wall = Vec::new();
    for _ in 0..frames.max(1) {
        r.render_frame()?;
        wall.push(r.last_frame_wall_ms);
        for t in &r.last_pass_times {
            if !samples.contains_key(&t.pass) {
                order.push(t.pass.clone());
            }
            samples.entry(t.pass.clone()).or_default().push(t.gpu_ms);
        }
    }
    let medians: Vec<(String, f64)> = order.iter().map(|p| (p.clone(), median(&samples[p]))).collect();
    let total_ms: f64 = medians.iter().map(|(_, ms)| ms).sum();
    let share = |ms: f64| if total_ms > 0.0 { ms / total_ms } else { 0.0 };
    let svgf_ms: f64 = medians.iter().filter(|(p, _)| p.starts_with("svgf_")).map(|(_, ms)| ms).sum();
    Ok(FrameCost {
        width,
        height,
        frames: frames.max(1),
        total_ms,
        passes: medians.into_iter().map(|(pass, ms)| PassCost { pass, ms, share: share(ms) }).collect(),
        svgf_ms,
        svgf_share: share(svgf_ms),
        wall_ms: median(&wall),
    })
}

/// The terminal table: one column per size.
pub fn table(costs: &[FrameCost]) -> String {
    let mut s = format!("{:<28}", "pass");
    for c in costs {
        s.push_str(&format!(" {:>22}", format!("{}x{} ms (share)", c.width, c.height)));
    }
    s.push('\n');
    let passes: Vec<&str> = costs.first().map(|c| c.passes.iter().map(|p| p.pass.as_str()).collect()).unwrap_or_default();
    for p in passes {
        s.push_str(&format!("{p:<28}"));
        for c in costs {
            let cell = c.passes.iter().find(|x| x.pass == p).map(|x| format!("{:.2} ({:.1}%)", x.ms, 100.0 * x.share));
            s.push_str(&format!(" {:>22}", cell.unwrap_or_default()));
        }
        s.push('\n');
    }
    s.push_str(&format!("{:<28}", "svgf_* (denoiser) total"));
    for c in costs {
        s.push_str(&format!(" {:>22}", format!("{:.2} ({:.1}%)", c.svgf_ms, 100.0 * c.svgf_share)));
    }
    s.push('\n');
    s.push_str(&format!("{:<28}", "timestamps total"));
    for c in costs {
        s.push_str(&format!(" {:>22}", format!("{:.2}", c.total_ms)));
    }
    s.push('\n');
    s.push_str(&format!("{:<28}", "frame wall clock"));
    for c in costs {
        s.push_str(&format!(" {:>22}", format!("{:.2}", c.wall_ms)));
    }
    s.push('\n');
    s
}
