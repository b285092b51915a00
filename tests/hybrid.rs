//! The hybrid frame converges to the reference for what it models. With the denoiser and the
//! radiance cache off (tests/radiance_cache.rs checks the bounces the cache adds, against
//! Mitsuba 3) and the scene frozen, the average of many hybrid frames of the default scene is compared
//! with the reference path tracer limited to two scattering events (direct light and one
//! bounce), which is what the hybrid frame computes: direct light from every light, one diffuse
//! bounce with next-event estimation at its hit, and one specular bounce shaded with direct
//! light at its hit.
//!
//! What the hybrid frame leaves out or approximates, and so what the bound allows for:
//! - sphere and disk lights are shaded from their centre (times their ray-traced visibility);
//! - the soft shadows' spatial filter blurs penumbrae slightly;
//! - surfaces rougher than the reflection cut-off (0.6) take the environment in the mirror
//!   direction instead of tracing their specular lobe (here: the black sky), so their specular
//!   highlight from the ceiling light is missing.
//!
//! The frames are rendered with TAA's sub-pixel jitter (and read before TAA), so their average
//! is box-filtered over each pixel like the reference's samples: without it, pixel centres on
//! the bright ceiling light against box-filtered edges make a difference that is not bias.
//!
//! Metrics: relative difference of the image's mean luminance; and the relative mean absolute
//! error (sum |h - r| / sum r, luminance) of 4x4-pixel block means, so that the remaining
//! sampling noise of both images (256 samples each) does not hide or fake a bias; the same
//! measure between two reference renders of different seeds is printed as the noise floor.

mod common;

use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::render::{RenderMode, Settings};
use hybrid_rt::scene::{LoadOptions, load_gltf};

const SIZE: u32 = 64;
const FRAMES: u32 = 256;

fn luminance(img: &[[f64; 3]]) -> Vec<f64> {
    img.iter().map(|c| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]).collect()
}

/// Means of 4x4 blocks of a SIZE x SIZE luminance image.
fn blocks(l: &[f64]) -> Vec<f64> {
    let n = (SIZE / 4) as usize;
    let mut out = vec![0.0; n * n];
    for (i, v) in l.iter().enumerate() {
        let (x, y) = (i % SIZE as usize, i / SIZE as usize);
        out[(y / 4) * n + x / 4] += v / 16.0;
    }
    out
}

fn rel_l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f64>() / b.iter().sum::<f64>()
}

fn reference(ctx: &std::sync::Arc<hybrid_rt::gpu::Context>, base: &Settings, seed: u32) -> Vec<f64> {
    let settings = Settings { mode: RenderMode::Reference { seed, max_bounces: 2 }, ..base.clone() };
    let scene = load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap();
    let backend = common::auto_backend(ctx);
    let mut r = common::renderer(ctx, scene, settings, backend);
    common::render_frames(&mut r, FRAMES);
    luminance(&rgb(&r.read_output(r.hdr_output()).unwrap()))
}

fn rgb(img: &CpuImage) -> Vec<[f64; 3]> {
    (0..img.pixel_count() as u32)
        .map(|i| {
            let (x, y) = (i % img.width, i / img.width);
            [img.get(x, y, 0) as f64, img.get(x, y, 1) as f64, img.get(x, y, 2) as f64]
        })
        .collect()
}

#[test]
fn accumulated_hybrid_frames_approach_the_two_bounce_reference() {
    let ctx = common::validated_context();
    let backend = common::auto_backend(&ctx);
    let scene = || load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap();
    let mut base =
        Settings { width: SIZE, height: SIZE, frame_dt: 0.0, denoiser: false, taa: true, ..Default::default() };
    base.radiance_cache.enabled = false;

    let mut hybrid = common::renderer(&ctx, scene(), base.clone(), backend);
    let mut sum = vec![[0.0f64; 3]; (SIZE * SIZE) as usize];
    for _ in 0..FRAMES {
        hybrid.render_frame().unwrap();
        let frame = rgb(&hybrid.read_output(passes::composite::COLOR).unwrap());
        for (s, f) in sum.iter_mut().zip(frame) {
            for c in 0..3 {
                s[c] += f[c] / FRAMES as f64;
            }
        }
    }
    drop(hybrid);

    let r = reference(&ctx, &base, 7);
    let r2 = reference(&ctx, &base, 8);
    let h = luminance(&sum);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mean_error = (mean(&h) - mean(&r)).abs() / mean(&r);
    let (bias, noise) = (rel_l1(&blocks(&h), &blocks(&r)), rel_l1(&blocks(&r2), &blocks(&r)));
    eprintln!(
        "hybrid ({FRAMES} frames) vs reference ({FRAMES} spp, 2 bounces): mean luminance {:.4} vs {:.4} ({:.2}%); \
         4x4-block relative L1 {bias:.3} (two references: {noise:.3})",
        mean(&h),
        mean(&r),
        mean_error * 100.0
    );
    assert!(mean_error < 0.02, "mean luminance differs by {:.1}%", mean_error * 100.0);
    assert!(bias < 0.05, "4x4-block relative L1 error {bias:.3} (noise floor {noise:.3})");
    common::assert_validation_clean(ctx);
}
