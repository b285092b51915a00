//! Every light is shadowed, however many there are (issue 14): `builtin:many-lights` has 304
//! punctual lights, 256 of them in a sealed room beside the camera's, behind a wall. The four
//! that bring the most direct light to the camera's view get per-light visibility from the
//! shadows chain (with only the sealed room's lights on, which bring it none, the four
//! brightest); the rest (those the plan does not cull) are resampled in gi (one light per pixel from candidates drawn from the light grid and
//! last frame's reservoir, with shadow rays). On both ray backends:
//! - no leak: with only the hidden room's lights on, nothing in the camera's room can receive
//!   light and the environment is black, so every pixel is exactly 0, in the raw first frame and
//!   after denoising; with every light on, the floor strip by the wall (which no camera-room
//!   light reaches) keeps the brightness it has without the hidden room (within 10%), where a
//!   leak would make it many times brighter (the test computes how much);
//! - energy: the raw frames, averaged, with the radiance cache off, match a two-event reference
//!   path tracer's mean luminance (the resampling is consistent); the denoised frame the user
//!   sees (defaults) is compared with the full reference under a looser bound, because SVGF's
//!   outlier clamp loses some light there (a known gap, measured in the README).
//!
//! `builtin:many-panels`, the same rooms lit by emissive panels, checks the same of the
//! emissive triangles, which the reservoirs hold too.

mod common;

use glam::{Quat, UVec3, Vec3};
use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::Context;
use hybrid_rt::graph::Output;
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes::{composite, gbuffer, gi, light_grid_update, taa};
use hybrid_rt::render::{RenderMode, Settings};
use hybrid_rt::scene::builtin_many_lights::{facts, many_lights, many_panels};
use hybrid_rt::scene::{LightKind, Scene};
use hybrid_rt::world::light_grid::{GROUP_COUNT, GROUPS_PER_SIDE};
use std::f32::consts::FRAC_PI_2;
use std::sync::Arc;

const SIZE: u32 = 64;
/// Raw frames averaged for the strip comparison, and the difference allowed there (measured:
/// 0.8%, then -2.9% once the light grid's candidates differed between the two renders, and
/// +3.6% since the shadows chain goes to the camera room's lights, 2026-12-06: the strip's light
/// is indirect only, from a few samples a pixel).
const STRIP_FRAMES: u32 = 24;
const STRIP_TOLERANCE: f64 = 0.1;

fn settings(denoiser: bool) -> Settings {
    Settings { width: SIZE, height: SIZE, frame_dt: 0.0, taa: true, denoiser, ..Default::default() }
}

fn backends(ctx: &Context) -> Vec<Backend> {
    let mut b = Vec::new();
    if ctx.caps.supports_ray_query() {
        b.push(Backend::RayQuery);
    }
    b.push(Backend::Compute);
    b
}

/// The scene with only the lights for which `keep(name)` holds.
fn with_lights(keep: impl Fn(&str) -> bool) -> Scene {
    let mut s = many_lights();
    s.lights.retain(|l| keep(&l.name));
    s
}

fn hidden(name: &str) -> bool {
    name.starts_with(facts::HIDDEN_PREFIX)
}

fn lum(img: &CpuImage, x: u32, y: u32) -> f64 {
    0.2126 * img.get(x, y, 0) as f64 + 0.7152 * img.get(x, y, 1) as f64 + 0.0722 * img.get(x, y, 2) as f64
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn mean_lum(img: &CpuImage) -> f64 {
    let mut sum = 0.0;
    for y in 0..img.height {
        for x in 0..img.width {
            sum += lum(img, x, y);
        }
    }
    sum / img.pixel_count() as f64
}

/// Renders `frames` frames and reads `outputs` of the last.
fn render(
    ctx: &Arc<Context>,
    scene: Scene,
    s: Settings,
    backend: Backend,
    frames: u32,
    outputs: &[Output],
) -> Vec<CpuImage> {
    let mut r = common::renderer(ctx, scene, s, backend);
    common::render_frames(&mut r, frames);
    r.read_outputs(outputs).unwrap()
}

/// The raw frame (no denoiser, no TAA) of `frames` frames, averaged: per-pixel luminance. What
/// the light sampling estimates, without the denoiser's clamps.
fn averaged_raw(ctx: &Arc<Context>, scene: Scene, s: Settings, backend: Backend, frames: u32) -> Vec<f64> {
    let s = Settings { denoiser: false, taa: false, ..s };
    let mut r = common::renderer(ctx, scene, s, backend);
    let mut sum = vec![0.0; (SIZE * SIZE) as usize];
    for _ in 0..frames {
        r.render_frame().unwrap();
        let img = r.read_output(composite::COLOR).unwrap();
        for (i, v) in sum.iter_mut().enumerate() {
            *v += lum(&img, i as u32 % SIZE, i as u32 / SIZE) / frames as f64;
        }
    }
    sum
}

/// Mean luminance over the strip's interior pixels (away from its silhouette), and their count.
fn strip_mean(lums: &[f64], ids: &CpuImage) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            if ids.get_u32(x, y, 0) == facts::STRIP_INSTANCE && common::interior(ids, x, y) {
                sum += lums[(y * SIZE + x) as usize];
                n += 1;
            }
        }
    }
    (sum / n.max(1) as f64, n)
}

