//! Every scene in ../shared/scenes and the default scene loads and renders on the device, with
//! the validation layer silent, and the picture is not empty.

mod common;

use hybrid_rt::gpu::ShaderLibrary;
use hybrid_rt::render::{self, CameraChoice, Renderer, Settings};
use hybrid_rt::scene::{LoadOptions, Scene, load_gltf};
use std::path::{Path, PathBuf};

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

/// Renders one frame and returns the fraction of pixels that are not black.
fn render_coverage(ctx: &std::sync::Arc<hybrid_rt::gpu::Context>, scene: Scene) -> f32 {
    let settings = Settings { width: 64, height: 48, ..Default::default() };
    let backend = common::auto_backend(ctx);
    let mut r =
        Renderer::new(ctx, &ShaderLibrary::embedded(), scene, settings, &CameraChoice::Default, backend).unwrap();
    r.render_frame().unwrap();
    let ids = r.read_output("gbuffer.ids").unwrap();
    let mut hit = 0;
    for y in 0..ids.height {
        for x in 0..ids.width {
            if ids.get_u32(x, y, 0) != hybrid_rt::passes::gbuffer::NO_ID {
                hit += 1;
            }
        }
    }
    let _ = r.read_output(render::DISPLAY_OUTPUT).unwrap();
    hit as f32 / ids.pixel_count() as f32
}

#[test]
fn every_shared_scene_loads_and_renders() {
    let Some(dir) = common::shared_scenes() else { return };
    let files = gltf_files(&dir);
    assert!(files.len() >= 8, "expected the shared scenes, found {files:?}");
    let ctx = common::validated_context();
    for f in files {
        let scene = load_gltf(&f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.triangle_count() > 0, "{}: no triangles", f.display());
        let coverage = render_coverage(&ctx, scene);
        assert!(coverage > 0.01, "{}: the picture is empty (coverage {coverage})", f.display());
    }
    common::assert_validation_clean(ctx);
}

#[test]
fn default_scene_loads_and_renders() {
    let scene = load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap();
    assert!(scene.warnings.is_empty(), "the project's own scene must load without warnings: {:?}", scene.warnings);
    assert!(scene.is_animated(), "the default scene has a moving object");
    assert!(!scene.lights.is_empty() && scene.materials.iter().any(|m| m.is_emissive()));
    let ctx = common::validated_context();
    let coverage = render_coverage(&ctx, scene);
    assert!(coverage > 0.5, "the Cornell box should fill most of the view (coverage {coverage})");
    common::assert_validation_clean(ctx);
}
