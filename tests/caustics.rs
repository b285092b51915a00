//! Light that reaches a surface only by way of a mirror. An emissive panel faces up, a mirror
//! ceiling above it throws the panel's light down, and the camera looks at a diffuse floor
//! beside the panel, which the panel never lights directly (its back is dark and does not emit).
//!
//! The hybrid frame's paths meet such light only through a specular vertex's BRDF-sampled ray
//! (`common/radiance_cache.glsl`, RC_SPECULAR_ROUGHNESS): a light sample through a mirror's
//! near-delta lobe almost never lands. Before specular vertices took it that way, the floor
//! here was black in the hybrid frame, and the default scene's floor, lit in part by its mirror
//! block, was 9% darker than the reference.

mod common;

use glam::{Quat, Vec3, Vec4};
use hybrid_rt::gpu::Context;
use hybrid_rt::metrics;
use hybrid_rt::passes::pathtrace;
use hybrid_rt::render::{Environment, RenderMode, Renderer, Settings};
use hybrid_rt::scene::{Camera, Instance, Material, Scene, builtin};
use std::sync::Arc;

const SIZE: u32 = 32;
const FRAMES: u32 = 48;
const AVERAGED_FROM: u32 = 17;

/// A 20 x 20 diffuse floor at y = 0, a 20 x 20 mirror facing it at y = 3, a 3 x 3 panel at
/// height 1 beside the camera's view emitting upward, and the camera at height 2 looking
/// straight down at the floor through 0.5 rad.
fn scene() -> Scene {
    let mut s = Scene { name: "mirror-caustic".into(), ..Default::default() };
    let mut add = |name: &str, material: Material, mesh: hybrid_rt::scene::Mesh, at: Vec3| {
        let index = s.materials.len() as u32;
        s.materials.push(Material { name: name.into(), ..material });
        s.meshes.push(hybrid_rt::scene::Mesh { material: index, ..mesh });
        s.nodes.push(common::node(name, at));
        s.instances.push(Instance { mesh: s.meshes.len() as u32 - 1, node: s.nodes.len() as u32 - 1 });
    };
    let floor = Material {
        base_color_factor: Vec4::new(0.5, 0.5, 0.5, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Default::default()
    };
    let mirror = Material {
        base_color_factor: Vec4::new(0.9, 0.9, 0.9, 1.0),
        metallic_factor: 1.0,
        roughness_factor: 0.0,
        ..Default::default()
    };
    let panel = Material {
        base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive_factor: Vec3::splat(10.0),
        ..Default::default()
    };
    // builtin::quad faces u x v.
    add("floor", floor, builtin::quad(Vec3::ZERO, Vec3::Z * 20.0, Vec3::X * 20.0, 0), Vec3::ZERO);
    add("mirror", mirror, builtin::quad(Vec3::ZERO, Vec3::X * 20.0, Vec3::Z * 20.0, 0), Vec3::Y * 3.0);
    add("panel", panel, builtin::quad(Vec3::ZERO, Vec3::Z * 3.0, Vec3::X * 3.0, 0), Vec3::new(3.0, 1.0, 0.0));
    s.nodes.push(hybrid_rt::scene::Node {
        rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        ..common::node("camera", Vec3::Y * 2.0)
    });
    s.cameras.push(Camera {
        name: "down".into(),
        yfov: 0.5,
        aspect_ratio: None,
        znear: 0.01,
        zfar: Some(100.0),
        node: s.nodes.len() as u32 - 1,
    });
    s
}

/// Mean luminance of the image: the reference after `spp` samples, or the raw hybrid frame (no
/// denoiser, no TAA) averaged over frames AVERAGED_FROM..=FRAMES.
fn mean_luminance(ctx: &Arc<Context>, reference_spp: Option<u32>) -> f64 {
    let settings = Settings {
        width: SIZE,
        height: SIZE,
        environment: Environment::Constant(Vec3::ZERO),
        denoiser: false,
        taa: false,
        mode: match reference_spp {
            Some(_) => RenderMode::Reference { seed: 1, max_bounces: 8 },
            None => RenderMode::default(),
        },
        ..Default::default()
    };
    let mut r: Renderer = common::renderer(ctx, scene(), settings, common::auto_backend(ctx));
    let luminance = |r: &mut Renderer, output| {
        let img = r.read_output(output).unwrap();
        let px = img.as_f32().unwrap();
        let sum: f64 = px
            .chunks_exact(4)
            .map(|p| {
                assert!(p[..3].iter().all(|c| c.is_finite()), "a pixel is not finite");
                metrics::luminance(p[0], p[1], p[2]) as f64
            })
            .sum();
        sum / (px.len() / 4) as f64
    };
    if let Some(spp) = reference_spp {
        common::render_frames(&mut r, spp);
        return luminance(&mut r, pathtrace::COLOR);
    }
    let mut sum = 0.0;
    for frame in 1..=FRAMES {
        r.render_frame().unwrap();
        if frame >= AVERAGED_FROM {
            let output = r.hdr_output();
            sum += luminance(&mut r, output);
        }
    }
    sum / (FRAMES - AVERAGED_FROM + 1) as f64
}

/// Measured (lavapipe, 2026-12-03): see the assertion's message.
#[test]
fn a_mirror_throws_an_area_light_onto_the_floor() {
    let ctx = common::validated_context();
    let reference = mean_luminance(&ctx, Some(256));
    let hybrid = mean_luminance(&ctx, None);
    eprintln!("floor lit only through a mirror: hybrid frame (raw) {hybrid:.4}, reference {reference:.4}");
    assert!(reference > 0.05, "the reference sees too little light to compare: {reference}");
    assert!(
        (hybrid / reference - 1.0).abs() <= 0.08,
        "hybrid frame {hybrid:.4} against the reference's {reference:.4}: {:.3}x",
        hybrid / reference
    );
    common::assert_validation_clean(ctx);
}