/// Outgoing radiance (luminance) of the strip's centre if the hidden room's lights shone
/// through the wall: what a leak would add, per light sum I cos / d^2 times albedo / pi.
fn leak_if_unshadowed(scene: &Scene) -> f64 {
    let pose = scene.evaluate(0.0);
    let p = facts::STRIP_CENTRE;
    let albedo = {
        let m = &scene.materials
            [scene.meshes[scene.instances[facts::STRIP_INSTANCE as usize].mesh as usize].material as usize];
        let c = m.base_color_factor;
        0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
    };
    let mut e = 0.0f64;
    for l in scene.lights.iter().filter(|l| hidden(&l.name)) {
        let at = pose.world[l.node as usize].transform_point3(glam::Vec3::ZERO);
        let d = at - p;
        let i = 0.2126 * l.color.x + 0.7152 * l.color.y + 0.0722 * l.color.z;
        e += (l.intensity * i * d.y.max(0.0) / d.length().powi(3)) as f64;
    }
    e * albedo as f64 / std::f64::consts::PI
}

#[test]
fn no_light_leaks_through_the_wall() {
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        // Hidden lights only: the camera's room is exactly black, raw and denoised.
        for (denoiser, frames) in [(false, 1), (true, 8)] {
            let img = render(&ctx, with_lights(hidden), settings(denoiser), backend, frames, &[composite::COLOR]);
            let mut max = 0.0f64;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    max = max.max(lum(&img[0], x, y));
                }
            }
            eprintln!("{backend:?} hidden lights only, denoiser {denoiser}: brightest pixel {max:e}");
            assert!(max <= 1e-6, "{backend:?}: light leaked into the sealed room (denoiser {denoiser}): {max:e}");
        }
        // Every light against the camera room's lights alone, on the strip by the wall, in raw
        // frames averaged (its light is indirect only, which the denoiser's firefly clamp
        // trims where light samples are sparse; see the energy test).
        let ids = &render(&ctx, many_lights(), settings(false), backend, 1, &[gbuffer::IDS])[0];
        let all = averaged_raw(&ctx, many_lights(), settings(false), backend, STRIP_FRAMES);
        let own = averaged_raw(&ctx, with_lights(|n| !hidden(n)), settings(false), backend, STRIP_FRAMES);
        let ((with, n), (without, _)) = (strip_mean(&all, ids), strip_mean(&own, ids));
        let leak = leak_if_unshadowed(&many_lights());
        let allowed = STRIP_TOLERANCE * without;
        eprintln!(
            "{backend:?}: strip ({n} px, {STRIP_FRAMES} raw frames) {with:.4} with every light, {without:.4} \
             without the hidden room; a leak would add {leak:.3}"
        );
        assert!(n > 50, "too few strip pixels: {n}");
        assert!(leak > 10.0 * allowed, "the check could not see a leak: {leak} vs {allowed}");
        assert!(
            (with - without).abs() <= allowed,
            "{backend:?}: strip {with:.4} vs {without:.4} without hidden lights"
        );
    }
    common::assert_validation_clean(ctx);
}

fn reference(ctx: &Arc<Context>, backend: Backend, max_bounces: u32, seed: u32) -> f64 {
    reference_of(ctx, many_lights(), backend, max_bounces, seed, true)
}

