//! `hybrid-rt plan [SCENE]`: the passes the frame will run for a scene, and why (the frame
//! plan of src/render/plan.rs, which `render` uses unless `--full` is given).

use super::SceneArgs;
use crate::render::Settings;
use crate::render::plan::FramePlan;
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct PlanArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(a: &PlanArgs) -> Result<()> {
    let scene = a.scene.load()?;
    let plan = FramePlan::for_scene(&scene, Settings::default().reflections.roughness_cutoff);
    if a.json {
        println!("{}", serde_json::to_string_pretty(&plan)?);
        return Ok(());
    }
    println!(
        "frame plan for {} ({} triangles, {} instances, {} lights):",
        scene.name,
        scene.triangle_count(),
        scene.instances.len(),
        scene.lights.len()
    );
    let on = |b: bool| if b { "runs" } else { "skipped" };
    println!("  gbuffer                  runs");
    println!(
        "  shadows                  runs ({})",
        if plan.soft_shadows { "adaptive soft shadows" } else { "one hard ray per light" }
    );
    println!("  shadows_penumbra/tent/filter {}", on(plan.soft_shadows));
    println!("  gi                       {}", on(plan.gi));
    if plan.resampled_lights > 0 {
        println!("    + many-light resampling of {} lights (one shadow ray per pixel)", plan.resampled_lights);
    }
    println!("  reflections              {}", on(plan.reflections));
    println!("  svgf chains, composite, taa, tonemap, history  run");
    println!("why:");
    for r in &plan.reasons {
        println!("  - {r}");
    }
    println!("(`hybrid-rt render --full` runs every pass)");
    Ok(())
}
