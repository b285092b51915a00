//! `hybrid-rt bench stability`: the stability suite's scenarios, denoised and raw, as a table
//! and JSON (src/bench/stability.rs).

use super::{GpuArgs, parse_size};
use crate::backend;
use crate::bench::{self, stability};
use crate::gpu::{Context, ContextOptions, ShaderLibrary, finish_validation};
use crate::image_io;
use crate::passes::gi::GiRate;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct StabilityArgs {
    #[command(flatten)]
    gpu: GpuArgs,
    /// Image size, WIDTHxHEIGHT (the bounds were measured at 48x48).
    #[arg(long, default_value = "48x48")]
    size: String,
    /// Run only the scenario of this name (as the table prints it, e.g. "light off").
    #[arg(long)]
    scenario: Option<String>,
    /// JSON output (default: out/bench/stability-<unix time>.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// gi's rate in the shipped frame, as `render --gi-rate` (the bounds were measured at the
    /// default).
    #[arg(long, value_enum, value_name = "RATE", default_value = "half")]
    gi_rate: GiRate,
}

pub fn run(a: &StabilityArgs) -> Result<()> {
    let (width, height) = parse_size(&a.size)?;
    let out = a.out.clone().unwrap_or_else(|| bench::default_output("stability"));
    image_io::check_overwrite(&out, a.force)?;
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let (picked, why) = backend::resolve(&ctx.caps, a.gpu.backend)?;
    log::info!("ray backend: {} ({why})", picked.variant());
    let shaders = ShaderLibrary::embedded();
    let rig = stability::Rig { ctx: &ctx, shaders: &shaders, backend: picked, width, height, gi_rate: a.gi_rate };
    if let Some(name) = &a.scenario
        && !stability::SCENARIOS.iter().any(|(n, _)| n == name)
    {
        let names: Vec<&str> = stability::SCENARIOS.iter().map(|(n, _)| *n).collect();
        anyhow::bail!("no scenario {name:?} in the stability suite; its scenarios: {}", names.join(", "));
    }
    let count = if a.scenario.is_some() { 1 } else { stability::SCENARIOS.len() };
    let bar = crate::progress::progress_bar(count as u64, "scenarios");
    let start = std::time::Instant::now();
    let rows = stability::run_all(&rig, a.scenario.as_deref(), &|name: &str| {
        bar.set_message(name.to_string());
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    outln!("device: {} ({}), {width}x{height}, backend {}", ctx.caps.device_name, ctx.caps.driver, picked.variant());
    if (width, height) != stability::BOUND_SIZE {
        let (bw, bh) = stability::BOUND_SIZE;
        outln!("note: the bounds were measured at {bw}x{bh}; at this size they are only a guide");
    }
    print!("{}", stability::table(&rows));
    let json = serde_json::json!({
        "device": ctx.caps.device_name,
        "driver": ctx.caps.driver,
        "backend": picked.variant(),
        "width": width,
        "height": height,
        "seconds": start.elapsed().as_secs_f64(),
        "rows": rows,
    });
    image_io::write_atomic(&out, |tmp| Ok(std::fs::write(tmp, serde_json::to_vec_pretty(&json)?)?))?;
    outln!("wrote {}", out.display());
    finish_validation(ctx)
}