/// The reference's mean luminance on `scene`, its resampled lights drawn from the light grid or
/// (`light_grid` false) by power from all of them.
fn reference_of(
    ctx: &Arc<Context>,
    scene: Scene,
    backend: Backend,
    max_bounces: u32,
    seed: u32,
    light_grid: bool,
) -> f64 {
    let s = Settings { mode: RenderMode::Reference { seed, max_bounces }, light_grid, ..settings(false) };
    let mut r = common::renderer(ctx, scene, s, backend);
    common::render_frames(&mut r, REFERENCE_SPP);
    let out = r.hdr_output();
    mean_lum(&r.read_output(out).unwrap())
}

/// The camera room's lights alone (so that drawn by power, without the grid, they are not too
/// sparse a choice for 256 spp).
fn camera_room() -> Scene {
    with_lights(|name| !hidden(name))
}

/// The camera room's lights made spots without a range, pointing down: the light grid then
/// culls them by their cones.
fn spots() -> Scene {
    let mut s = camera_room();
    let Scene { lights, nodes, .. } = &mut s;
    for l in lights.iter_mut() {
        l.kind = LightKind::Spot { inner_cone: 0.3, outer_cone: 0.5 };
        l.range = None;
        nodes[l.node as usize].rotation = Quat::from_rotation_x(-FRAC_PI_2);
    }
    s
}

/// The light grid leaves a light out of a cell only where it cannot reach (its range, a spot's
/// cone), so the reference with the grid and without it agree but for noise: on the camera
/// room's point lights (range culling) and on the same lights made spots (cone culling). Two
/// scattering events, 256 spp, the same seed. Measured: +0.51% (points) and -0.59% (spots);
/// over seeds 6-9 at most 1.3% either way. A grid that left out lights that reach a cell would
/// make the image with it darker than without: culling every spot measured -96%.
const GRID_TOLERANCE: f64 = 0.02;

#[test]
fn the_light_grid_leaves_out_no_light() {
    let ctx = common::validated_context();
    let backend = backends(&ctx)[0];
    for (name, scene) in [("points", camera_room as fn() -> Scene), ("spots", spots)] {
        let with = reference_of(&ctx, scene(), backend, TWO_EVENTS, 5, true);
        let without = reference_of(&ctx, scene(), backend, TWO_EVENTS, 5, false);
        let off = (with - without) / without;
        eprintln!("{name}: reference {with:.4} with the light grid, {without:.4} without ({:+.2}%)", 100.0 * off);
        assert!(without > 0.01, "{name}: the scene is dark ({without})");
        assert!(off.abs() < GRID_TOLERANCE, "{name}: {with} with the light grid, {without} without");
    }
    common::assert_validation_clean(ctx);
}

const REFERENCE_SPP: u32 = 256;
/// Allowed differences in mean luminance. The raw frames: the light sampling is consistent, and
/// 32 frames of one GI sample each are noisier than 256 spp (measured -0.67% on both backends
/// since the shadows chain goes to the camera room's lights, 2026-12-06; -2.5% with gi at half
/// rate, -3.1% at full rate before, when two of its channels went to the sealed room's sphere
/// lights; the two references differ by 0.2%). The denoised frame: it still loses some light
/// where GI's light samples are sparse (measured -1.32% on the ray-query backend, -1.30% on the
/// compute one, 2026-12-06, with that chain; -2.45% and -2.41% before, 2026-12-05, since a young
/// SVGF history's outlier clamp hands on what it takes too; -3.6% at half rate and -5.6% at
/// full rate before, 2026-12-04, since an established one's hands on exactly what it takes;
/// -7.2% before that; README, known gaps). The bound was 7% until then.
const RAW_TOLERANCE: f64 = 0.05;
const DENOISED_TOLERANCE: f64 = 0.05;
/// Two scattering events, what the hybrid frame models with the radiance cache off.
const TWO_EVENTS: u32 = 2;
/// The reference's default: paths end by Russian roulette.
const EVERY_BOUNCE: u32 = 64;

