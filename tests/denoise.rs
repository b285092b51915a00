//! The denoised hybrid frame against the reference (issue 5):
//! - a sharp albedo checkerboard lit by an area light stays sharp after denoising;
//! - the denoised static frame keeps the image's mean HDR luminance within 2% of the reference;
//! - at frames 1, 16 and 64 the denoised error is below the raw (undenoised, one frame) error
//!   by the stated factors;
//! - a smooth, coarsely tessellated sphere shows no steps at its triangle edges after denoising
//!   (issue 13: the filter's edge-stopping normal). Error: relative MSE, mean((test - ref)^2 / (ref^2 + 0.01)) over RGB,
//!   the usual measure for renderings, which a few very bright pixels (the ceiling light and its
//!   edges) cannot dominate as they do a plain RMSE.
//!
//! The reference is the path tracer limited to two scattering events (what the hybrid frame
//! models; tests/hybrid.rs checks that the undenoised frames converge to it).

mod common;

use hybrid_rt::gpu::Context;
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::metrics;
use hybrid_rt::passes;
use hybrid_rt::passes::svgf::{self, atrous};
use hybrid_rt::render::{RenderMode, Renderer, Settings};
use hybrid_rt::scene::builtin::{self, checker_test_facts as facts};
use hybrid_rt::scene::{LoadOptions, Scene, load_gltf};
use std::sync::Arc;

const SIZE: u32 = 64;

fn lum(img: &CpuImage) -> Vec<f64> {
    (0..img.pixel_count() as u32)
        .map(|i| {
            let (x, y) = (i % img.width, i / img.width);
            0.2126 * img.get(x, y, 0) as f64 + 0.7152 * img.get(x, y, 1) as f64 + 0.0722 * img.get(x, y, 2) as f64
        })
        .collect()
}

/// The full frame (TAA on, so its jitter box-filters pixels as the reference does) with or
/// without the denoiser, scene frozen; without the radiance cache, so that the frame is the
/// two-bounce estimate the reference below computes exactly and any difference is the
/// denoiser's (tests/radiance_cache.rs checks the cache).
fn settings(denoiser: bool) -> Settings {
    let mut s = Settings { width: SIZE, height: SIZE, frame_dt: 0.0, taa: true, denoiser, ..Default::default() };
    s.radiance_cache.enabled = false;
    s
}

fn renderer(ctx: &Arc<Context>, scene: Scene, s: Settings) -> Renderer {
    common::renderer(ctx, scene, s, common::auto_backend(ctx))
}

fn reference(ctx: &Arc<Context>, scene: Scene, spp: u32) -> CpuImage {
    let s = Settings { mode: RenderMode::Reference { seed: 11, max_bounces: 2 }, ..settings(false) };
    let mut r = renderer(ctx, scene, s);
    common::render_frames(&mut r, spp);
    r.read_output(r.hdr_output()).unwrap()
}

