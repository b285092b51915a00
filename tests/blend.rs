//! alphaMode BLEND as coverage: a blended surface covers the share alpha of each point and the
//! rest of the light passes straight through it. In a furnace of radiance 1, a quad seen
//! head-on must show alpha times what the same quad shows opaque, plus (1 - alpha) times the
//! environment behind it: in the reference path tracer (which decides per path) and in the
//! hybrid frame (whose reflections pass traces what lies behind).

mod common;

use glam::{Vec3, Vec4};
use hybrid_rt::gpu::Context;
use hybrid_rt::passes::pathtrace;
use hybrid_rt::render::{Environment, RenderMode, Settings};
use hybrid_rt::scene::{AlphaMode, Camera, Instance, Material, Scene, builtin};
use std::sync::Arc;

const SIZE: u32 = 16;

/// A dark, rough quad facing the camera 3 away, seen through 0.02 rad: every pixel sees it.
fn quad_scene(alpha: f32, mode: AlphaMode) -> Scene {
    let mut s = Scene { name: "blend".into(), ..Default::default() };
    s.materials.push(Material {
        name: "veil".into(),
        base_color_factor: Vec4::new(0.2, 0.2, 0.2, alpha),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        alpha_mode: mode,
        ..Default::default()
    });
    s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X * 4.0, Vec3::Y * 4.0, 0));
    s.nodes.push(common::node("quad", Vec3::ZERO));
    s.nodes.push(common::node("camera", Vec3::new(0.0, 0.0, 3.0)));
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.cameras.push(Camera {
        name: "front".into(),
        yfov: 0.02,
        aspect_ratio: None,
        znear: 0.01,
        zfar: Some(100.0),
        node: 1,
    });
    s
}

/// Mean luminance of the image after `frames` frames in a furnace of radiance 1.
fn mean(ctx: &Arc<Context>, scene: Scene, reference: bool, frames: u32) -> f64 {
    let settings = Settings {
        width: SIZE,
        height: SIZE,
        environment: Environment::Constant(Vec3::ONE),
        mode: if reference { RenderMode::Reference { seed: 1, max_bounces: 16 } } else { RenderMode::default() },
        ..Default::default()
    };
    let mut r = common::renderer(ctx, scene, settings, common::auto_backend(ctx));
    common::render_frames(&mut r, frames);
    let output = if reference { pathtrace::COLOR } else { r.hdr_output() };
    let img = r.read_output(output).unwrap();
    let px = img.as_f32().unwrap();
    let sum: f64 = px.chunks_exact(4).map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum();
    sum / (px.len() / 4) as f64
}

#[test]
fn blended_surfaces_cover_their_alpha() {
    let ctx = common::validated_context();
    for (reference, frames, name) in [(true, 256, "reference"), (false, 32, "hybrid frame")] {
        let opaque = mean(&ctx, quad_scene(1.0, AlphaMode::Opaque), reference, frames);
        for alpha in [0.25f32, 0.7] {
            let blended = mean(&ctx, quad_scene(alpha, AlphaMode::Blend), reference, frames);
            let a = alpha as f64;
            let want = a * opaque + (1.0 - a);
            eprintln!("{name}: alpha {alpha}: {blended:.4}, coverage says {want:.4} (opaque {opaque:.4})");
            assert!((blended - want).abs() < 0.01 * want, "{name}, alpha {alpha}: {blended:.4} vs {want:.4}");
        }
    }
    common::assert_validation_clean(ctx);
}