#[test]
fn mean_luminance_matches_the_reference() {
    const FRAMES: u32 = 32;
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        // The resampling's estimate: raw frames averaged, two events, against the reference
        // with two events (its own noise measured with a second seed).
        let mut two = settings(false);
        two.radiance_cache.enabled = false;
        let raw = mean(&averaged_raw(&ctx, many_lights(), two, backend, FRAMES));
        let (r2, r2b) = (reference(&ctx, backend, TWO_EVENTS, 5), reference(&ctx, backend, TWO_EVENTS, 6));
        // What the user sees: the default frame (cache on, denoised, TAA) against every bounce.
        let denoised = mean_lum(&render(&ctx, many_lights(), settings(true), backend, FRAMES, &[taa::COLOR])[0]);
        let all = reference(&ctx, backend, EVERY_BOUNCE, 5);
        let off = |x: f64, r: f64| (x - r) / r;
        eprintln!(
            "{backend:?}: mean luminance, raw frames averaged {raw:.4} vs two-event reference {r2:.4} ({:+.2}%; \
             reference noise {:+.2}%); denoised frame {FRAMES} {denoised:.4} vs full reference {all:.4} ({:+.2}%)",
            100.0 * off(raw, r2),
            100.0 * off(r2b, r2),
            100.0 * off(denoised, all)
        );
        assert!(off(raw, r2).abs() < RAW_TOLERANCE, "{backend:?}: raw frames' mean luminance {raw} vs {r2}");
        assert!(
            off(denoised, all).abs() < DENOISED_TOLERANCE,
            "{backend:?}: denoised mean luminance {denoised} vs {all}"
        );
    }
    common::assert_validation_clean(ctx);
}

/// Frames rendered before the light grid's estimates are read: gi at half rate (the default)
/// traces each pixel every other frame, so 32 frames send the rays 16 did at full rate.
/// Measured mean estimate of the hidden groups: 0.35 after 16 frames at full rate, 0.50 after
/// 16 and 0.36 after 32 at half rate (2026-12-04).
const LEARNING_FRAMES: u32 = 32;

/// What the light grid learns (`light_grid_update.visibility`, one row per cell, one column per
/// light group): after LEARNING_FRAMES frames, from the cells wholly on the camera's side of the
/// wall, the groups of lights wholly behind it that shadow rays tested have been found hidden, and
/// the camera room's own groups seen by every ray. Lights are grouped by position on a 4 x 4 x 4
/// grid over the bounds, so groups 0-1 along x lie in the camera's room and 2-3 behind the wall. A
/// group that no ray from a cell has tested keeps the estimate 1; the test needs the hidden ones
/// tested. Then the hidden room's lights dim, which rebuilds the grid over the same cells: what was
/// learned stays. On both backends.
#[test]
fn the_light_grid_learns_that_the_wall_hides_the_other_room() {
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        let mut r = common::renderer(&ctx, many_lights(), settings(true), backend);
        let hidden_mean = learns_the_wall(&mut r, &format!("{backend:?}, lights"));

        // The hidden room's lights dim: the grid is rebuilt over the same cells and keeps what
        // it learned (reset, one frame's rays would leave the estimates near 1).
        for l in r.scene.lights.iter_mut().filter(|l| hidden(&l.name)) {
            l.intensity *= 0.5;
        }
        common::render_frames(&mut r, 1);
        let (after, _) = learned(&mut r);
        let after_mean = mean(&after);
        eprintln!("{backend:?}: after the hidden lights dimmed, {} pairs, mean estimate {after_mean:.4}", after.len());
        assert!(after.len() > 100, "{backend:?}: only {} pairs were tested after the change", after.len());
        assert!(
            after_mean < hidden_mean + 0.05,
            "{backend:?}: the light change forgot what was learned: mean estimate {hidden_mean} before, {after_mean} \
             after"
        );
    }
    common::assert_validation_clean(ctx);
}

/// The same for the emissive panels of `builtin:many-panels` (no punctual light: the grid's
/// cells list nothing, and gi's shadow rays toward the panels teach them, by the region each
/// sampled point lies in): after LEARNING_FRAMES frames the hidden room's groups that rays
/// tested from the camera's side are found hidden, the camera room's seen. Both backends.
#[test]
fn the_light_grid_learns_which_panels_the_wall_hides() {
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        let mut r = common::renderer(&ctx, many_panels(), settings(true), backend);
        learns_the_wall(&mut r, &format!("{backend:?}, panels"));
    }
    common::assert_validation_clean(ctx);
}

