//! The hybrid frame's plan: which passes run, in which order, wired by their typed outputs.
//!
//! gbuffer -> [primary_rays] -> shadows chain -> [light_grid_update] -> [radiance_cache] -> gi -> [gi_fill] -> reflections ->
//! [svgf chains: diffuse on gi, specular on reflections, filtered together; what glass lets
//! through on its own] ->
//! composite -> [taa] -> tonemap -> history.
//! `history` comes last: it keeps what the next frame's temporal passes reproject.

use super::Settings;
use super::plan::FramePlan;
use crate::graph::{Output, Pass, Resource};
use crate::passes::{self, PassBuilder, history, inject, radiance_cache, svgf};
use anyhow::Result;
use std::collections::HashMap;
use std::sync::Arc;

/// The name of the test signal's SVGF chain when `Settings::test_signal` is on.
pub const TEST_SIGNAL: &str = "signal";
/// The test signal the CPU injects (see `Renderer::inject`).
pub const TEST_INPUT: Output = Output::new(inject::NAME, TEST_SIGNAL);

pub struct HybridFrame {
    pub passes: Vec<Box<dyn Pass>>,
    /// Images the CPU provides, for tests.
    pub injected: HashMap<Output, inject::Texels>,
    /// The linear HDR result.
    pub hdr_output: Output,
    /// The radiance cache, when a pass traces rays that end in it.
    pub radiance_cache: Option<Arc<radiance_cache::Cache>>,
}

/// Whether `hybrid` builds the same passes, with the same parameters, for plans `a` and `b`:
/// what it reads of a plan, below, compared. The shadows chain ranked again at another view
/// keeps the frame where only which punctual lights hold the channels changed
/// (`Renderer::rank_chain_for`). Keep it beside `hybrid`: a plan field `hybrid` starts to read
/// belongs here too.
pub fn same_passes(a: &FramePlan, b: &FramePlan) -> bool {
    let read = |p: &FramePlan| {
        (
            (p.soft_shadows, p.tinted_shadows, p.gi, p.reflections, p.let_through, p.reservoirs(), p.emitters > 0),
            (p.chain_punctual, p.chain_emitters.clone(), p.scene_diagonal.to_bits()),
        )
    };
    read(a) == read(b)
}

pub fn hybrid(b: &PassBuilder, settings: &Settings, plan: &FramePlan) -> Result<HybridFrame> {
    let mut passes: Vec<Box<dyn Pass>> = vec![Box::new(passes::gbuffer::new(b)?)];
    let mut kept = history::gbuffer();
    let mut injected = HashMap::new();
    if settings.primary_rays {
        passes.push(Box::new(passes::primary_rays::new(b)?));
    }
    let extent = crate::gpu::vk::Extent2D { width: settings.width, height: settings.height };
    let mesh_lights = passes::shadows::MeshLights::new(plan.chain_punctual, &plan.chain_emitters);
    let shadows =
        passes::shadows::chain(b, &settings.shadows, extent, plan.soft_shadows, plan.tinted_shadows, mesh_lights)?;
    passes.extend(shadows.passes);
    kept.extend(shadows.kept);
    // gi's shadow rays toward the resampled lights and the emitters teach the light grid what
    // its cells see; the update comes before any pass draws from the grid.
    if plan.gi && plan.reservoirs() && settings.light_grid {
        passes.push(Box::new(passes::light_grid_update::new(b)?));
    }
    // The cache answers where gi's and the reflections' rays end; with it off they trace on.
    let cache = Arc::new(radiance_cache::Cache::new(b.ctx, &settings.radiance_cache, plan.scene_diagonal)?);
    let cache_used = settings.radiance_cache.enabled && (plan.gi || plan.reflections);
    if cache_used {
        passes.push(Box::new(radiance_cache::new(b, &cache, settings.seed)?));
    }
    log::info!("{}", radiance_cache::describe(&settings.radiance_cache, cache_used, plan.scene_diagonal));
    // gi makes the diffuse signal and the rough surfaces' specular one; when the plan drops it
    // (smooth metals only), both are zero.
    let (gi_diffuse, gi_specular) = if plan.gi {
        let gi = passes::gi::new(
            b,
            &settings.gi,
            settings.seed,
            settings.reflections.roughness_cutoff,
            &cache,
            plan.reservoirs(),
            plan.emitters > 0,
        )?;
        passes.extend(gi.passes);
        kept.push(passes::gi::kept(plan.reservoirs()));
        (gi.radiance.into(), gi.specular.into())
    } else {
        let zero = crate::graph::zero(crate::gpu::vk::Format::R32G32B32A32_SFLOAT, false);
        (zero, zero)
    };
    // Without glossy surfaces, no reflection rays: gi's estimate of the rough lobes is the
    // specular signal.
    let mut specular: Resource = if plan.reflections {
        passes.push(Box::new(passes::reflections::new(
            b,
            &settings.reflections,
            settings.seed,
            gi_specular,
            &cache,
            settings.gi.bounces,
            plan.let_through,
        )?));
        passes::reflections::RADIANCE.into()
    } else {
        gi_specular
    };
    let mut diffuse = gi_diffuse;
    let mut let_through = plan.let_through.then_some(passes::reflections::LET_THROUGH.into());
    // Where the radiance cache or a pixel's resampled light let go of light that is gone, so do
    // the denoiser's and TAA's histories.
    let restarts = history::Restarts {
        cache_changed: cache_used.then_some(radiance_cache::CHANGED.into()),
        light_lost: (plan.gi && plan.reservoirs()).then_some(passes::gi::LIGHT_LOST.into()),
    };
    if settings.denoiser {
        // The specular signal of reflection rays follows what they hit when the camera moves.
        let hit_distance = plan.reflections.then_some(passes::reflections::HIT_DISTANCE.into());
        let chain = svgf::pair(b, diffuse, specular, hit_distance, restarts, &settings.denoise)?;
        passes.extend(chain.passes);
        kept.extend(chain.kept);
        (diffuse, specular) = (chain.outputs[0].into(), chain.outputs[1].into());
        if plan.let_through {
            let chain = svgf::let_through(b, &settings.denoise)?;
            passes.extend(chain.passes);
            kept.extend(chain.kept);
            let_through = Some(chain.outputs[0].into());
        }
    }
    if settings.test_signal {
        let (pass, texels) = inject::new(b.ctx, TEST_INPUT, extent)?;
        passes.push(Box::new(pass));
        let chain = svgf::single(b, TEST_SIGNAL, TEST_INPUT.into(), &settings.denoise)?;
        passes.extend(chain.passes);
        kept.extend(chain.kept);
        injected.insert(TEST_INPUT, texels);
    }
    passes.push(Box::new(passes::composite::new(
        b,
        shadows.visibility.into(),
        plan.tinted_shadows,
        mesh_lights,
        settings.reflections.roughness_cutoff,
        passes::composite::Signals { diffuse, specular, let_through },
    )?));
    let mut hdr_output = passes::composite::COLOR;
    if settings.taa {
        passes.push(Box::new(passes::taa::new(b, hdr_output.into(), plan.reflections, plan.let_through, restarts)?));
        kept.extend(passes::taa::kept());
        hdr_output = passes::taa::COLOR;
    }
    passes.push(Box::new(passes::tonemap::new(b, hdr_output.into())?));
    passes.push(Box::new(history::new(kept)));
    Ok(HybridFrame { passes, injected, hdr_output, radiance_cache: cache_used.then_some(cache) })
}
