//! `hybrid-rt bench rays`: build time, memory and rays per second of both ray backends on the
//! same rays, in one run.
//!
//! # The ray sets (a written definition, so other tracers can do exactly the same work)
//!
//! Take the scene's triangles in world space (animation time 0). Let C be the centre and diag
//! the diagonal length of their bounding box.
//! - **Primary**: camera at C + 1.5 diag normalize(1, 0.7, 1.2) looking at C, world up
//!   (0, 1, 0), 60 degree vertical field of view, 1024x1024 rays through pixel centres (row 0
//!   at the top), closest hit, tmin 0, tmax f32::MAX.
//! - **Shadow**: one ray per primary hit toward a point light at camera + (0, 0.5 diag, 0),
//!   tmin = 1e-4 diag, tmax = distance - 1e-4 diag, unit direction, any hit. The primary hits
//!   are the compute backend's (the backends agree hit for hit; tests/backends.rs).
//! - **Incoherent**: 1,048,576 rays, origins uniform in the bounding box, directions uniform on
//!   the sphere: splitmix64 seeded with 2, per ray five draws ox, oy, oz, u, v, each
//!   (next >> 40) * 2^-24; origin = min + (ox, oy, oz) * extent; z = 1 - 2u, r = sqrt(1 - z^2),
//!   phi = 2 pi v, dir = (r cos phi, r sin phi, z); closest hit, tmin 0, tmax f32::MAX.
//!
//! The generators are in src/accel/bvh/rays.rs. Hit counts are printed beside the rates so
//! two tracers can be checked to have done the same work. Trace times are wall clock from
//! recording to fence (median of the repeats), the one clock every bench here uses: lavapipe's
//! timestamp queries miss most compute passes inside a frame (see bench/frame.rs), though they
//! time this lone dispatch right (within 0.5 ms of the wall clock). The timestamps are kept in
//! the JSON (`gpu_ms`) for GPUs, where they exclude the submission's overhead.
//! Build times are wall clock.

use super::median;
use crate::accel::AccelStats;
use crate::accel::bvh::rays::{BenchView, Ray};
use crate::backend::Backend;
use crate::gpu::{Context, ShaderLibrary};
use crate::render::ray_batch::TraceTime;
use crate::render::{CameraChoice, Renderer, Settings};
use crate::scene::{Pose, Scene};
use anyhow::{Result, bail};
use glam::Vec3;
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct Options {
    pub width: u32,
    pub height: u32,
    pub incoherent: usize,
    pub repeats: u32,
}