/// Renders LEARNING_FRAMES frames and checks what the light grid learned (`learned`): more
/// than 100 (camera cell, hidden group) pairs tested, their mean estimate under 0.5 (it falls
/// as 4 / (4 + n) with n rays blocked, and at 64x64 a pair gets a few rays a frame; a ray that
/// got through would put it near 1), every camera-room group seen from the camera room's cells.
/// Returns that mean.
fn learns_the_wall(r: &mut hybrid_rt::render::Renderer, what: &str) -> f64 {
    common::render_frames(r, LEARNING_FRAMES);
    let (hidden, own_min) = learned(r);
    let hidden_mean = mean(&hidden);
    eprintln!(
        "{what}: {} (camera cell, hidden group) pairs tested, mean estimate {hidden_mean:.4}; least estimate of a \
         camera-room group {own_min:.4}",
        hidden.len(),
    );
    assert!(hidden.len() > 100, "{what}: only {} (cell, hidden group) pairs were tested", hidden.len());
    assert!(hidden_mean < 0.5, "{what}: the hidden room's groups are still taken as seen: {hidden_mean}");
    assert!(own_min > 0.99, "{what}: a camera-room group is taken as hidden from a camera-room cell: {own_min}");
    hidden_mean
}

/// What the light grid has learned, from the cells wholly on the camera's side of the wall:
/// the estimates of the hidden room's groups that have been tested (below 1), and the least
/// estimate of the camera room's groups.
fn learned(r: &mut hybrid_rt::render::Renderer) -> (Vec<f64>, f32) {
    let visibility = r.read_outputs(&[light_grid_update::VISIBILITY]).unwrap().remove(0);
    let h = r.scene_gpu.light_tables.grid_header();
    let lo = Vec3::from(h.lo);
    let cell = 1.0 / Vec3::from(h.inv_cell);
    let group = cell * UVec3::from(h.dims).as_vec3() / GROUPS_PER_SIDE as f32;
    let (mut hidden, mut own_min) = (Vec::new(), f32::INFINITY);
    for c in 0..h.cell_count {
        let cell_x = lo.x + (c % h.dims[0]) as f32 * cell.x;
        if cell_x + cell.x > -facts::WALL {
            continue;
        }
        for g in 0..GROUP_COUNT - 1 {
            let group_x = lo.x + (g % GROUPS_PER_SIDE) as f32 * group.x;
            let v = visibility.get(g, c, 0);
            if group_x >= -1e-3 && v < 1.0 {
                hidden.push(v as f64);
            } else if group_x + group.x <= 1e-3 {
                own_min = own_min.min(v);
            }
        }
    }
    (hidden, own_min)
}

/// `builtin:many-panels` without the camera room's panels.
fn hidden_panels() -> Scene {
    let mut s = many_panels();
    let visible: Vec<bool> =
        s.instances.iter().map(|i| s.nodes[i.node as usize].name.starts_with("visible.")).collect();
    let mut keep = visible.iter().map(|v| !v);
    s.instances.retain(|_| keep.next().unwrap());
    s
}

