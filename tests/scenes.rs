//! Every scene in ../shared/scenes and the default scene loads and renders on the device, with
//! the validation layer silent, and the lit picture is right: no NaN or infinity anywhere, the
//! surfaces not black, and their mean luminance within `FACTOR` of a short render of the
//! reference path tracer at the same size and camera, limited to the paths the hybrid frame
//! models (direct light and the gi pass's bounces: a closed Cornell box gets several times
//! more light from longer paths, a known gap, see README). Scenes that bring no light of their own
//! are lit by the default light (a daylight sky, src/render/default_light.rs); turned off
//! (`--no-default-light`, a black environment) such a scene is black but for its emission.

mod common;

use glam::{Quat, Vec3};
use hybrid_rt::gpu::Context;
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::passes::gbuffer::NO_ID;
use hybrid_rt::passes::pathtrace;
use hybrid_rt::render::{self, Environment, RenderMode, Settings, View};
use hybrid_rt::scene::{Instance, LoadOptions, Material, Node, Scene, builtin, load_gltf};
use std::path::{Path, PathBuf};
use std::sync::Arc;

const W: u32 = 64;
const H: u32 = 48;
/// Hybrid frames on a frozen pose (denoiser on): the histories settle enough for a mean.
const FRAMES: u32 = 6;
/// Samples per pixel of the reference: its mean over a few hundred surface pixels is within a
/// few percent at this count. Glints need more than most: at 8 spp LightsPunctualLamp's mean
/// read 2.85 where 256 spp give 2.42.
const REFERENCE_SPP: u32 = 32;
/// The hybrid frame's mean surface luminance must lie within this factor of the reference's,
/// either way. It denoises one sample per pixel, so it is not the reference, but a missing
/// sun (71% of the default light on a horizontal surface), a doubled light (2) or a black
/// environment (0) fall outside. Measured on this machine (lavapipe, 2026-12-05; the test
/// prints them): 0.79 to 1.29 over the shared scenes and the default scene, lowest on
/// LightsPunctualLamp (the bulb's glints on the normal-mapped brass, smaller than a pixel:
/// README, known gaps) and DamagedHelmet (0.92; 0.87 before a young SVGF history's outlier
/// clamp handed on what it takes, 0.74 before the reflections pass sampled the sun, against an
/// 8-spp reference), highest on the closed nvpro Cornell box (1.29: the reference stops at two
/// bounces, the radiance cache models more). Before shadow rays crossed thin glass the lamp
/// measured 1.59. Since the shadows chain is ranked by the first view (2026-12-06) the lamp
/// reads 0.965: the same four of its five lights have the chain, in another order, so the
/// reference draws its light samples differently, and its 32 spp now read 2.07 where they read
/// 2.45 (256 spp: 2.42); the frame itself measured 2.00 against 1.97 before.
const FACTOR: f64 = 1.5;
/// Mean surface luminance below which a picture counts as black.
const BLACK: f64 = 0.01;

fn gltf_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            out.extend(gltf_files(&p));
        } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn luminance(p: &[f32]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// What one render of a scene shows.
struct Picture {
    /// The linear HDR image (RGBA).
    hdr: CpuImage,
    /// gbuffer.ids of the hybrid frame (instance, material), or of the hybrid frame the
    /// reference is compared on.
    ids: CpuImage,
    /// gbuffer.metal_rough of that hybrid frame (metallic, roughness, ...).
    metal_rough: CpuImage,
    lighting: render::default_light::Lighting,
    /// The camera of the last frame.
    view: View,
}

impl Picture {
    /// Pixels that see a surface.
    fn surface(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.ids.height)
            .flat_map(move |y| (0..self.ids.width).map(move |x| (x, y)))
            .filter(|&(x, y)| self.ids.get_u32(x, y, 0) != NO_ID)
    }

    fn coverage(&self) -> f64 {
        self.surface().count() as f64 / self.ids.pixel_count() as f64
    }

    fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        [self.hdr.get(x, y, 0), self.hdr.get(x, y, 1), self.hdr.get(x, y, 2)]
    }

    /// Mean luminance over the pixels of `pixels`.
    fn mean_over(&self, pixels: impl Iterator<Item = (u32, u32)>) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for (x, y) in pixels {
            sum += luminance(&self.pixel(x, y));
            n += 1;
        }
        sum / n.max(1) as f64
    }

    fn non_finite(&self) -> usize {
        self.hdr.as_f32().unwrap().iter().filter(|v| !v.is_finite()).count()
    }
}

/// `FRAMES` hybrid frames of `scene` at a frozen pose with environment `env`.
fn hybrid(ctx: &Arc<Context>, scene: Scene, env: Environment) -> Picture {
    hybrid_sized(ctx, scene, env, (W, H), FRAMES)
}