impl Default for Options {
    fn default() -> Self {
        Self { width: 1024, height: 1024, incoherent: 1 << 20, repeats: 3 }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct SetResult {
    pub rays: usize,
    pub hits: usize,
    /// Median wall-clock time of one trace of the whole set, recording to fence.
    pub ms: f64,
    /// Median timestamp time around the dispatch, where the device reports one.
    pub gpu_ms: Option<f64>,
    /// Rays over `ms`.
    pub mrays_per_s: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct BackendResult {
    pub backend: Backend,
    pub accel: AccelStats,
    pub primary: SetResult,
    pub shadow: SetResult,
    pub incoherent: SetResult,
}

#[derive(Clone, Debug, Serialize)]
pub struct SceneResult {
    pub scene: String,
    pub triangles: usize,
    pub instances: usize,
    pub backends: Vec<BackendResult>,
}

/// World-space bounds of the scene's triangles at a pose.
fn triangle_bounds(scene: &Scene, pose: &Pose) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for inst in &scene.instances {
        let m = pose.world[inst.node as usize];
        let mesh = &scene.meshes[inst.mesh as usize];
        for &i in &mesh.indices {
            let p = m.transform_point3(Vec3::from(mesh.vertices[i as usize].position));
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    (lo, hi)
}

fn set_result(rays: &[Ray], hits: usize, times: &[TraceTime]) -> SetResult {
    let ms = median(&times.iter().map(|t| t.wall_ms).collect::<Vec<_>>());
    let stamps: Vec<f64> = times.iter().filter_map(|t| t.gpu_ms).collect();
    let gpu_ms = (!stamps.is_empty()).then(|| median(&stamps));
    SetResult { rays: rays.len(), hits, ms, gpu_ms, mrays_per_s: rays.len() as f64 / (ms * 1e-3) / 1e6 }
}

/// Runs every ray set on every backend for one scene.
pub fn bench_scene(
    ctx: &Arc<Context>,
    shaders: &ShaderLibrary,
    scene: Scene,
    backends: &[Backend],
    opts: &Options,
    progress: &dyn Fn(&str),
) -> Result<SceneResult> {
    if !backends.contains(&Backend::Compute) {
        bail!("the ray bench needs the compute backend (its primary hits define the shadow rays)");
    }
    let pose = scene.evaluate(0.0);
    let (lo, hi) = triangle_bounds(&scene, &pose);
    let view = BenchView::new(lo, hi);
    let primary = view.primary(opts.width, opts.height);
    let incoherent = view.incoherent(opts.incoherent);
    let mut result = SceneResult {
        scene: scene.name.clone(),
        triangles: scene.triangle_count(),
        instances: scene.instances.len(),
        backends: Vec::new(),
    };
    // Compute first: its primary hits define the shadow rays both backends trace.
    let mut order = vec![Backend::Compute];
    order.extend(backends.iter().copied().filter(|b| *b != Backend::Compute));
    let mut shadow: Option<Vec<Ray>> = None;
    for backend in order {
        progress(&format!("{}: building the {} backend", scene.name, backend.variant()));
        let settings = Settings { width: 8, height: 8, ..Default::default() };
        let mut r = Renderer::new(ctx, shaders, scene.clone(), settings, &CameraChoice::Default, backend)?;
        progress(&format!("{}: {} primary rays", scene.name, backend.variant()));
        let (hits, t_primary) = r.trace_rays(shaders, &primary, false, opts.repeats)?;
        let n_primary = hits.iter().filter(|h| h.is_hit()).count();
        let shadow_rays = shadow.get_or_insert_with(|| {
            let t: Vec<Option<f32>> = hits.iter().map(|h| h.is_hit().then_some(h.t)).collect();
            view.shadow(&primary, &t)
        });
        progress(&format!("{}: {} shadow rays", scene.name, backend.variant()));
        let (sh, t_shadow) = r.trace_rays(shaders, shadow_rays, true, opts.repeats)?;
        progress(&format!("{}: {} incoherent rays", scene.name, backend.variant()));
        let (inc, t_inc) = r.trace_rays(shaders, &incoherent, false, opts.repeats)?;
        result.backends.push(BackendResult {
            backend,
            accel: r.scene_gpu.accel.stats(),
            primary: set_result(&primary, n_primary, &t_primary),
            shadow: set_result(shadow_rays, sh.iter().filter(|h| h.is_hit()).count(), &t_shadow),
            incoherent: set_result(&incoherent, inc.iter().filter(|h| h.is_hit()).count(), &t_inc),
        });
    }
    Ok(result)
}

/// The terminal table.
pub fn table(results: &[SceneResult]) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<28} {:<9} {:>10} {:>9} {:>22} {:>22} {:>22}\n",
        "scene (triangles)",
        "backend",
        "build ms",
        "MiB",
        "primary Mray/s (hits)",
        "shadow Mray/s (hits)",
        "incoh. Mray/s (hits)"
    ));
    for r in results {
        for b in &r.backends {
            let set = |x: &SetResult| format!("{:.3} ({})", x.mrays_per_s, x.hits);
            s.push_str(&format!(
                "{:<28} {:<9} {:>10.1} {:>9.1} {:>22} {:>22} {:>22}\n",
                format!("{} ({})", short(&r.scene), r.triangles),
                b.backend.variant(),
                b.accel.blas_build_ms,
                (b.accel.blas_bytes + b.accel.tlas_bytes) as f64 / (1 << 20) as f64,
                set(&b.primary),
                set(&b.shadow),
                set(&b.incoherent)
            ));
        }
        if let (Some(c), Some(q)) = (
            r.backends.iter().find(|b| b.backend == Backend::Compute),
            r.backends.iter().find(|b| b.backend == Backend::RayQuery),
        ) {
            s.push_str(&format!(
                "{:<28} compute / ray query speed: primary {:.2}x, shadow {:.2}x, incoherent {:.2}x\n",
                "",
                c.primary.mrays_per_s / q.primary.mrays_per_s,
                c.shadow.mrays_per_s / q.shadow.mrays_per_s,
                c.incoherent.mrays_per_s / q.incoherent.mrays_per_s
            ));
        }
    }
    s
}

fn short(name: &str) -> String {
    let n = std::path::Path::new(name).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if n.len() > 20 { n[..20].to_string() } else { n }
}