/// Emissive triangles go through the same resampling as the punctual lights past the shadowed
/// ones (issue 14: emissive meshes too), on `builtin:many-panels` (the two rooms lit by 72
/// panels, 144 triangles, 128 behind the wall; no punctual light). On both backends:
/// - no leak: with only the hidden room's panels the camera's room is exactly black, raw and
///   denoised;
/// - the reservoirs hold them: most surface pixels keep a triangle they see (W > 0), and every
///   reservoir's entry is one of the triangles;
/// - energy: the raw frames averaged, cache off, against the two-event reference; the denoised
///   frame against every bounce.
#[test]
fn emissive_panels_are_resampled_and_shadowed() {
    const FRAMES: u32 = 32;
    let ctx = common::validated_context();
    let triangles = hybrid_rt::world::lights::emitter_bases(&many_panels()).1;
    for backend in backends(&ctx) {
        for (denoiser, frames) in [(false, 1), (true, 8)] {
            let img = render(&ctx, hidden_panels(), settings(denoiser), backend, frames, &[composite::COLOR]);
            let max = (0..SIZE * SIZE).map(|i| lum(&img[0], i % SIZE, i / SIZE)).fold(0.0, f64::max);
            eprintln!("{backend:?} hidden panels only, denoiser {denoiser}: brightest pixel {max:e}");
            assert!(max <= 1e-6, "{backend:?}: panel light leaked into the sealed room (denoiser {denoiser}): {max:e}");
        }

        // Every panel in the reservoirs (by default the four brightest are mesh lights of the
        // shadows chain, which the reservoirs leave out: 48% of the pixels then keep one).
        let resampled = Settings { mesh_lights: false, ..settings(false) };
        let out = render(&ctx, many_panels(), resampled, backend, 4, &[gi::RESERVOIR, gbuffer::IDS]);
        let (reservoir, ids) = (&out[0], &out[1]);
        let (mut surface, mut seen, mut foreign) = (0, 0, 0);
        for y in 0..SIZE {
            for x in 0..SIZE {
                // No surface (NO_INSTANCE in gbuffer.glsl).
                if ids.get_u32(x, y, 0) == u32::MAX {
                    continue;
                }
                surface += 1;
                if reservoir.get(x, y, 1) > 0.0 {
                    seen += 1;
                    if reservoir.get(x, y, 0).to_bits() >= triangles {
                        foreign += 1;
                    }
                }
            }
        }
        let share = seen as f64 / surface as f64;
        eprintln!(
            "{backend:?}: {seen} of {surface} surface pixels keep a panel they see ({share:.3}), {foreign} another entry"
        );
        assert!(share > 0.5 && foreign == 0, "{backend:?}: {seen} of {surface} keep a panel, {foreign} another entry");

        let mut two = settings(false);
        two.radiance_cache.enabled = false;
        let raw = mean(&averaged_raw(&ctx, many_panels(), two, backend, FRAMES));
        let r2 = reference_of(&ctx, many_panels(), backend, TWO_EVENTS, 5, true);
        let r2b = reference_of(&ctx, many_panels(), backend, TWO_EVENTS, 6, true);
        let denoised = mean_lum(&render(&ctx, many_panels(), settings(true), backend, FRAMES, &[taa::COLOR])[0]);
        let all = reference_of(&ctx, many_panels(), backend, EVERY_BOUNCE, 5, true);
        let off = |x: f64, r: f64| (x - r) / r;
        eprintln!(
            "{backend:?}: panels, raw frames averaged {raw:.4} vs two-event reference {r2:.4} ({:+.2}%; reference \
             noise {:+.2}%); denoised frame {FRAMES} {denoised:.4} vs full reference {all:.4} ({:+.2}%)",
            100.0 * off(raw, r2),
            100.0 * off(r2b, r2),
            100.0 * off(denoised, all)
        );
        assert!(off(raw, r2).abs() < RAW_TOLERANCE, "{backend:?}: panels' raw mean luminance {raw} vs {r2}");
        assert!(off(denoised, all).abs() < DENOISED_TOLERANCE, "{backend:?}: panels' denoised {denoised} vs {all}");
    }
    common::assert_validation_clean(ctx);
}

/// `builtin:many-panels` with four point lights of the camera's room back on, dimmer than a
/// panel (0.2 cd: 4 pi 0.2 = 2.5 against a panel's pi 8 0.16 = 4.0).
/// The scene camera's view at time 0 for the tests' image size, which the renderer's plan ranks
/// the shadows chain's lights by.
fn first_view(s: &Scene) -> hybrid_rt::render::View {
    hybrid_rt::render::camera::first_view(s, &Default::default(), SIZE, SIZE).unwrap()
}

fn panels_and_dim_lights() -> Scene {
    let mut s = many_panels();
    for k in 0..4 {
        let name = format!("visible.{k}");
        let node = s.nodes.iter().position(|n| n.name == name).expect("the lights' nodes stay") as u32;
        s.lights.push(hybrid_rt::scene::Light {
            name: format!("dim.{k}"),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 0.2,
            range: None,
            radius: 0.0,
            node,
        });
    }
    s
}

