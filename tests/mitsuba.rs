//! The reference path tracer against an independent renderer: Mitsuba 3 with the glTF 2.0
//! Appendix B material written as a Mitsuba BSDF plugin (tools/mitsuba_reference.py, which also
//! writes the scenes). For each scene under tests/mitsuba/ the committed files are the glTF
//! scene, two Mitsuba renders with different seeds (mitsuba-a.exr, mitsuba-b.exr), one at 16
//! times their spp (mitsuba-converged.exr) and mitsuba.json (the scene's file, size and spp).
//! One scene nobody here wrote, the nvpro Cornell box, is read from ../shared/scenes (its folder
//! here holds only the renders). This test renders `hybrid-rt reference` on the same glTF at
//! the same size and spp as the pair, and requires:
//!
//! - mean luminance within 0.5 % of Mitsuba's converged render: the energy of the material
//!   model, bounce after bounce in a closed room (the noise of the mean at 512 spp is about
//!   0.13 %, so the bound is ~4 standard errors). The nvpro box's light also lights a narrow
//!   gap above it, where light bounces many times: a noisy mean even at its 8192 spp (four
//!   seeds of hybrid-rt's reference at 2048 spp spread over 0.988..1.007 of Mitsuba's, a
//!   standard deviation of about 0.9 %, so about 0.45 % at 8192), so its bound is 2 %;
//! - HDR-FLIP against mitsuba-a within 1.15 x Mitsuba's own noise floor, the HDR-FLIP between
//!   its two renders: per pixel, no more different from Mitsuba than Mitsuba is from itself.
//!
//! And that the comparison can fail: the energy-coupled model (`--brdf coupled`) misses the
//! luminance bound in the closed diffuse box.
//!
//! CI needs no Mitsuba: it only reads the committed EXRs.

mod common;

use hybrid_rt::gpu::Context;
use hybrid_rt::image_io::{self, CpuImage};
use hybrid_rt::metrics::{self, HdrFlipOptions};
use hybrid_rt::passes::pathtrace;
use hybrid_rt::render::{Environment, RenderMode, Settings};
use hybrid_rt::scene::{LoadOptions, load_gltf};
use hybrid_rt::world::brdf::BrdfModel;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Mean luminance may differ from Mitsuba's by this fraction.
const LUMINANCE_TOLERANCE: f64 = 0.005;
/// The nvpro Cornell box's bound (its mean is noisier: see the module's comment).
const NVPRO_LUMINANCE_TOLERANCE: f64 = 0.02;
/// HDR-FLIP against Mitsuba may exceed Mitsuba's own noise floor by this factor.
const FLIP_FACTOR: f64 = 1.15;

fn scene_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mitsuba").join(name)
}

/// What the Mitsuba renders in `dir` were made of (mitsuba.json).
struct MitsubaSettings {
    /// The glTF file, from the repository's root (../shared/scenes/... for a shared scene).
    scene: PathBuf,
    size: (u32, u32),
    spp: u32,
}

