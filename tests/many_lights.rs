//! Every light is shadowed, however many there are (issue 14): `builtin:many-lights` has 304
//! punctual lights, 256 of them in a sealed room behind the camera room's wall. The four
//! brightest (hidden-room lights) get per-light visibility; the other 300 are resampled in gi,
//! one light per pixel with its own shadow ray. On both ray backends:
//! - no leak: with only the hidden room's lights on, nothing in the camera's room can receive
//!   light and the environment is black, so every pixel is exactly 0, in the raw first frame and
//!   after denoising; with every light on, the floor strip by the wall (which no camera-room
//!   light reaches) keeps the brightness it has without the hidden room (within 10%), where a
//!   leak would make it many times brighter (the test computes how much);
//! - energy: the denoised frame's mean luminance is within 5% of the reference path tracer's
//!   (two scattering events, what the hybrid frame models; 256 spp).

mod common;

use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::{Context, ShaderLibrary};
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::render::{CameraChoice, RenderMode, Renderer, Settings};
use hybrid_rt::scene::Scene;
use hybrid_rt::scene::builtin_many_lights::{facts, many_lights};
use std::sync::Arc;

const SIZE: u32 = 64;

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
    outputs: &[&str],
) -> Vec<CpuImage> {
    let mut r = Renderer::new(ctx, &ShaderLibrary::embedded(), scene, s, &CameraChoice::Default, backend).unwrap();
    for _ in 0..frames {
        r.render_frame().unwrap();
    }
    r.read_outputs(outputs).unwrap()
}

/// Mean luminance over the strip's interior pixels (away from its silhouette), and their count.
fn strip_mean(color: &CpuImage, ids: &CpuImage) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            if ids.get_u32(x, y, 0) == facts::STRIP_INSTANCE && common::interior(ids, x, y) {
                sum += lum(color, x, y);
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
            let img = render(&ctx, with_lights(hidden), settings(denoiser), backend, frames, &["composite.color"]);
            let mut max = 0.0f64;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    max = max.max(lum(&img[0], x, y));
                }
            }
            eprintln!("{backend:?} hidden lights only, denoiser {denoiser}: brightest pixel {max:e}");
            assert!(max <= 1e-6, "{backend:?}: light leaked into the sealed room (denoiser {denoiser}): {max:e}");
        }
        // Every light against the camera room's lights alone, on the strip by the wall.
        let outputs = ["composite.color", "gbuffer.ids"];
        let all = render(&ctx, many_lights(), settings(true), backend, 16, &outputs);
        let own = render(&ctx, with_lights(|n| !hidden(n)), settings(true), backend, 16, &outputs);
        let ((with, n), (without, _)) = (strip_mean(&all[0], &all[1]), strip_mean(&own[0], &own[1]));
        let leak = leak_if_unshadowed(&many_lights());
        let allowed = 0.1 * without;
        eprintln!(
            "{backend:?}: strip ({n} px) {with:.4} with every light, {without:.4} without the hidden room; \
             a leak would add {leak:.3}"
        );
        assert!(n > 50, "too few strip pixels: {n}");
        assert!(leak > 20.0 * allowed, "the check could not see a leak: {leak} vs {allowed}");
        assert!(
            (with - without).abs() <= allowed,
            "{backend:?}: strip {with:.4} vs {without:.4} without hidden lights"
        );
    }
    common::assert_validation_clean(ctx);
}

#[test]
fn mean_luminance_matches_the_reference() {
    let ctx = common::validated_context();
    for backend in backends(&ctx) {
        let reference = {
            let s = Settings { mode: RenderMode::Reference { seed: 5, max_bounces: 2 }, ..settings(false) };
            let mut r =
                Renderer::new(&ctx, &ShaderLibrary::embedded(), many_lights(), s, &CameraChoice::Default, backend)
                    .unwrap();
            for _ in 0..256 {
                r.render_frame().unwrap();
            }
            let out = r.hdr_output().to_string();
            mean_lum(&r.read_output(&out).unwrap())
        };
        let hybrid = mean_lum(&render(&ctx, many_lights(), settings(true), backend, 32, &["taa.color"])[0]);
        let error = (hybrid - reference).abs() / reference;
        eprintln!("{backend:?}: mean luminance {hybrid:.4}, reference {reference:.4} ({:.2}%)", error * 100.0);
        assert!(error < 0.05, "{backend:?}: mean luminance off by {:.2}%", error * 100.0);
    }
    common::assert_validation_clean(ctx);
}