/// Punctual lights and mesh lights are ranked together for the shadows chain's four channels
/// (issue 14): where four punctual lights are dimmer than the panels (and bring less to the
/// camera's view, by which the renderer ranks them), four of the camera room's panels take the
/// channels and the punctual lights are resampled in gi, a case in which every
/// punctual light used to take a channel first and every panel was resampled. The frame then
/// keeps the reference's light, with no punctual light in the chain (light 0 resampled, the
/// light table's and the grid's ranges starting at 0), on both backends: the raw frames
/// averaged, radiance cache off, against the two-event reference; the denoised frame against
/// every bounce. Measured (2026-12-06): raw +0.01%, denoised -1.78% (ray query) and -1.79%
/// (compute); since the four are ranked by what they bring to the camera's view (the same day,
/// other panels of the eight), raw -0.12%, denoised -1.92% and -1.93%; bounds RAW_TOLERANCE and
/// DENOISED_TOLERANCE.
#[test]
fn the_brightest_lights_take_the_chain_whatever_their_kind() {
    const FRAMES: u32 = 32;
    let s = panels_and_dim_lights();
    let plan = hybrid_rt::render::plan::FramePlan::for_scene(&s, 0.6, true, true, &[first_view(&s)]);
    let chain: Vec<&str> =
        plan.chain_emitters.iter().map(|c| s.nodes[s.instances[c.0 as usize].node as usize].name.as_str()).collect();
    assert_eq!(plan.chain_punctual, 0, "{:?}", plan.reasons);
    // (The camera room's eight panels emit alike: which four win is rounding.)
    assert!(chain.len() == 4 && chain.iter().all(|n| n.starts_with("visible.")), "{chain:?}: {:?}", plan.reasons);
    assert_eq!(plan.resampled_lights, 4, "{:?}", plan.reasons);
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        let mut two = settings(false);
        two.radiance_cache.enabled = false;
        let raw = mean(&averaged_raw(&ctx, panels_and_dim_lights(), two, backend, FRAMES));
        let r2 = reference_of(&ctx, panels_and_dim_lights(), backend, TWO_EVENTS, 5, true);
        let denoised =
            mean_lum(&render(&ctx, panels_and_dim_lights(), settings(true), backend, FRAMES, &[taa::COLOR])[0]);
        let all = reference_of(&ctx, panels_and_dim_lights(), backend, EVERY_BOUNCE, 5, true);
        let off = |x: f64, r: f64| (x - r) / r;
        eprintln!(
            "{backend:?}: panels and dim lights, raw frames averaged {raw:.4} vs two-event reference {r2:.4} \
             ({:+.2}%); denoised frame {FRAMES} {denoised:.4} vs full reference {all:.4} ({:+.2}%)",
            100.0 * off(raw, r2),
            100.0 * off(denoised, all)
        );
        assert!(raw > 0.01 && raw.is_finite(), "{backend:?}: the raw frame is dark or not finite ({raw})");
        assert!(off(raw, r2).abs() < RAW_TOLERANCE, "{backend:?}: raw mean luminance {raw} vs {r2}");
        assert!(off(denoised, all).abs() < DENOISED_TOLERANCE, "{backend:?}: denoised {denoised} vs {all}");
    }
    common::assert_validation_clean(ctx);
}

/// A view from the sealed room's far wall across its lights, the way the viewer's fly camera
/// would stand there.
fn in_the_sealed_room() -> hybrid_rt::render::ViewOverride {
    let (eye, target) = (Vec3::new(3.9, 2.2, 0.0), Vec3::new(0.5, 0.6, 0.0));
    hybrid_rt::render::ViewOverride {
        view: glam::Mat4::look_at_rh(eye, target, Vec3::Y),
        yfov: 1.3,
        znear: 0.05,
        zfar: 100.0,
    }
}

/// The chain's lights by name, in the renderer's shading order.
fn chain_of(r: &hybrid_rt::render::Renderer) -> Vec<String> {
    r.scene.lights[..r.plan.chain_punctual].iter().map(|l| l.name.clone()).collect()
}

/// Relative L1 of `img`'s luminance from `reference`'s.
fn relative_l1(img: &CpuImage, reference: &CpuImage) -> f64 {
    let (mut diff, mut sum) = (0.0, 0.0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            diff += (lum(img, x, y) - lum(reference, x, y)).abs();
            sum += lum(reference, x, y);
        }
    }
    diff / sum
}

/// Four lights in each room: four low ones in the middle of the camera room (their range
/// reaches the floor) and four of the sealed room's, so that either room's four can hold the
/// chain, and whichever do not are resampled. The sealed room's are sphere lights (its two
/// brightest and two of the small ones) or, with `points`, four of its point lights.
fn four_a_room(points: bool) -> Scene {
    let sealed = if points {
        ["hidden.0", "hidden.1", "hidden.2", "hidden.3"]
    } else {
        ["hidden.5", "hidden.37", "hidden.150", "hidden.165"]
    };
    with_lights(|n| ["visible.18", "visible.19", "visible.21", "visible.22"].contains(&n) || sealed.contains(&n))
}

