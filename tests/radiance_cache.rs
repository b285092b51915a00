//! The radiance cache carries every bounce: the hybrid frame's energy against Mitsuba 3's
//! converged render of the same closed rooms (tests/mitsuba/, made by tools/mitsuba_reference.py),
//! with the cache on and off, and no light through a wall thinner than a cache cell.
//!
//! Energy: the mean luminance of the hybrid frame (the shipped path: SVGF and TAA), averaged
//! over frames 17..48 at 64x64, without the emitter's pixels (where the frame shows emission
//! exactly and a ratio would only dilute the indirect light the cache is for).

mod common;

use hybrid_rt::gpu::{Context, ShaderLibrary};
use hybrid_rt::image_io::{self, CpuImage};
use hybrid_rt::metrics;
use hybrid_rt::render::{CameraChoice, Environment, Renderer, Settings};
use hybrid_rt::scene::gltf::{LoadOptions, load_gltf};
use std::path::PathBuf;
use std::sync::Arc;

const FRAMES: u32 = 48;
const AVERAGED_FROM: u32 = 17;

fn scene_dir(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/mitsuba").join(name)
}

/// Per-pixel luminance of an RGBA f32 image.
fn luminances(img: &CpuImage) -> Vec<f64> {
    let px = img.as_f32().unwrap();
    px.chunks_exact(img.channels).map(|p| metrics::luminance(p[0], p[1], p[2]) as f64).collect()
}

/// Mean of `values` over the pixels that `keep` marks.
fn masked_mean(values: &[f64], keep: &[bool]) -> f64 {
    let (sum, n) = values.iter().zip(keep).filter(|(_, k)| **k).fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
    sum / n.max(1) as f64
}

/// The hybrid frame's HDR output averaged over frames AVERAGED_FROM..=FRAMES.
fn hybrid_luminance(ctx: &Arc<Context>, name: &str, cache: bool, size: (u32, u32)) -> Vec<f64> {
    let scene = load_gltf(&scene_dir(name).join("scene.gltf"), &LoadOptions::default()).unwrap();
    let mut settings = Settings {
        width: size.0,
        height: size.1,
        // Closed rooms, as Mitsuba rendered them.
        environment: Environment::Constant(glam::Vec3::ZERO),
        taa: true,
        ..Default::default()
    };
    settings.radiance_cache.enabled = cache;
    let backend = common::auto_backend(ctx);
    let mut r =
        Renderer::new(ctx, &ShaderLibrary::embedded(), scene, settings, &CameraChoice::Default, backend).unwrap();
    let mut sum = vec![0.0; (size.0 * size.1) as usize];
    for frame in 1..=FRAMES {
        r.render_frame().unwrap();
        if frame >= AVERAGED_FROM {
            let out = r.read_output(r.hdr_output()).unwrap();
            for (s, l) in sum.iter_mut().zip(luminances(&out)) {
                assert!(l.is_finite(), "{name}: a non-finite pixel in frame {frame}");
                *s += l;
            }
        }
    }
    if cache {
        let stats = r.radiance_cache_stats().expect("the frame has a cache");
        eprintln!("{name}: radiance cache after {FRAMES} frames: {} live cells, {} updated", stats.live, stats.updated);
        assert!(stats.live > 0 && stats.updated > 0, "{name}: the cache holds nothing: {stats:?}");
    }
    let n = (FRAMES - AVERAGED_FROM + 1) as f64;
    sum.iter().map(|s| s / n).collect()
}

/// `tolerance`: how far from Mitsuba's mean luminance the frame with the cache may be;
/// `with_cache_off`: also render without the cache, which must come out darker.
fn check_energy(name: &str, tolerance: f64, with_cache_off: bool) {
    let ctx = common::validated_context();
    let converged = image_io::read_exr_rgba(&scene_dir(name).join("mitsuba-converged.exr")).unwrap();
    let size = (converged.width, converged.height);
    let reference = luminances(&converged);
    // The emitter: far brighter than any lit wall.
    let brightest_wall = {
        let mut sorted = reference.clone();
        sorted.sort_by(f64::total_cmp);
        sorted[sorted.len() * 9 / 10]
    };
    let keep: Vec<bool> = reference.iter().map(|&l| l <= 4.0 * brightest_wall).collect();
    let reference_mean = masked_mean(&reference, &keep);
    let on = masked_mean(&hybrid_luminance(&ctx, name, true, size), &keep) / reference_mean;
    let off = with_cache_off.then(|| masked_mean(&hybrid_luminance(&ctx, name, false, size), &keep) / reference_mean);
    eprintln!(
        "{name} ({}x{}, frames {AVERAGED_FROM}..={FRAMES}, {} of {} pixels without the emitter): mean luminance \
         x Mitsuba's: cache on {on:.4}, cache off {off:?}",
        size.0,
        size.1,
        keep.iter().filter(|k| **k).count(),
        keep.len()
    );
    assert!(
        (on - 1.0).abs() <= tolerance,
        "{name}: with the radiance cache the frame's mean luminance is {on:.4} x Mitsuba's (tolerance {tolerance})"
    );
    if let Some(off) = off {
        assert!(off < on - 0.1, "{name}: the cache adds too little light ({off:.4} off, {on:.4} on)");
    }
    common::assert_validation_clean(ctx);
}

/// Measured (lavapipe, 2026-12-02): cache on 0.988 (0.977 before young cells traced deep), cache off 0.723 (one bounce). Bound 3%.
#[test]
fn diffuse_box_converges_to_mitsubas_energy() {
    check_energy("diffuse_box", 0.03, true);
}

/// Measured: cache on 0.922 with SVGF and TAA, about 0.96 raw (both without SVGF and TAA: each of
/// them alone gives 0.90, their outlier clamps cut the rare bright paths through the metal and
/// glossy blocks); cache off 0.62. Bound 12%, which a cache that stopped carrying the bounces
/// after the first fails.
#[test]
fn glossy_blocks_converge_to_mitsubas_energy() {
    check_energy("glossy_blocks", 0.12, false);
}
