//! Shared test helpers: a validated Vulkan context, the shared scenes folder, temp folders.
#![allow(dead_code)] // each test binary uses a different subset of these helpers

use hybrid_rt::gpu::{Context, ContextOptions};
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes::gbuffer::NO_ID;
use std::path::PathBuf;
use std::sync::Arc;

/// A context with the Khronos validation layer and synchronization validation on.
pub fn validated_context() -> Arc<Context> {
    Context::new(&ContextOptions { validate: true, ..Default::default() }).expect("Vulkan context with validation")
}

/// Tears the context down and fails the test if the validation layer said anything, teardown
/// (leak reports) included.
pub fn assert_validation_clean(ctx: Arc<Context>) {
    let log = ctx.validation.clone();
    assert_eq!(Arc::strong_count(&ctx), 1, "something still holds the Vulkan context");
    drop(ctx);
    let messages = log.messages();
    assert!(messages.is_empty(), "validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"));
}

/// ../shared/scenes beside the repository. Missing: the test fails under CI=true and is
/// skipped (returns None, with a note) elsewhere.
pub fn shared_scenes() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("{} is missing: CI must provide ../shared/scenes beside the checkout", dir.display());
    }
    eprintln!("skipping: {} is missing (set CI=true to make this a failure)", dir.display());
    None
}

/// A fresh empty folder under the system temp dir, unique to this test process and name.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hybrid-rt-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Copies a folder tree (`to` is created).
pub fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dest = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

pub fn default_scene() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/default/cornell.gltf")
}

/// The backend `--backend auto` would pick on this device.
pub fn auto_backend(ctx: &Context) -> hybrid_rt::backend::Backend {
    hybrid_rt::backend::resolve(&ctx.caps, hybrid_rt::backend::BackendChoice::Auto).expect("auto backend").0
}

/// A renderer of `scene` with the embedded shaders and the scene's default camera.
pub fn renderer(
    ctx: &Arc<Context>,
    scene: hybrid_rt::scene::Scene,
    settings: hybrid_rt::render::Settings,
    backend: hybrid_rt::backend::Backend,
) -> hybrid_rt::render::Renderer {
    let shaders = hybrid_rt::gpu::ShaderLibrary::embedded();
    hybrid_rt::render::Renderer::new(ctx, &shaders, scene, settings, &hybrid_rt::render::CameraChoice::Default, backend)
        .expect("renderer")
}

/// Renders `frames` frames.
pub fn render_frames(r: &mut hybrid_rt::render::Renderer, frames: u32) {
    for _ in 0..frames {
        r.render_frame().expect("frame");
    }
}

/// A root node at `translation`, unrotated and unscaled (test scenes built in code).
pub fn node(name: &str, translation: glam::Vec3) -> hybrid_rt::scene::Node {
    hybrid_rt::scene::Node {
        name: name.into(),
        parent: None,
        translation,
        rotation: glam::Quat::IDENTITY,
        scale: glam::Vec3::ONE,
    }
}

/// True when all 8 neighbours see the same instance in the G-buffer (not a silhouette).
pub fn interior(ids: &CpuImage, x: u32, y: u32) -> bool {
    if x == 0 || y == 0 || x + 1 >= ids.width || y + 1 >= ids.height {
        return false;
    }
    let id = ids.get_u32(x, y, 0);
    (-1i32..=1).all(|dy| (-1i32..=1).all(|dx| ids.get_u32((x as i32 + dx) as u32, (y as i32 + dy) as u32, 0) == id))
}

/// Compares two backends' primary hits (`primary_rays.hit` and `.bary` of each); returns the
/// number of ties.
///
/// Equal means: the same instance and triangle at t within 1e-4 relative. A tie is a ray
/// through an edge (both hits within 1e-4 of an edge in barycentric terms) that the backends
/// give to different triangles, of one instance or of two instances sharing the edge, at the
/// same t; or a ray grazing an outer edge that one backend hits and the other misses. With
/// `coincident_surfaces`, two instances hit at the same t (within 1e-6) anywhere are a tie too
/// (scenes with coplanar overlapping instances). Ties are allowed and counted; anything else
/// fails.
pub fn compare_primary_hits(
    name: &str,
    (hit_a, bary_a): (&CpuImage, &CpuImage),
    (hit_b, bary_b): (&CpuImage, &CpuImage),
    coincident_surfaces: bool,
) -> usize {
    let on_edge = |bary: &CpuImage, x, y| {
        let (u, v) = (bary.get(x, y, 0), bary.get(x, y, 1));
        u.min(v).min(1.0 - u - v) < 1e-4
    };
    let mut ties = 0;
    for y in 0..hit_a.height {
        for x in 0..hit_a.width {
            let (ia, ib) = (hit_a.get_u32(x, y, 0), hit_b.get_u32(x, y, 0));
            if ia == NO_ID && ib == NO_ID {
                continue;
            }
            if ia == NO_ID || ib == NO_ID {
                let bary = if ia == NO_ID { bary_b } else { bary_a };
                assert!(on_edge(bary, x, y), "{name}: only one backend hits at ({x},{y}), away from any edge");
                ties += 1;
                continue;
            }
            let (ta, tb) = (f32::from_bits(hit_a.get_u32(x, y, 2)), f32::from_bits(hit_b.get_u32(x, y, 2)));
            assert!((ta - tb).abs() <= 1e-4 * ta.abs().max(tb.abs()), "{name}: t differs at ({x},{y}): {ta} vs {tb}");
            if ia != ib || hit_a.get_u32(x, y, 1) != hit_b.get_u32(x, y, 1) {
                let coincident = coincident_surfaces && ia != ib && (ta - tb).abs() <= 1e-6 * ta.abs();
                assert!(
                    coincident || (on_edge(bary_a, x, y) && on_edge(bary_b, x, y)),
                    "{name}: different triangles at ({x},{y}) away from an edge (instances {ia}/{ib}, t {ta}/{tb})"
                );
                ties += 1;
            }
        }
    }
    ties
}
