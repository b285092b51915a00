//! The stability suite (src/bench/stability.rs) at 48x48 on the validated context: each
//! scenario rendered denoised (SVGF and TAA) and raw (neither), each metric held under its
//! bound. The bounds live beside the metrics in the library (the bench prints them); the
//! comments here say what was measured on lavapipe and why the bound is where it is.

mod common;

use hybrid_rt::bench::stability::{self, Measure, Rig};
use hybrid_rt::gpu::{Context, ShaderLibrary};
use hybrid_rt::render::Settings;
use std::sync::Arc;

fn rig<'a>(ctx: &'a Arc<Context>, shaders: &'a ShaderLibrary) -> Rig<'a> {
    let (width, height) = stability::BOUND_SIZE;
    Rig { ctx, shaders, backend: common::auto_backend(ctx), width, height, gi_rate: Settings::default().gi.rate }
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
        eprintln!(
            "{name}: {}: denoised {:.5} (bound {}), raw {:.5} (bound {}) {}",
            d.metric, d.value, d.bound, r.value, r.bound, d.unit
        );
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

/// A pan's scenario run as `run` does, and its denoised and raw errors during the pan, printed
/// with their ratio.
fn pan(name: &str, scenario: stability::ScenarioFn) -> (Vec<Measure>, Vec<Measure>, f64, f64) {
    let (denoised, raw) = run(name, scenario);
    let (d, r) = (value(&denoised, "during the pan"), value(&raw, "during the pan"));
    eprintln!("{name}: denoised {d:.4}, raw {r:.4} ({:.2}x)", d / r);
    (denoised, raw, d, r)
}

/// Metric: relative mean absolute luminance error (sum |Y - Y_ref| / sum Y_ref) against the
/// new view's reference (8 raw frames), in the first frame after a cut from the sunlit wall to
/// the floor behind the camera, and over the 8 frames after it. Measured: denoised 0.082 and
/// 0.083 (the converged level of this view: no trace of the old one), raw 0.147 and 0.156
/// (one sample's noise). Bounds 0.15 denoised, 0.25 raw: about 1.7x the measurement.
/// A history that survived the cut would make the first frame worse than the later ones: it
/// must not be. The deliberately bad configuration, a camera change the renderer is not told
/// about, measured 0.082 too (reprojection alone rejects history from behind the old eye) and
/// must stay within the same bound.
#[test]
fn camera_cut() {
    let (denoised, _) = run("camera cut", stability::camera_cut);
    let (first, later) = (value(&denoised, "first frame"), value(&denoised, "8 frames"));
    assert!(first <= 1.25 * later, "the first frame after the cut is worse than the later ones: {first} vs {later}");
    let ctx = common::validated_context();
    let shaders = ShaderLibrary::embedded();
    let kept = stability::camera_cut_errors(&rig(&ctx, &shaders), true, false).unwrap();
    eprintln!("camera cut without a history reset: errors {kept:.4?}");
    assert!(kept[0] <= denoised[0].bound, "an unannounced cut kept stale history: {} vs {first}", kept[0]);
    common::assert_validation_clean(ctx);
}

/// Metric: relative mean absolute luminance error halfway through and at the end of a pan of
/// 2.8 degrees (about 2.5 pixels) a frame, against 8 raw frames at the same pose. Measured:
/// denoised 0.192, raw 0.176. It was 0.246 while TAA resampled its history bilinearly (a blur
/// that compounds every frame the image moves) with the same weight at any speed; Catmull-Rom
/// history took it to 0.220, and giving the new frame more weight the faster the image moves
/// to 0.192. What is left is mostly the jitter: the reference is unjittered, and during the pan
/// TAA keeps too little history to average the jitter out (with TAA off, SVGF alone measured
/// 0.062). Bounds 0.27 denoised, 0.25 raw (about 1.4x), and denoised within 1.25x of raw
/// (1.09 measured; 1.40 before). With gi at half rate: denoised 0.189, raw 0.157 (1.20x): the
/// fill's averaged samples lowered the raw frame's noise more than the denoised frame's error.
/// Since the jitter shrinks as the camera moves the image (`taa::jitter_scale`,
/// `camera::image_motion`): denoised 0.102, raw 0.155 (0.66x; 0.091 with no jitter at all
/// while the camera moves). Bounds 0.15 denoised, 0.25 raw, and the denoised frame no worse
/// than the raw one.
#[test]
fn fast_pan() {
    let (denoised, raw) = run("fast pan", stability::fast_pan);
    let (d, r) = (value(&denoised, "during the pan"), value(&raw, "during the pan"));
    assert!(d <= r, "during the pan the denoised frame is {:.2}x the raw error: {d:.4} vs {r:.4}", d / r);
}

/// Metric: relative mean absolute luminance error over a near-mirror floor (roughness 0.05)
/// while the camera moves sideways over it, against 8 raw frames at the same pose. Measured:
/// denoised 0.202, raw 0.100. The denoised frame was 0.44 with SVGF alone while the specular
/// history followed the floor and the a-trous filter spread the mirror's reflection over its
/// neighbours; following the reflected wall (the virtual point at the hit distance) took SVGF
/// alone to 0.27, and giving a mirror's reflection no spatial footprint to 0.178; with TAA
/// (0.266 while it reprojected with the floor's motion, 0.202 since it follows the reflection
/// on metals too; 0.213 since SVGF's outlier clamp keeps the light it takes out; 0.212, raw
/// 0.087, since path vertices take the light that specular surfaces throw; 0.197 since the
/// jitter shrinks as the camera moves the image; 0.145, raw 0.083, since a mirror's SVGF
/// history is capped at 2 frames instead of 8). Bounds 0.2 denoised, 0.15 raw. Before the pan
/// the denoised floor is closer to the reference than the raw one (0.063 and 0.085; bounds 0.1
/// and 0.15): what is left in motion is the smear of reprojected history.
#[test]
fn mirror_pan() {
    let (denoised, raw, _, _) = pan("mirror pan", stability::mirror_pan);
    let (ds, rs) = (value(&denoised, "before the pan"), value(&raw, "before the pan"));
    assert!(ds <= rs, "the still mirror's denoised floor is {:.2}x the raw error: {ds:.4} vs {rs:.4}", ds / rs);
}

/// Metric: as the mirror pan's, over a thin glass pane 2 in front of the camera with a sunlit
/// wall 4.5 behind it (`stability-glass`). Measured at 48x48: denoised 0.125, raw 0.045
/// (2.8x). It was 0.313 (7x) while the pane's history followed the pane: the reflections pass
/// now reports, for thin glass that lets through more light than it reflects, the distance to
/// the surface seen through it, so the specular history follows that surface, and TAA follows it
/// on transmissive surfaces as on metals. What is left: TAA alone takes the pane to 0.095 (as it
/// takes the wall seen directly to 0.10: the jitter against an unjittered reference), SVGF alone
/// to 0.080 (its 2-frame history for a smooth surface). Bounds 0.17 denoised, 0.1 raw, and
/// denoised within 4x raw, which the ghosting (7x) fails. Before the pan 0.052 and 0.053.
/// Since what glass lets through has a chain of its own (`svgf_temporal_let_through`, which
/// follows it while the pane's reflection follows its own hits): 0.127 during the pan, 0.053
/// before it.
#[test]
fn glass_pan() {
    let (_, _, d, r) = pan("glass pan", stability::glass_pan);
    assert!(d <= 4.0 * r, "the pane's history ghosts: during the pan denoised {d:.4} is {:.2}x raw {r:.4}", d / r);
}

/// Metric: as the glass pan's, past a rough blended pane (alpha 0.3, `stability-blend`).
/// Measured at 48x48: denoised 0.062 before the pan, 0.106 during it; the raw frame 0.0006 and
/// 0.0003 (here it has no noise to speak of: the sun's light, and nothing random on the way
/// through one blended layer), so what the bounds hold is the denoiser's own error. It was
/// 0.225 and 0.326 while the pane's history followed the pane and its a-trous footprint was the
/// pane's roughness (0.6): still, the filter blurred the wall's checkers seen through the
/// pane; moving, the history smeared them. What the pane lets through now takes the history
/// from where it was and a mirror's footprint (now in a chain of its own,
/// `svgf_temporal_let_through`: 0.043 and 0.089, where it shared the specular chain's at 0.054
/// and 0.103). Bounds 0.1 and 0.15 denoised (both of the old errors fail them), 0.01 raw.
#[test]
fn blend_pan() {
    pan("blend pan", stability::blend_pan);
}

/// Metric: as the glass pan's, past a slab of glass 0.2 thick (a volume, `stability-slab`).
/// Measured at 48x48: during the pan denoised 0.262, raw 0.092 (2.85x); 0.395 (4.3x) while
/// the slab's history followed the slab: a path that leaves the volume in the direction it
/// went in now reports how far it went, as through thin glass. Before the pan the denoised
/// slab is further from the reference than the raw one (0.163 against 0.074, the same before
/// this change): not the reprojection but TAA's jitter against the unjittered reference (TAA
/// alone 0.180, SVGF alone 0.079; the jittered frame passed through unaveraged 0.251), which
/// the slab's many sharp edges show more than the thin pane's (0.125).
/// Since the let-through chain keeps no history of what shows through at no distance while the
/// image moves (the slab's edges turn their paths; see `lens_pan`): 0.255 during the pan.
/// Bounds 0.2 and 0.32 denoised, 0.1 and 0.12 raw, and denoised within 3.5x raw in motion.
#[test]
fn slab_pan() {
    let (_, _, d, r) = pan("slab pan", stability::slab_pan);
    assert!(d <= 3.5 * r, "the slab's history ghosts: during the pan denoised {d:.4} is {:.2}x raw {r:.4}", d / r);
}

/// Metric: as the glass pan's, past a pane turned 60 degrees (`stability-glass-reflect`), a
/// third of whose light is the reflection of a brightly lit side wall and the rest the wall
/// behind, against the mean of 64 raw frames. Measured at 48x48: denoised 0.190 before the pan
/// and 0.191 during it, raw 0.409 and 0.467. While both shared the specular chain (one history,
/// following what shows through): 0.198 and 0.199; with their own chains but the give-back of
/// the clamp lost on smooth glass (common/svgf_atrous.glsl), 0.213 and 0.211. Both lights are
/// noisy here (two suns to sample) and a smooth pane keeps 2 frames of history, so the noise
/// outweighs the reprojection: this bounds the scene, it does not tell the two builds apart.
/// Bounds 0.25 denoised, 0.6 raw, and denoised within half of raw during the pan.
#[test]
fn reflecting_glass_pan() {
    let (_, _, d, r) = pan("reflecting glass pan", stability::reflecting_glass_pan);
    assert!(d <= 0.5 * r, "the reflecting pane: denoised {d:.4} is {:.2}x raw {r:.4}", d / r);
}

/// Metric: as the glass pan's, past a ball of glass (radius 0.6, IOR 1.5, `stability-lens`),
/// which shows the wall behind it turned, against the mean of 64 raw frames. Measured at
/// 48x48: denoised 0.148 before the pan and 0.209 during it, raw 0.121 and 0.110. While the
/// ball's let-through history followed its surface in motion (SVGF's 2 frames, TAA's whole
/// window), the ghost of the turned image read 0.303 (2.8x raw); TAA taking it from the frame
/// alone, 0.257. Bounds 0.2 and 0.26 denoised, 0.2 raw, and denoised within 2.4x raw.
#[test]
fn lens_pan() {
    let (_, _, d, r) = pan("lens pan", stability::lens_pan);
    assert!(d <= 2.4 * r, "the lens's image ghosts: during the pan denoised {d:.4} is {:.2}x raw {r:.4}", d / r);
}

/// Metric: as the glass pan's, past a rough thin glass pane (roughness 0.3,
/// `stability-rough-glass`), against the mean of 64 raw frames. Measured at 48x48: denoised
/// 0.090 before the pan and 0.107 during it, raw 0.633 and 0.619. While what the pane lets
/// through shared the specular chain it was 0.230 and 0.212: a let-through signal was filtered
/// as a mirror's (2 frames of history, no spatial footprint, whatever the glass's roughness);
/// its own chain filters it as far as the pane's lobe blurs it. Bounds 0.13 and 0.16 denoised,
/// 0.8 raw, and denoised within a quarter of raw.
#[test]
fn rough_glass_pan() {
    let (_, _, d, r) = pan("rough glass pan", stability::rough_glass_pan);
    assert!(d <= 0.25 * r, "the rough pane's light is not averaged: denoised {d:.4} is {:.2}x raw {r:.4}", d / r);
}

/// Metrics: the fraction of the background's light missing in the cube's 3-frame trail
/// (ghosting), and the relative error of pixels in their first frame uncovered
/// (disocclusion). Measured: ghosting denoised 0.020, raw 0.028 (the raw value is the cube's
/// real moving shadow on the wall plus noise, not a ghost); disocclusion denoised 0.154, raw
/// 0.169 (0.048 with SVGF alone: most of it is TAA's restarted history). Bounds 0.06 and 0.25. A ghost is light missing beyond what the raw frame misses: the
/// denoised trail may miss at most 2 % of the background more than the raw one.
/// The cube's light over the wall's behind it: denoised 0.0824, raw 0.0823 (bound 0.11 both).
#[test]
fn moving_object() {
    let (denoised, raw) = run("moving object", stability::moving_object);
    let (d, r) = (value(&denoised, "ghosting"), value(&raw, "ghosting"));
    assert!(d <= r + 0.02, "the denoised frame leaves a ghost: {d} of the trail's light missing, raw {r}");
}

/// The slide with the cube moved by a morph target: the same metrics, which measured the same
/// as the moving object's to four digits (2026-12-07). Without last frame's morphed positions
/// in the motion vectors, the denoised frame measured ghosting 0.308, disocclusion 0.470 and
/// the cube's light 0.126: each over its bound.
#[test]
fn morphing_object() {
    let (denoised, raw) = run("morphing object", stability::morphing_object);
    let (d, r) = (value(&denoised, "ghosting"), value(&raw, "ghosting"));
    assert!(d <= r + 0.02, "the denoised frame leaves a ghost: {d} of the trail's light missing, raw {r}");
}

/// Metrics: the fraction of the step still missing in the first frame after a light jumped
/// across the room (left half of the image), and the frames until it stays within 10 % of the
/// step. The frame that sees the lights change (FRAME_LIGHTS_CHANGED) restarts SVGF's temporal
/// history and the radiance cache's means. Measured: denoised 0.059 and 0 frames (0.16 and 3
/// frames before the restart), raw 0.024 and 0 (0.005 without the cache: the cells hold one
/// sample of the new light in that frame, and the raw left half varies by about 5 % of the
/// step from frame to frame after it). With gi at half rate: denoised 0.063, raw 0.080 (the raw
/// frame's one-frame noise against the step, from half the samples); since a pixel without
/// history starts from its window's mean, denoised 0.042 (0.071 with the 3x3 a-trous kernel
/// alone); since TAA drops its history on a change of the lights too (2026-12-05), 0.002, and
/// 0.004 once a young history's outlier clamp handed on what it takes (the same day).
/// Bounds 0.02 denoised, 0.12 raw, lag 2 frames denoised and 0 raw.
#[test]
fn moving_light() {
    run("moving light", stability::moving_light);
}

/// As `moving_light`, over the whole image, for a light switched off. Measured: denoised 0.079
/// and 0 frames (0.29 and 6 frames before SVGF's history restarted on a change of the lights),
/// raw 0.006 and 0 (0.007 without the radiance cache; 0.065 when the cache's restart traced 3
/// vertices instead of 6: the white room's deep bounces); since a pixel without history starts
/// from its window's mean, denoised 0.067; since TAA drops its history on a change of the lights
/// too (2026-12-05), 0.004, and 0.001 once a young history's outlier clamp handed on what it
/// takes (the same day). Bounds 0.02 and 2 frames denoised; 0.05 and 0 raw.
#[test]
fn light_off() {
    run("light off", stability::light_off);
}

/// `moving_light` and `light_off` with the two lights resampled in gi's reservoirs: four brighter
/// lights behind the room's back wall take the shadows chain. Measured (2026-12-04, both backends
/// alike): a moved light's first frame misses 0.097 of the step denoised (0.045 with gi at full
/// rate; the chain's light: 0.042) and the raw frame keeps 0.12 of it for two frames (at full rate
/// 0.092, the same two frames high). Nothing holds it: against the mean of 56 later frames those
/// two frames are 0.08 of the step high, and the metric's end value (frames 12..15) is 0.046 low,
/// within the spread of the radiance cache's frame-correlated noise (README, under the stability
/// table). A light switched off: denoised 0.0004, raw 0.025, 0 frames. Since TAA drops its
/// history on a change of the lights too (2026-12-05): the moved light 0.035 denoised; the
/// switched one 0.061, the first SVGF frame reading dark (its young history's outlier clamp
/// drops some of the resampled lights' bright samples), which TAA's held-back light used to
/// make up for. Since that clamp hands on what it takes (the same day): the moved light 0.063
/// (the denoised frame keeps more of the raw frame's light, and of its two high frames), the
/// switched one 0.042. Bounds 0.08 and 0.16 for the moved light's first frame, 2 frames of lag
/// both ways; the switched light's 0.06 denoised, 0.05 raw, 2 and 0 frames.
/// The lights the suite's frame resamples in gi (its renderer ranks the shadows chain by power,
/// `bench::stability`'s `renderer`), as indices into the scene's lights.
fn resampled_lights(scene: &hybrid_rt::scene::Scene) -> Vec<usize> {
    let plan = hybrid_rt::render::plan::FramePlan::for_scene(scene, 0.6, true, true, &[]);
    plan.light_order[plan.chain_punctual..].to_vec()
}

#[test]
fn resampled_lights_follow_a_move_and_a_switch() {
    let scene = hybrid_rt::scene::builtin_stability::lights_resampled();
    let resampled: Vec<&str> = resampled_lights(&scene).iter().map(|&i| scene.lights[i].name.as_str()).collect();
    assert_eq!(resampled, ["mover", "switched"], "the two lights under test must be the resampled ones");
    run("resampled move", stability::resampled_move);
    run("resampled off", stability::resampled_off);
}

/// A box closes around a light between two frames (`occluder`: a light with the shadows chain;
/// `resampled occluder`: one resampled in gi's reservoirs). Nothing about the lights changes, so
/// the light-change restart does not happen; the radiance cache's cells notice the change by
/// their last sample's shadow ray and restart, and SVGF's diffuse history restarts where a cell
/// around the pixel did. Measured (2026-12-05) over 48 frames after it, against the path
/// tracer's mean after the change, first frame and 16 frames later: raw 0.175 and 0.046
/// (chain), 0.366 and 0.100 (resampled), 0.326 and 0.195, 0.460 and 0.177 without the cells'
/// restarts (raw bounds 0.25 and 0.1, 0.45 and 0.15); denoised 0.341 and 0.079, 0.758 and
/// 0.212, 0.628 and 0.249, 0.951 and 0.446 with the cells' restarts only (bounds 0.42 and 0.12,
/// 0.85 and 0.28 then). Since SVGF's and TAA's histories also restart where the pixel's
/// resampled light went into shadow (`gi.light_lost`) and TAA's where a cell restarted:
/// 0.257 and 0.071, 0.531 and 0.159 (bounds 0.32 and 0.1, 0.62 and 0.2); 0.273 and 0.077,
/// 0.546 and 0.166 since a young SVGF history's outlier clamp hands on what it takes, some of
/// it the light the cells and reservoirs still hold. Since a restart of a tenth of the updated
/// cells tells every pixel's histories (2026-12-06): 0.156 and 0.061, 0.268 and 0.161 (bounds
/// 0.2 and 0.08, 0.35 and 0.2; without it the first frames fail them). The rest is the cells
/// no check caught, the light the cells feeding cells carry back, and the reservoirs' and the
/// light grid's own lag (README, "Stability").
#[test]
fn a_light_hidden_by_an_occluder_is_let_go_of() {
    let scene = hybrid_rt::scene::builtin_stability::lights_occluded(true);
    let resampled = resampled_lights(&scene);
    assert!(resampled.iter().any(|&i| scene.lights[i].name == "mover"), "the hidden light must be resampled");
    run("occluder", stability::occluder);
    run("resampled occluder", stability::resampled_occluder);
}

/// Metric: the flicker of frames 17-32 of the white room with nothing moving (the mean absolute
/// frame-to-frame change of a pixel's luminance over the mean luminance), lights with the
/// shadows chain and resampled. What lets a history go on a change the frame was not told of
/// must not fire where nothing changed. Measured (2026-12-06): denoised 0.0044 and 0.0037, raw
/// 0.434 and 0.557, the same to four digits without those restarts; 0.0056 and 0.0054 with
/// SVGF's diffuse history restarted at 2% of the pixels every frame (a local build). Bounds
/// 0.0052 and 0.0045 denoised, 0.6 and 0.75 raw.
#[test]
fn a_still_room_does_not_flicker() {
    run("still room", stability::still_room);
}

/// Metric: relative mean absolute luminance error of frames 9-16 of a point light gliding 6 cm
/// a frame across the white room, each against 8 raw frames at its own pose. Every frame's
/// lights differ from the last's, so SVGF restarts its history every frame and the denoised
/// frame is its spatial filter and TAA. Measured (2026-12-03): denoised 0.132, raw 0.353; a
/// per-pixel test of the history against its window's mean (kept where it still held this
/// frame's light) measured 0.131 here and failed the light-off and moving-light lags (0.35
/// and 0.24 of the step missing; README Known gaps). Bounds 0.18 denoised, 0.45 raw.
#[test]
fn gliding_light() {
    let (denoised, raw) = run("gliding light", stability::gliding_light);
    assert!(value(&denoised, "frames") < value(&raw, "frames"), "the denoised glide is worse than the raw one");
}

/// Metrics: mean luminance inside the sealed room, and on the unlit outer face at the room's
/// edge, relative to the lit face's median; the truth is 0 for both. Measured: exactly 0 for
/// both, denoised and raw. Bound 1e-4: any leak through the zero-thickness wall, or blur of
/// the lit face across the edge, shows far above it.
#[test]
fn leaking() {
    run("leaking", stability::leaking);
}

/// Metric: mean luminance of the dark room's floor beside a zero-thickness wall that the
/// radiance cache's floor cells straddle, relative to the lit room's floor; the truth is 0.
/// Measured: raw exactly 0; denoised 0.015 (SVGF blurs the lit floor across the wall's edge,
/// where both floors have the same depth and normal on screen). Bounds: raw 1e-4, which a cell
/// whose point lies in the lit room answering queries from the dark room exceeds (without the
/// cache's visibility ray the raw frame measured 0.0012); denoised 0.03.
#[test]
fn cache_leak() {
    run("cache leak", stability::cache_leak);
}

/// Metrics: shadowed fraction of the open floor under a 5-degree sun (acne), its fraction
/// darker than half the median (speckle), and the shadowed fraction of the coarse sphere's
/// pixels whose shading normal faces the light (terminator). Measured: acne 0 and 0, speckle
/// 0.0009 denoised and 0 raw, terminator 0.006 denoised and 0 raw. Bounds 0.005 (about 20
/// pixels over the 4 frames), 0.01 and 0.03.
#[test]
fn grazing_floor() {
    run("grazing floor", stability::grazing_floor);
}

/// Metrics: fraction of pixels over 10x their 5x5 median, and the peak-to-mean ratio, in a room lit
/// only through the hot spot of a tiny very bright emitter. Measured: denoised 0 and 25 (31 before
/// the clamp kept the fireflies' light, 2026-12-03; 28 since), raw 0.092 and 458 (0.104 and 425
/// since path vertices take caustics through specular surfaces, sampled as sparks; 0.114 and 528
/// since the emitters joined gi's reservoirs, 2026-12-04, and the denoised peak 7, 8.2 since the
/// later a-trous iterations stopped prefiltering the variance, 2026-12-05: the raw count
/// rose at the other sizes tried too, 0.098 -> 0.103 at 56x56 and 0.102 -> 0.114 at 64x64, not
/// explained; the emitter faces the ceiling, away from every surface in view). Without the radiance
/// cache raw measured 0.011: with it a pixel shows its gi ray's cell, and after 8 frames a cell
/// holds at most 8 cosine samples, the lucky ones of which saw the hot spot (0.043 after 32 frames,
/// as the cells fill). Bounds 0.002 and 100 denoised, 0.15 and 5000 raw (0.12 until the count
/// reached 0.114) (a peak is one sample's luck). The denoiser must remove at least 80 % of the raw
/// frame's fireflies.
#[test]
fn fireflies() {
    let (denoised, raw) = run("fireflies", stability::fireflies);
    let (d, r) = (value(&denoised, "pixels"), value(&raw, "pixels"));
    assert!(d <= 0.2 * r, "the denoiser kept fireflies: {d} of the pixels, raw {r}");
}
