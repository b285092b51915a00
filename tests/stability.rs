//! The stability suite (src/bench/stability.rs) at 48x48 on the validated context: each
//! scenario rendered denoised (SVGF and TAA) and raw (neither), each metric held under its
//! bound. The bounds live beside the metrics in the library (the bench prints them); the
//! comments here say what was measured on lavapipe and why the bound is where it is.

mod common;

use hybrid_rt::bench::stability::{self, Measure, Rig};
use hybrid_rt::gpu::{Context, ShaderLibrary};
use std::sync::Arc;

fn rig<'a>(ctx: &'a Arc<Context>, shaders: &'a ShaderLibrary) -> Rig<'a> {
    let (width, height) = stability::BOUND_SIZE;
    Rig { ctx, shaders, backend: common::auto_backend(ctx), width, height }
}

/// Runs `scenario` denoised and raw, prints both, checks every bound and returns (denoised,
/// raw) for further checks.
fn run(name: &str, scenario: stability::ScenarioFn) -> (Vec<Measure>, Vec<Measure>) {
    let ctx = common::validated_context();
    let shaders = ShaderLibrary::embedded();
    let (denoised, raw) = {
        let rig = rig(&ctx, &shaders);
        (scenario(&rig, true).unwrap(), scenario(&rig, false).unwrap())
    };
    for (d, r) in denoised.iter().zip(&raw) {
        eprintln!("{name}: {}: denoised {:.5} (bound {}), raw {:.5} (bound {}) {}", d.metric, d.value, d.bound, r.value, r.bound, d.unit);
    }
    for m in denoised.iter().chain(&raw) {
        assert!(m.within_bound(), "{name}: {} = {} is over its bound {}", m.metric, m.value, m.bound);
    }
    common::assert_validation_clean(ctx);
    (denoised, raw)
}

fn value(measures: &[Measure], prefix: &str) -> f64 {
    measures.iter().find(|m| m.metric.starts_with(prefix)).unwrap_or_else(|| panic!("no metric {prefix}")).value
}

/// Metric: relative mean absolute luminance error against the new view's reference, in the
/// first frame after a cut and over the 8 after it. Measured: TODO. Without telling the
/// renderer about the cut (history kept, reprojection alone), the first frame is clearly worse.
#[test]
fn camera_cut() {
    let (denoised, _) = run("camera cut", stability::camera_cut);
    let ctx = common::validated_context();
    let shaders = ShaderLibrary::embedded();
    let kept = stability::camera_cut_errors(&rig(&ctx, &shaders), true, false).unwrap();
    eprintln!("camera cut without a history reset: errors {kept:.4?}");
    let first = value(&denoised, "first frame");
    assert!(kept[0] > 1.5 * first, "keeping the history over a cut is not worse: {} vs {first}", kept[0]);
    common::assert_validation_clean(ctx);
}

/// Metric: relative mean absolute luminance error halfway through and at the end of a pan of
/// 2.8 degrees a frame, against 8 raw frames at the same pose. Measured: TODO.
#[test]
fn fast_pan() {
    run("fast pan", stability::fast_pan);
}

/// Metrics: the fraction of the background's light missing in the cube's 3-frame trail
/// (ghosting), and the relative error of pixels in their first frame uncovered
/// (disocclusion). Measured: TODO. Raw frames have no history: their trail misses nothing
/// beyond noise, and the denoised trail must stay within a few times of that.
#[test]
fn moving_object() {
    run("moving object", stability::moving_object);
}

/// Metrics: the fraction of a light's step still missing in the first frame after it jumped,
/// and the frames until the image stays within 10 % of the step. Measured: TODO. Raw frames
/// follow at once (no history): lag 0.
#[test]
fn moving_light() {
    let (_, raw) = run("moving light", stability::moving_light);
    assert_eq!(value(&raw, "lag"), 0.0, "raw frames have no history to lag with");
}

/// As `moving_light`, for a light switched off. Measured: TODO.
#[test]
fn light_off() {
    let (_, raw) = run("light off", stability::light_off);
    assert_eq!(value(&raw, "lag"), 0.0, "raw frames have no history to lag with");
}

/// Metrics: mean luminance inside the sealed room, and on the unlit outer face at the room's
/// edge, relative to the lit face's median; the truth is 0 for both. Measured: TODO.
#[test]
fn leaking() {
    run("leaking", stability::leaking);
}

/// Metrics: shadowed fraction of the open floor under a 5-degree sun (acne), its fraction
/// darker than half the median (speckle), and the shadowed fraction of the coarse sphere's
/// pixels whose shading normal faces the light (terminator). Measured: TODO.
#[test]
fn grazing_floor() {
    run("grazing floor", stability::grazing_floor);
}

/// Metrics: fraction of pixels over 10x their 5x5 median, and the peak-to-mean ratio, with a
/// tiny very bright emitter. Measured: TODO. The denoiser must leave fewer than the raw frame.
#[test]
fn fireflies() {
    let (denoised, raw) = run("fireflies", stability::fireflies);
    assert!(value(&denoised, "pixels") <= value(&raw, "pixels"), "the denoiser added fireflies");
}