/// `frames` hybrid frames of `scene` at `size`, at a frozen pose with environment `env`.
fn hybrid_sized(
    ctx: &Arc<Context>,
    scene: Scene,
    env: Environment,
    (width, height): (u32, u32),
    frames: u32,
) -> Picture {
    let settings = Settings { width, height, frame_dt: 0.0, environment: env, ..Default::default() };
    let mut r = common::renderer(ctx, scene, settings, common::auto_backend(ctx));
    common::render_frames(&mut r, frames);
    let mut images = r.read_outputs(&[r.hdr_output(), passes::gbuffer::IDS, passes::gbuffer::METAL_ROUGH]).unwrap();
    let metal_rough = images.remove(2);
    let ids = images.remove(1);
    let hdr = images.remove(0);
    Picture { hdr, ids, metal_rough, lighting: r.lighting.clone(), view: r.last_view.unwrap() }
}

/// `REFERENCE_SPP` samples of the reference path tracer, read on the hybrid frame's pixels.
fn reference(ctx: &Arc<Context>, scene: Scene, env: Environment, like: &Picture) -> Picture {
    reference_spp(ctx, scene, env, like, REFERENCE_SPP)
}

/// `spp` samples of the reference path tracer at the size of `like`, read on its pixels.
fn reference_spp(ctx: &Arc<Context>, scene: Scene, env: Environment, like: &Picture, spp: u32) -> Picture {
    let settings = Settings {
        width: like.ids.width,
        height: like.ids.height,
        environment: env,
        // Two scattering events, what the frame computes without its radiance cache. The cache
        // adds the further bounces (tests/radiance_cache.rs checks them against Mitsuba), so
        // the frame may come out brighter than this reference, within FACTOR. Against a
        // 16-bounce reference the frame is 0.43 on nvpro-cornell-box although the medians
        // agree (0.0115 and 0.0114): half of the gap sits in 20 pixels at the rim of its
        // ceiling light, where the reference's light grows with every bounce (16 at 4 bounces,
        // 42 at 16) and the frame shows 2.9: light trapped in the gap between the light and the
        // ceiling, whose rays are too short for the cache to answer. The reference is right there
        // (tests/mitsuba.rs checks it against Mitsuba); the frame is not (the README's known gaps).
        mode: RenderMode::Reference { seed: 3, max_bounces: 2 },
        ..Default::default()
    };
    let mut r = common::renderer(ctx, scene, settings, common::auto_backend(ctx));
    common::render_frames(&mut r, spp);
    let hdr = r.read_output(pathtrace::COLOR).unwrap();
    Picture {
        hdr,
        ids: like.ids.clone(),
        metal_rough: like.metal_rough.clone(),
        lighting: r.lighting.clone(),
        view: like.view,
    }
}

/// Renders `scene` both ways and checks the picture; returns a line for the log.
fn check_lit_picture(ctx: &Arc<Context>, name: &str, scene: Scene) -> String {
    let frame = hybrid(ctx, scene.clone(), Environment::DefaultLight);
    let coverage = frame.coverage();
    assert!(coverage > 0.01, "{name}: the picture is empty (coverage {coverage})");
    assert_eq!(frame.non_finite(), 0, "{name}: NaN or infinity in the hybrid frame");
    let ours = frame.mean_over(frame.surface());
    assert!(ours > BLACK, "{name}: the surfaces are black (mean luminance {ours}; {})", frame.lighting.note);
    let truth = reference(ctx, scene, Environment::DefaultLight, &frame);
    assert_eq!(truth.non_finite(), 0, "{name}: NaN or infinity in the reference");
    let theirs = truth.mean_over(frame.surface());
    let ratio = ours / theirs;
    assert!(
        (1.0 / FACTOR..=FACTOR).contains(&ratio),
        "{name}: mean surface luminance {ours:.4} against the reference's {theirs:.4} (ratio {ratio:.3}, bound \
         {FACTOR}x either way; {})",
        frame.lighting.note
    );
    format!(
        "{name}: coverage {coverage:.2}, mean surface luminance {ours:.4} (reference {theirs:.4}, ratio {ratio:.3}), \
         default light {}",
        frame.lighting.default_light
    )
}

#[test]
fn every_shared_scene_renders_a_lit_picture_close_to_the_reference() {
    let Some(dir) = common::shared_scenes() else { return };
    let files = gltf_files(&dir);
    assert!(files.len() >= 8, "expected the shared scenes, found {files:?}");
    let ctx = common::validated_context();
    let mut lines = Vec::new();
    for f in &files {
        let scene = load_gltf(f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.triangle_count() > 0, "{}: no triangles", f.display());
        let name = f.strip_prefix(&dir).unwrap_or(f).display().to_string();
        lines.push(check_lit_picture(&ctx, &name, scene));
        eprintln!("{}", lines.last().unwrap());
    }
    common::assert_validation_clean(ctx);
}