fn mitsuba_settings(dir: &Path) -> MitsubaSettings {
    let path = dir.join("mitsuba.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let size = &json["size"];
    let (scene, w, h, spp) = (json["scene"].as_str(), size[0].as_u64(), size[1].as_u64(), json["spp"].as_u64());
    match (scene, w, h, spp) {
        (Some(scene), Some(w), Some(h), Some(spp)) => MitsubaSettings {
            scene: Path::new(env!("CARGO_MANIFEST_DIR")).join(scene),
            size: (w as u32, h as u32),
            spp: spp as u32,
        },
        _ => panic!("{}: expected scene, size [w, h] and spp", path.display()),
    }
}

fn mean_luminance(img: &CpuImage) -> f64 {
    let px = img.as_f32().unwrap();
    let sum: f64 = px.chunks_exact(img.channels).map(|p| metrics::luminance(p[0], p[1], p[2]) as f64).sum();
    sum / img.pixel_count() as f64
}

/// hybrid-rt's reference of the glTF file at Mitsuba's size and spp.
fn render_reference(ctx: &Arc<Context>, file: &Path, brdf: BrdfModel, spp: u32, size: (u32, u32)) -> CpuImage {
    let scene = load_gltf(file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"));
    let settings = Settings {
        width: size.0,
        height: size.1,
        // The rooms are closed; a black environment says so whatever the default sky is.
        environment: Environment::Constant(glam::Vec3::ZERO),
        mode: RenderMode::Reference { seed: 11, max_bounces: 256 },
        brdf,
        ..Default::default()
    };
    let backend = common::auto_backend(ctx);
    let mut r = common::renderer(ctx, scene, settings, backend);
    common::render_frames(&mut r, spp);
    r.read_output(pathtrace::COLOR).unwrap()
}

struct Comparison {
    luminance_ratio: f64,
    flip: f64,
    noise_floor: f64,
}

fn compare(ctx: &Arc<Context>, name: &str, brdf: BrdfModel, spp_override: Option<u32>) -> Comparison {
    let dir = scene_dir(name);
    let settings = mitsuba_settings(&dir);
    let (w, h) = settings.size;
    let spp = spp_override.unwrap_or(settings.spp);
    let read = |f: &str| image_io::read_exr_rgba(&dir.join(f)).unwrap_or_else(|e| panic!("{e:#}"));
    let (a, b, converged) = (read("mitsuba-a.exr"), read("mitsuba-b.exr"), read("mitsuba-converged.exr"));
    for img in [&a, &b, &converged] {
        assert_eq!((img.width, img.height), (w, h), "{name}: EXR sizes differ from mitsuba.json");
    }
    let start = Instant::now();
    let ours = render_reference(ctx, &settings.scene, brdf, spp, (w, h));
    let seconds = start.elapsed().as_secs_f64();
    let mitsuba_mean = mean_luminance(&converged);
    let opts = HdrFlipOptions::default();
    let c = Comparison {
        luminance_ratio: mean_luminance(&ours) / mitsuba_mean,
        flip: metrics::hdr_flip(&a, &ours, &opts).unwrap().mean,
        noise_floor: metrics::hdr_flip(&a, &b, &opts).unwrap().mean,
    };
    eprintln!(
        "{name} ({brdf:?}, {w}x{h}, {spp} spp, {seconds:.1} s): mean luminance {:.5} vs Mitsuba {mitsuba_mean:.5} \
         (ratio {:.4}; Mitsuba's two renders at this spp: {:.4}, {:.4}); HDR-FLIP {:.4} vs Mitsuba's noise floor \
         {:.4} ({:.3}x)",
        mean_luminance(&ours),
        c.luminance_ratio,
        mean_luminance(&a) / mitsuba_mean,
        mean_luminance(&b) / mitsuba_mean,
        c.flip,
        c.noise_floor,
        c.flip / c.noise_floor
    );
    c
}

fn check_scene(name: &str, luminance_tolerance: f64) {
    let ctx = common::validated_context();
    {
        let c = compare(&ctx, name, BrdfModel::Gltf, None);
        assert!(
            (c.luminance_ratio - 1.0).abs() <= luminance_tolerance,
            "{name}: mean luminance {:.4} x Mitsuba's (tolerance {luminance_tolerance})",
            c.luminance_ratio
        );
        assert!(
            c.flip <= FLIP_FACTOR * c.noise_floor,
            "{name}: HDR-FLIP against Mitsuba {:.4} > {FLIP_FACTOR} x its noise floor {:.4}",
            c.flip,
            c.noise_floor
        );
    }
    common::assert_validation_clean(ctx);
}

#[test]
fn diffuse_box_matches_mitsuba() {
    check_scene("diffuse_box", LUMINANCE_TOLERANCE);
}

#[test]
fn glossy_blocks_match_mitsuba() {
    check_scene("glossy_blocks", LUMINANCE_TOLERANCE);
}

#[test]
fn textured_scene_matches_mitsuba() {
    check_scene("textured", LUMINANCE_TOLERANCE);
}

/// A real glTF file nobody here wrote: interleaved buffers, a blended sphere (alpha 0.05, which
/// Mitsuba's `volpath` crosses as hybrid-rt does, paths and shadow rays), double-sided
/// materials, and a box-shaped light 0.27 m under the ceiling whose top face lights the gap
/// above it. In that gap light bounces many times: the hybrid frame reads 0.76 of this mean
/// (Known gaps), the reference must not.
#[test]
fn nvpro_cornell_box_matches_mitsuba() {
    if common::shared_scenes().is_none() {
        return;
    }
    check_scene("nvpro_cornell_box", NVPRO_LUMINANCE_TOLERANCE);
}

/// The luminance bound can fail: the energy-coupled diffuse lobe, not the specification's,
/// puts more light into the closed box than Mitsuba's Appendix B material. A quarter of the
/// samples suffice to see it (the bound is 0.5 %, the difference several times that).
#[test]
fn the_coupled_model_misses_the_bound() {
    let ctx = common::validated_context();
    {
        let spp = mitsuba_settings(&scene_dir("diffuse_box")).spp;
        let c = compare(&ctx, "diffuse_box", BrdfModel::Coupled, Some((spp / 4).max(1)));
        assert!(
            (c.luminance_ratio - 1.0).abs() > LUMINANCE_TOLERANCE,
            "the coupled model's mean luminance is within {LUMINANCE_TOLERANCE} of Mitsuba's Appendix B material \
             (ratio {:.4}): the comparison cannot tell the models apart",
            c.luminance_ratio
        );
    }
    common::assert_validation_clean(ctx);
}
