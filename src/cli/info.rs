//! `hybrid-rt info`: the device, what it can do, and the ray backend `auto` picks and why.

use super::GpuArgs;
use crate::backend;
use crate::gpu::{Context, ContextOptions, finish_validation};
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    gpu: GpuArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(a: &InfoArgs) -> Result<()> {
    let ctx = Context::new(&ContextOptions { validate: a.gpu.validate, ..Default::default() })?;
    let caps = &ctx.caps;
    let (picked, why) = backend::resolve(caps, a.gpu.backend)?;
    if a.json {
        let v = serde_json::json!({ "device": caps, "backend": picked, "reason": why });
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let yes = |b: bool| if b { "yes" } else { "no" };
        outln!("device:                   {} ({})", caps.device_name, caps.device_type);
        outln!("driver:                   {}", caps.driver);
        outln!("Vulkan:                   {}", caps.api_version);
        outln!("acceleration structures:  {}", yes(caps.acceleration_structure));
        outln!("ray query:                {}", yes(caps.ray_query));
        outln!("buffer device address:    {}", yes(caps.buffer_device_address));
        outln!("deferred host operations: {}", yes(caps.deferred_host_operations));
        outln!("timestamps:               {}", if caps.timestamp_period_ns > 0.0 { "yes" } else { "no" });
        outln!("ray backend:              {} ({why})", picked.variant());
    }
    finish_validation(ctx)
}