#[test]
fn default_scene_loads_and_renders_a_lit_picture() {
    let scene = load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap();
    assert!(scene.warnings.is_empty(), "the project's own scene must load without warnings: {:?}", scene.warnings);
    assert!(scene.is_animated(), "the default scene has a moving object");
    assert!(!scene.lights.is_empty() && scene.materials.iter().any(|m| m.is_emissive()));
    let ctx = common::validated_context();
    let frame = hybrid(&ctx, scene.clone(), Environment::DefaultLight);
    assert!(!frame.lighting.default_light, "the Cornell box has its own lights: {}", frame.lighting.note);
    assert!(frame.coverage() > 0.5, "the Cornell box should fill most of the view (coverage {})", frame.coverage());
    eprintln!("{}", check_lit_picture(&ctx, "default scene", scene));
    common::assert_validation_clean(ctx);
}

/// The range the hybrid frame's glossy metal must read in, as a share of the reference's light.
/// Measured on this machine (lavapipe, 2026-12-04): 0.90. Before the light sample, `render` and
/// `reference` at this size gave 0.65 where they now give 0.87. Most of the rest is lost in the
/// filters, which take a highlight of a pixel or two for an outlier: 0.91 without TAA, 0.95
/// without SVGF's outlier clamp too. One raw frame averages 0.96 over eight seeds, and the
/// reference's own mean moves by 3% between seeds at 128 spp (320x240).
const GLOSSY_SUN_RANGE: std::ops::RangeInclusive<f64> = 0.8..=1.15;

/// Glossy metal under the default light keeps the sun's highlight. The sun is a small, very
/// bright target that a glossy lobe's own rays find rarely, and the denoiser's outlier clamp
/// cuts the rare hits: over the metal spheres of MetalRoughSpheresNoTextures that the
/// reflections pass traces (roughness above a mirror's, at most its cut-off) the hybrid frame
/// read 0.65 of the reference's light before that pass took a light sample of the emitters and
/// the environment (shaders-glsl/reflections.comp).
#[test]
fn glossy_metal_keeps_the_default_suns_highlight() {
    let Some(dir) = common::shared_scenes() else { return };
    let file = dir.join("khronos/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb");
    let scene = load_gltf(&file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let ctx = common::validated_context();
    let frame = hybrid_sized(&ctx, scene.clone(), Environment::DefaultLight, (160, 120), 16);
    assert!(frame.lighting.default_light, "{}", frame.lighting.note);
    let cutoff = Settings::default().reflections.roughness_cutoff as f64;
    let glossy: Vec<(u32, u32)> = frame
        .surface()
        .filter(|&(x, y)| {
            let (metallic, roughness) = (frame.metal_rough.get(x, y, 0) as f64, frame.metal_rough.get(x, y, 1) as f64);
            metallic > 0.5 && roughness > 0.05 && roughness <= cutoff
        })
        .collect();
    assert!(glossy.len() > 300, "the glossy metal spheres are in view ({} pixels)", glossy.len());
    assert_eq!(frame.non_finite(), 0);
    let truth = reference_spp(&ctx, scene, Environment::DefaultLight, &frame, 64);
    let (ours, theirs) = (frame.mean_over(glossy.iter().copied()), truth.mean_over(glossy.iter().copied()));
    let ratio = ours / theirs;
    eprintln!(
        "glossy metal under the default light: {ours:.4} against the reference's {theirs:.4} (ratio {ratio:.3}, {} pixels)",
        glossy.len()
    );
    assert!(
        GLOSSY_SUN_RANGE.contains(&ratio),
        "glossy metal under the default light: {ours:.4} against the reference's {theirs:.4} (ratio {ratio:.3}, \
         outside {GLOSSY_SUN_RANGE:?})"
    );
    common::assert_validation_clean(ctx);
}

/// Emission of the small lamp in `lightless_scene`: far too weak to light it (see the rule).
const LAMP: f32 = 0.5;

/// A sphere on a floor and a small, weak emissive tile, no punctual light, no camera.
fn lightless_scene() -> Scene {
    let mut s = Scene { name: "lightless".into(), ..Default::default() };
    let diffuse = |name: &str, c: f32| Material {
        name: name.into(),
        base_color_factor: glam::Vec4::new(c, c, c, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.8,
        ..Default::default()
    };
    s.materials.push(diffuse("floor", 0.6));
    s.materials.push(diffuse("ball", 0.8));
    s.materials.push(Material { emissive_factor: Vec3::splat(LAMP), ..diffuse("tile", 0.0) });
    s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X * 4.0, Vec3::NEG_Z * 4.0, 0));
    s.meshes.push(builtin::uv_sphere(0.8, 32, 16, 1));
    s.meshes.push(builtin::quad(Vec3::new(1.2, 0.01, 0.8), Vec3::X * 0.4, Vec3::NEG_Z * 0.4, 2));
    for (i, t) in [Vec3::ZERO, Vec3::new(0.0, 0.8, 0.0), Vec3::ZERO].into_iter().enumerate() {
        s.nodes.push(Node {
            name: format!("n{i}"),
            parent: None,
            translation: t,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        });
        s.instances.push(Instance { mesh: i as u32, node: i as u32 });
    }
    s
}

