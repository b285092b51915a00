//! `hybrid-rt plan [SCENE]`: the passes the frame will run for a scene, and why (the frame
//! plan of src/render/plan.rs, which `render` uses unless `--full` is given), and what lights
//! it from outside (the default light or not, src/render/default_light.rs).

use super::{EnvironmentArgs, SceneArgs};
use crate::render::plan::FramePlan;
use crate::render::{CameraChoice, Settings, camera, default_light};
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct PlanArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    environment: EnvironmentArgs,
    /// Scene camera by name or index (default: the first camera, or a framing camera): the
    /// default light is not given to a camera in a closed room, and the shadows chain goes to
    /// the lights that bring the most to its view.
    #[arg(long)]
    camera: Option<CameraChoice>,
}

pub fn run(a: &PlanArgs) -> Result<()> {
    let scene = a.scene.load()?;
    let defaults = Settings::default();
    let choice = a.camera.clone().unwrap_or_default();
    let views = camera::shot_views(&scene, &choice, defaults.width, defaults.height)?;
    let plan = FramePlan::for_scene(
        &scene,
        defaults.reflections.roughness_cutoff,
        defaults.light_grid,
        defaults.mesh_lights,
        &views,
    );
    let start = camera::start_position(&scene, &choice)?;
    let lighting = default_light::choose(&a.environment.environment(), &scene, start);
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            plan: &'a FramePlan,
            lighting: &'a default_light::Lighting,
        }
        outln!("{}", serde_json::to_string_pretty(&Out { plan: &plan, lighting: &lighting })?);
        return Ok(());
    }
    outln!(
        "frame plan for {} ({} triangles, {} instances, {} lights):",
        scene.name,
        scene.triangle_count(),
        scene.instances.len(),
        scene.lights.len()
    );
    let on = |b: bool| if b { "runs" } else { "skipped" };
    outln!("  gbuffer                  runs");
    outln!(
        "  shadows                  runs ({})",
        if plan.soft_shadows { "adaptive soft shadows" } else { "one hard ray per light" }
    );
    outln!("  shadows_penumbra/tent/filter {}", on(plan.soft_shadows));
    let cache = Settings::default().radiance_cache;
    let cache_used = plan.gi || plan.reflections;
    outln!("  radiance_cache           {}", on(cache_used));
    outln!("  gi                       {}", on(plan.gi));
    outln!("  reflections              {}", on(plan.reflections));
    outln!("  svgf chains, composite, taa, tonemap, history  run");
    outln!("why:");
    for r in &plan.reasons {
        outln!("  - {r}");
    }
    outln!("  - lighting: {}", lighting.note);
    outln!("  - {}", crate::passes::radiance_cache::describe(&cache, cache_used, plan.scene_diagonal));
    outln!("(`hybrid-rt render --full` runs every pass)");
    Ok(())
}