fn rel_mse(test: &CpuImage, truth: &CpuImage) -> f64 {
    metrics::rel_mse(truth, test, metrics::REL_MSE_EPSILON).unwrap()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn albedo_checkerboard_stays_sharp() {
    let ctx = common::validated_context();
    let mut r = renderer(&ctx, builtin::checker_test(), settings(true));
    common::render_frames(&mut r, 16);
    let imgs = r.read_outputs(&[passes::composite::COLOR, passes::gbuffer::BASE_COLOR, passes::gbuffer::IDS]).unwrap();
    let (l, albedo) = (lum(&imgs[0]), lum(&imgs[1]));
    // Light on the wall varies slowly; the albedo jumps by 8x between cells. Compare each
    // pixel with its right neighbour across every cell edge: the image must jump as the albedo
    // does (ratio of radiance ratio to albedo ratio near 1), not be smeared across the edge.
    let (mut ratios, mut edges) = (Vec::new(), 0);
    for y in 0..SIZE {
        for x in 0..SIZE - 1 {
            let (i, j) = ((y * SIZE + x) as usize, (y * SIZE + x + 1) as usize);
            if imgs[2].get_u32(x, y, 0) != facts::WALL_INSTANCE || imgs[2].get_u32(x + 1, y, 0) != facts::WALL_INSTANCE
            {
                continue;
            }
            let (a0, a1) = (albedo[i], albedo[j]);
            if (a0 / a1 - 1.0).abs() < 0.5 {
                continue;
            }
            edges += 1;
            ratios.push((l[i] / l[j]) / (a0 / a1));
        }
    }
    ratios.sort_by(|a, b| a.total_cmp(b));
    let median = ratios[ratios.len() / 2];
    eprintln!("checker: {edges} cell-edge pixel pairs, median (radiance ratio / albedo ratio) {median:.3}");
    assert!(edges > 50, "too few edges: {edges}");
    assert!((median - 1.0).abs() < 0.15, "the checkerboard edge contrast changed by the denoiser: {median:.3}");
    drop(r);
    common::assert_validation_clean(ctx);
}

#[test]
fn denoised_frames_keep_energy_and_beat_raw_noise() {
    let ctx = common::validated_context();
    let scene = || load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap();
    let truth = reference(&ctx, scene(), 512);

    let mut raw = renderer(&ctx, scene(), settings(false));
    raw.render_frame().unwrap();
    // One raw frame: no denoiser, no history (TAA's output equals its input on the first frame).
    let raw_error = rel_mse(&raw.read_output(passes::taa::COLOR).unwrap(), &truth);
    drop(raw);

    let mut den = renderer(&ctx, scene(), settings(true));
    let mut errors = Vec::new();
    let mut last = None;
    for frame in 1..=64u32 {
        den.render_frame().unwrap();
        if [1, 16, 64].contains(&frame) {
            let img = den.read_output(passes::taa::COLOR).unwrap();
            errors.push((frame, rel_mse(&img, &truth)));
            last = Some(img);
        }
    }
    let (last, truth_l) = (lum(&last.unwrap()), lum(&truth));
    let energy = (mean(&last) - mean(&truth_l)).abs() / mean(&truth_l);
    eprintln!(
        "raw 1-frame relMSE {raw_error:.4}; denoised {errors:?}; mean luminance {:.4} vs reference {:.4} ({:.2}%)",
        mean(&last),
        mean(&truth_l),
        energy * 100.0
    );
    assert!(energy < 0.02, "denoised mean luminance off by {:.2}%", energy * 100.0);
    // Stated factors (measured on lavapipe, 2026-12-04: 4.6x, 13.0x, 9.3x since the clamp hands
    // on exactly what it takes and converged taps are left out, 4.6x, 12.4x, 9.0x before;
    // 2026-12-03: 5.0x, 13.2x, 10.0x; 5.0x, 15.7x, 14.9x
    // before the outlier clamp kept the fireflies' light, which it spreads as low blotches that a
    // relative MSE weighs heavily in the dark): frame 1 (spatial filtering of one
    // sample) at least 4x below the raw single frame; frames 16 and 64 (history) at least 8x.
    // Frame 64 is not below frame 16: what remains is the filter's bias, not noise.
    for ((frame, e), factor) in errors.iter().zip([4.0, 8.0, 8.0]) {
        assert!(e * factor < raw_error, "frame {frame}: denoised relMSE {e:.4} not {factor}x below raw {raw_error:.4}");
    }
    drop(den);
    common::assert_validation_clean(ctx);
}

/// Steps at triangle edges in `signal` over `instance`: the mean relative luminance jump
/// between 4-neighbour pixels on two different faces (geometric normals more than 2 degrees
/// apart), and between 4-neighbours on one face; (across edges, inside faces, pair counts).
/// Silhouettes are left out: both pixels must be surrounded by the instance.
fn facet_steps(signal: &CpuImage, normal_geo: &CpuImage, ids: &CpuImage, instance: u32) -> (f64, f64, usize, usize) {
    let l = lum(signal);
    let n = |x: u32, y: u32| glam::Vec3::new(normal_geo.get(x, y, 0), normal_geo.get(x, y, 1), normal_geo.get(x, y, 2));
    let (mut across, mut inside) = (Vec::new(), Vec::new());
    for y in 0..signal.height {
        for x in 0..signal.width {
            for (qx, qy) in [(x + 1, y), (x, y + 1)] {
                if qx >= signal.width || qy >= signal.height {
                    continue;
                }
                let on = |x, y| ids.get_u32(x, y, 0) == instance && common::interior(ids, x, y);
                if !on(x, y) || !on(qx, qy) {
                    continue;
                }
                let (a, b) = (l[(y * signal.width + x) as usize], l[(qy * signal.width + qx) as usize]);
                let jump = (a - b).abs() / (0.5 * (a + b) + 1e-6);
                let cos = n(x, y).normalize().dot(n(qx, qy).normalize());
                if cos < 2f32.to_radians().cos() {
                    across.push(jump);
                } else if cos > 0.99999 {
                    inside.push(jump);
                }
            }
        }
    }
    (mean(&across), mean(&inside), across.len(), inside.len())
}

/// How much larger the mean jump between neighbouring pixels on two faces of the facet test's
/// spheres may be than between neighbours on one face. The true shading is smooth, so the two
/// differ only by noise and by the shading's slope (the same on both). Measured on lavapipe
/// (128x64, 8 frames): with the face normal as the filter's edge-stopping normal (the
/// faceting bug) 7.6 (diffuse signal), 3.4 (specular signal), 1.95 and 1.69 (the final frame on
/// the diffuse and the glossy sphere); with the shading normal 1.06, 1.10, 1.02
/// and 1.12. The bound fails every one of the old four and leaves the new ones 25% margin.
const FACET_RATIO: f64 = 1.4;

/// The faceting of issue 13: a smooth sphere of 960 triangles (the default scene's gold sphere's
/// tessellation), lit by an area light, must not show steps at triangle edges after denoising,
/// neither in the filtered signals nor in the final frame.
#[test]
fn curved_surfaces_are_not_faceted() {
    use builtin::facet_test_facts::*;
    let ctx = common::validated_context();
    let s = Settings { width: 128, height: 64, ..settings(true) };
    let mut r = renderer(&ctx, builtin::facet_test(), s);
    common::render_frames(&mut r, 8);
    let last = hybrid_rt::passes::svgf::SvgfSettings::default().iterations - 1;
    let diffuse = atrous::DIFFUSE.of(svgf::iteration(svgf::PAIR, last));
    let specular = atrous::SPECULAR.of(svgf::iteration(svgf::PAIR, last));
    let names = [passes::gbuffer::NORMAL_GEO, passes::gbuffer::IDS, diffuse, specular, passes::taa::COLOR];
    let imgs = r.read_outputs(&names).unwrap();
    let (ng, ids) = (&imgs[0], &imgs[1]);
    for (what, img, instance) in [
        ("diffuse signal", &imgs[2], DIFFUSE_SPHERE_INSTANCE),
        ("specular signal", &imgs[3], GLOSSY_SPHERE_INSTANCE),
        ("frame, diffuse sphere", &imgs[4], DIFFUSE_SPHERE_INSTANCE),
        ("frame, glossy sphere", &imgs[4], GLOSSY_SPHERE_INSTANCE),
    ] {
        let (across, inside, n_across, n_inside) = facet_steps(img, ng, ids, instance);
        eprintln!(
            "{what}: mean relative jump across triangle edges {across:.4} ({n_across} pairs), inside triangles \
             {inside:.4} ({n_inside} pairs), ratio {:.2}",
            across / inside
        );
        assert!(n_across > 300 && n_inside > 1000, "{what}: too few pixel pairs ({n_across}, {n_inside})");
        assert!(
            across <= FACET_RATIO * inside,
            "{what}: steps at triangle edges: mean jump {across:.4} across them, {inside:.4} inside"
        );
    }
    drop(r);
    common::assert_validation_clean(ctx);
}