/// The shadows chain follows the camera (issue 14: ranked once at the first view, a camera that
/// walked into the sealed room kept the camera room's four lights, which bring it nothing, and
/// the sealed room's lights were resampled). `Renderer::rank_chain_for` at a view in the sealed
/// room gives the chain that room's four lights, the same view again changes nothing, and the
/// camera room's view takes the chain back. With sphere lights there the frame is rebuilt (the
/// soft-shadow passes come and go); with point lights the passes stay and only the light
/// tables are made again. At the sealed room's view the frame keeps the reference's light
/// (DENOISED_TOLERANCE) and is closer to it than the frame whose chain stayed with the camera
/// room. Measured (2026-12-07, ray query, 64x64, frame 16 denoised against 256 spp): sphere
/// lights, relative L1 0.0427 (re-ranked) against 0.0535 (kept), mean luminance 2.341 and
/// 2.336 against 2.399, rebuilt in 1.5-2.0 s, nearly all of it the passes' pipelines; point
/// lights, 0.1165 against 0.1281, mean 0.372 and 0.364 against 0.383, the tables made in 3 ms.
#[test]
fn the_chain_follows_the_view_into_the_other_room() {
    use hybrid_rt::render::Reranked;
    const FRAMES: u32 = 16;
    let ctx = common::validated_context();
    let backend = backends(&ctx)[0];
    let shaders = hybrid_rt::gpu::ShaderLibrary::embedded();
    let at = |r: &hybrid_rt::render::Renderer| r.view_of(&r.pose_of(r.frame_index));
    for points in [false, true] {
        let what = if points { "point lights" } else { "sphere lights" };
        let changed = if points { Reranked::TablesRemade } else { Reranked::FrameRebuilt };
        let frame_at_sealed_room = |rerank: bool| {
            let mut r = common::renderer(&ctx, four_a_room(points), settings(true), backend);
            assert!(chain_of(&r).iter().all(|n| n.starts_with("visible.")), "first view: {:?}", chain_of(&r));
            r.set_view_override(Some(in_the_sealed_room()));
            if rerank {
                let view = at(&r);
                let start = std::time::Instant::now();
                assert_eq!(r.rank_chain_for(&shaders, &view).unwrap(), changed, "{what}: the sealed room's view");
                eprintln!("{what}: ranked again in {:.0} ms ({changed:?})", start.elapsed().as_secs_f64() * 1e3);
                let chain = chain_of(&r);
                assert!(chain.len() == 4 && chain.iter().all(|n| hidden(n)), "{what}, sealed room's view: {chain:?}");
                assert_eq!(r.plan.soft_shadows, !points, "{what}: {:?}", r.plan.reasons);
                assert_eq!(r.rank_chain_for(&shaders, &view).unwrap(), Reranked::Same, "{what}: the same view again");
            }
            common::render_frames(&mut r, FRAMES);
            let img = r.read_output(taa::COLOR).unwrap();
            if rerank {
                r.set_view_override(None);
                let view = at(&r);
                assert_eq!(r.rank_chain_for(&shaders, &view).unwrap(), changed, "{what}: back in the camera room");
                assert!(chain_of(&r).iter().all(|n| n.starts_with("visible.")), "{what}, back: {:?}", chain_of(&r));
                common::render_frames(&mut r, 1);
            }
            img
        };
        let followed = frame_at_sealed_room(true);
        let kept = frame_at_sealed_room(false);
        let reference = {
            let s = Settings { mode: RenderMode::Reference { seed: 3, max_bounces: EVERY_BOUNCE }, ..settings(false) };
            let mut r = common::renderer(&ctx, four_a_room(points), s, backend);
            r.set_view_override(Some(in_the_sealed_room()));
            common::render_frames(&mut r, REFERENCE_SPP);
            let out = r.hdr_output();
            r.read_output(out).unwrap()
        };
        let (l1_followed, l1_kept) = (relative_l1(&followed, &reference), relative_l1(&kept, &reference));
        let (m_followed, m_kept, m_ref) = (mean_lum(&followed), mean_lum(&kept), mean_lum(&reference));
        eprintln!(
            "{backend:?}, {what}: sealed room's view, frame {FRAMES}: chain re-ranked: relative L1 {l1_followed:.4}, \
             mean {m_followed:.4}; chain kept: {l1_kept:.4}, {m_kept:.4}; reference {m_ref:.4}"
        );
        assert!(m_followed.is_finite() && m_followed > 0.01, "{what}: the re-ranked frame is dark: {m_followed}");
        assert!((m_followed - m_ref).abs() / m_ref < DENOISED_TOLERANCE, "{what}: mean {m_followed} vs {m_ref}");
        assert!(l1_followed < l1_kept, "{what}: re-ranked {l1_followed} is no closer than kept {l1_kept}");
    }
    common::assert_validation_clean(ctx);
}