fn scene_bounds(s: &Scene) -> (Vec3, Vec3) {
    s.bounds(&s.evaluate(0.0))
}

#[test]
fn a_lightless_scene_gets_the_default_light_and_no_default_light_leaves_only_emission() {
    let ctx = common::validated_context();
    let scene = lightless_scene();
    let lit = hybrid(&ctx, scene.clone(), Environment::DefaultLight);
    assert!(lit.lighting.default_light, "{}", lit.lighting.note);
    // No camera in the file: the framing camera has all of the content in view, and not as a
    // speck (its bounding sphere fills the vertical field of view).
    let (lo, hi) = scene_bounds(&lightless_scene());
    let size = glam::Vec2::new(W as f32, H as f32);
    let corners: Vec<glam::Vec2> = (0..8)
        .map(|i| {
            let c = Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]);
            lit.view.project(c, size)
        })
        .collect();
    assert!(corners.iter().all(|p| p.cmpge(glam::Vec2::ZERO).all() && p.cmple(size).all()), "{corners:?}");
    let span = corners.iter().fold(glam::Vec2::splat(f32::MAX), |a, p| a.min(*p));
    let span = corners.iter().fold(glam::Vec2::ZERO, |a, p| a.max(*p)) - span;
    assert!(span.x > size.x / 3.0 || span.y > size.y / 3.0, "the content spans {span} of {size}");
    let material = |p: &Picture, (x, y): (u32, u32)| p.ids.get_u32(x, y, 1);
    let plain = |p: &Picture| p.surface().filter(|&px| material(p, px) != 2).collect::<Vec<_>>();
    let lit_mean = lit.mean_over(plain(&lit).into_iter());
    assert!(lit_mean > 0.1, "under the default light the floor and ball are lit: mean {lit_mean}");
    eprintln!("default light: {} (surfaces' mean luminance {lit_mean:.4})", lit.lighting.note);

    // What `--no-default-light` gives: a black environment.
    let off = hybrid(&ctx, scene, Environment::Constant(Vec3::ZERO));
    assert!(!off.lighting.default_light && off.lighting.note.contains("off"), "{}", off.lighting.note);
    let dark = off.mean_over(plain(&off).into_iter());
    assert!(dark < 0.01 * lit_mean, "without the default light only the weak tile lights them: {dark} vs {lit_mean}");
    let tiles: Vec<(u32, u32)> = off.surface().filter(|&px| material(&off, px) == 2).collect();
    assert!(!tiles.is_empty(), "the emissive tile is in view");
    let glow = off.mean_over(tiles.into_iter());
    assert!((glow - LAMP as f64).abs() < 0.05 * LAMP as f64, "the tile shows its emission {LAMP}: {glow}");
    assert_eq!(off.non_finite(), 0);
    eprintln!("--no-default-light: surfaces' mean luminance {dark:.5}, the emissive tile {glow:.4}");
    common::assert_validation_clean(ctx);
}

#[test]
fn plan_says_whether_the_default_light_is_used_and_the_flag_turns_it_off() {
    let Some(dir) = common::shared_scenes() else { return };
    let helmet = dir.join("khronos/DamagedHelmet/DamagedHelmet.glb");
    let plan = |extra: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
            .arg("plan")
            .arg(&helmet)
            .args(extra)
            .output()
            .expect("run hybrid-rt plan");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let on = plan(&[]);
    assert!(on.contains("lighting: default light: a daylight sky"), "{on}");
    let off = plan(&["--no-default-light"]);
    assert!(off.contains("lighting: black environment: the default light is off"), "{off}");
    let sky = plan(&["--sky", "1,1,1"]);
    assert!(sky.contains("lighting: constant environment 1,1,1"), "{sky}");
    let cornell = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt")).arg("plan").output().unwrap();
    let cornell = String::from_utf8_lossy(&cornell.stdout);
    assert!(cornell.contains("no default light: the scene has"), "{cornell}");
}

#[test]
fn plan_gives_no_default_light_to_a_camera_in_a_closed_room() {
    // The Mitsuba diffuse box (in this repository): its panel is too weak for the emission rule,
    // but its camera is in a closed room, where a sky would light nothing.
    let room = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/mitsuba/diffuse_box/scene.gltf");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hybrid-rt")).args(["plan", room]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let room = String::from_utf8_lossy(&out.stdout);
    assert!(room.contains("too weak") && room.contains("the camera is in a closed room"), "{room}");
}
