//! Skinned meshes (glTF skins, skinned on the GPU by the `skinning` pass) through both ray
//! backends:
//! - the G-buffer of a skinned mesh matches a static copy of the scene whose mesh holds the
//!   CPU-skinned vertices (`SkinnedMesh::skin`), on builtin:skin-test and on the Khronos
//!   sample models RiggedSimple and BrainStem (../shared/scenes);
//! - primary rays agree with the G-buffer, and the compute BVH (refit on the CPU) and ray query
//!   (BLAS updates) agree hit for hit, frame after frame across the periodic rebuild;
//! - the G-buffer's motion vectors carry the skinned motion: a point near the arm's tip moves
//!   on screen as the CPU-skinned point projected at this frame and the last one;
//! - validation (with synchronization validation) stays clean.

mod common;

use glam::Vec3;
use hybrid_rt::accel::REBUILD_EVERY;
use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::Context;
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes::{gbuffer, gbuffer::NO_ID, primary_rays};
use hybrid_rt::render::{Renderer, Settings};
use hybrid_rt::scene::builtin_skin::{facts, skin_test};
use hybrid_rt::scene::{Scene, load_gltf};
use std::sync::Arc;

const W: u32 = 96;
const H: u32 = 72;
/// Animation seconds per frame: the joints move every frame.
const FRAME_DT: f32 = 0.08;
const START: f32 = 0.2;

fn settings(start_time: f32) -> Settings {
    Settings {
        width: W,
        height: H,
        primary_rays: true,
        frame_dt: FRAME_DT,
        start_time,
        // Not under test here, and the slowest pass of a frame on lavapipe.
        denoiser: false,
        ..Default::default()
    }
}

fn backends(ctx: &Context) -> Vec<Backend> {
    if ctx.caps.supports_ray_query() {
        vec![Backend::Compute, Backend::RayQuery]
    } else {
        assert_ne!(std::env::var("CI").as_deref(), Ok("true"), "CI machines have Mesa >= 24.1 with ray query");
        eprintln!("ray query unavailable on this device: checking the compute backend only");
        vec![Backend::Compute]
    }
}

/// `scene` with every skinned mesh replaced by its CPU-skinned vertices at `time`, and no skins.
fn cpu_skinned(scene: &Scene, time: f32) -> Scene {
    let mut s = scene.clone();
    let pose = scene.evaluate(time);
    for sk in &scene.skinned {
        let joints = scene.skins[sk.skin as usize].joint_matrices(&pose, sk.node);
        let mesh = &mut s.meshes[sk.mesh as usize];
        mesh.vertices = sk.skin(&mesh.vertices, &joints);
    }
    s.skinned.clear();
    s.skins.clear();
    s
}

const OUTPUTS: [hybrid_rt::graph::Output; 6] =
    [gbuffer::IDS, gbuffer::DEPTH, gbuffer::NORMAL, gbuffer::MOTION, primary_rays::HIT, primary_rays::BARY];

fn frame_images(
    ctx: &Arc<Context>,
    scene: Scene,
    backend: Backend,
    start_time: f32,
    frames: u32,
) -> (Renderer, Vec<CpuImage>) {
    let mut r = common::renderer(ctx, scene, settings(start_time), backend);
    common::render_frames(&mut r, frames);
    let images = r.read_outputs(&OUTPUTS).unwrap();
    (r, images)
}

/// Skinned G-buffer against the CPU-skinned copy's: where both see the same instance, depth
/// and shading normal agree (everywhere away from silhouettes; at silhouette pixels, where a
/// sample may fall on a fold of the mesh, all but 2%). The instances differ only at
/// silhouettes. Returns the number of pixels compared on skinned instances.
fn compare_gbuffers(name: &str, scene: &Scene, skinned: &[CpuImage], cpu: &[CpuImage]) -> usize {
    let is_skinned = |id: u32| scene.instances.get(id as usize).is_some_and(|i| scene.skinned_of(i.mesh).is_some());
    let (mut on_skin, mut edge, mut edge_differs) = (0, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let interior = common::interior(&skinned[0], x, y);
            let (a, b) = (skinned[0].get_u32(x, y, 0), cpu[0].get_u32(x, y, 0));
            if a != b {
                assert!(!interior, "{name}: instance at ({x},{y}): {a} GPU-skinned, {b} CPU-skinned");
                continue;
            }
            if a == NO_ID {
                continue;
            }
            let (da, db) = (skinned[1].get(x, y, 0), cpu[1].get(x, y, 0));
            let n = |img: &CpuImage| Vec3::new(img.get(x, y, 0), img.get(x, y, 1), img.get(x, y, 2));
            let (na, nb) = (n(&skinned[2]), n(&cpu[2]));
            let same = (da - db).abs() <= 1e-4 * db && (na - nb).length() < 2e-3;
            if interior {
                assert!(same, "{name}: at ({x},{y}): depth {da} / normal {na} GPU-skinned, {db} / {nb} CPU-skinned");
            } else {
                edge += 1;
                edge_differs += usize::from(!same);
            }
            on_skin += usize::from(is_skinned(a));
        }
    }
    assert!(edge_differs * 50 <= edge, "{name}: {edge_differs} of {edge} silhouette pixels differ");
    on_skin
}

#[test]
fn skinned_arm_matches_cpu_skinning_and_the_backends_agree() {
    let ctx = common::validated_context();
    // Enough frames for refits, one rebuild and refits after it.
    let frames = REBUILD_EVERY + 4;
    let time = START + (frames - 1) as f32 * FRAME_DT;
    let mut per_backend = Vec::new();
    for backend in backends(&ctx) {
        let name = format!("{backend:?}");
        let (r, img) = frame_images(&ctx, skin_test(), backend, START, frames);
        let stats = r.scene_gpu.accel.stats();
        assert_eq!((stats.blas_refits, stats.blas_rebuilds), (u64::from(frames) - 1, 1), "{name}: refit schedule");
        // The CPU-skinned copy, drawn statically at the last frame's time.
        let (_, cpu) = frame_images(&ctx, cpu_skinned(&r.scene, time), backend, time, 1);
        let on_arm = compare_gbuffers(&name, &r.scene, &img, &cpu);
        assert!(on_arm > 400, "{name}: only {on_arm} pixels on the arm");
        // Primary rays see the G-buffer's instance and depth.
        for y in 0..H {
            for x in 0..W {
                if common::interior(&img[0], x, y) {
                    assert_eq!(
                        img[4].get_u32(x, y, 0),
                        img[0].get_u32(x, y, 0),
                        "{name}: ray vs G-buffer at ({x},{y})"
                    );
                }
            }
        }
        check_motion(&name, &r, &img);
        eprintln!(
            "{name}: {on_arm} arm pixels match CPU skinning; refit {:.3} ms, rebuild {:.3} ms",
            stats.blas_refit_ms, stats.blas_rebuild_ms
        );
        per_backend.push(img);
    }
    if let [c, q] = per_backend.as_slice() {
        let ties = common::compare_primary_hits("skin-test", (&c[4], &c[5]), (&q[4], &q[5]), false);
        assert!(ties < (W * H / 50) as usize, "{ties} edge ties");
    }
    common::assert_validation_clean(ctx);
}

/// The motion at the pixel where a point on the arm's front face near its tip lands now is
/// where it was last frame, both from CPU skinning; the wall does not move.
fn check_motion(name: &str, r: &Renderer, img: &[CpuImage]) {
    let scene = &r.scene;
    let sk = &scene.skinned[0];
    let skin = &scene.skins[sk.skin as usize];
    // The front face's ring near the tip: its two vertices' midpoint, on the arm's centre line.
    let ring = facts::SEGMENTS - 3;
    let (a, b) = ((2 * ring) as usize, (2 * ring + 1) as usize);
    let base = &scene.meshes[sk.mesh as usize].vertices;
    let mid = (Vec3::from(base[a].position) + Vec3::from(base[b].position)) * 0.5;
    let frame = r.frame_index - 1;
    let at = |f: u32| {
        let pose = r.pose_of(f);
        let m = pose.world[sk.node as usize] * sk.matrix(a, &skin.joint_matrices(&pose, sk.node));
        let clip = r.view_of(&pose).view_proj() * m.transform_point3(mid).extend(1.0);
        let ndc = clip.truncate().truncate() / clip.w;
        ndc * 0.5 * glam::Vec2::new(W as f32, H as f32)
    };
    let (now, before) = (at(frame), at(frame - 1));
    let expected = now - before;
    let pixel = now + glam::Vec2::new(W as f32, H as f32) * 0.5;
    let (x, y) = (pixel.x as u32, pixel.y as u32);
    assert_eq!(img[0].get_u32(x, y, 0), facts::ARM_INSTANCE, "{name}: the tip point lands on the arm at ({x},{y})");
    let motion = glam::Vec2::new(img[3].get(x, y, 0), img[3].get(x, y, 1));
    assert!(expected.length() > 1.0, "{name}: the tip moves {expected} px a frame: too little to test");
    assert!(
        (motion - expected).length() < 0.1 * expected.length() + 0.3,
        "{name}: motion at the tip ({x},{y}) {motion}, CPU skinning says {expected}"
    );
    let wall = glam::Vec2::new(img[3].get(2, 2, 0), img[3].get(2, 2, 1));
    assert_eq!(img[0].get_u32(2, 2, 0), facts::WALL_INSTANCE);
    assert!(wall.length() < 1e-3, "{name}: the wall moves {wall}");
    eprintln!("{name}: tip motion {motion} px, CPU skinning {expected} px");
}

/// Pixels whose instance or depth (beyond 0.1%) differs between two G-buffers.
fn count_moved(a: &[CpuImage], b: &[CpuImage]) -> usize {
    let mut moved = 0;
    for y in 0..H {
        for x in 0..W {
            let (ia, ib) = (a[0].get_u32(x, y, 0), b[0].get_u32(x, y, 0));
            let (da, db) = (a[1].get(x, y, 0), b[1].get(x, y, 0));
            moved += usize::from(ia != ib || (ia != NO_ID && (da - db).abs() > 1e-3 * db));
        }
    }
    moved
}

/// Well into the sample models' animations (both loop within a few seconds).
const KHRONOS_START: f32 = 0.9;

/// Khronos sample models with skins: the G-buffer after a few animated frames matches the
/// CPU-skinned copy, on both backends.
#[test]
fn khronos_skinned_models_match_cpu_skinning() {
    let Some(shared) = common::shared_scenes() else {
        return;
    };
    let ctx = common::validated_context();
    for model in ["RiggedSimple/RiggedSimple.glb", "BrainStem/BrainStem.glb"] {
        let path = shared.join("khronos").join(model);
        let scene = load_gltf(&path, &Default::default()).unwrap();
        assert!(!scene.skinned.is_empty(), "{model}: no skinned mesh loaded");
        assert!(scene.warnings.iter().all(|w| !w.contains("skin")), "{model}: {:?}", scene.warnings);
        for backend in backends(&ctx) {
            let name = format!("{model}, {backend:?}");
            let frames = 3;
            let (r, img) = frame_images(&ctx, scene.clone(), backend, KHRONOS_START, frames);
            let time = KHRONOS_START + (frames - 1) as f32 * FRAME_DT;
            let (_, cpu) = frame_images(&ctx, cpu_skinned(&r.scene, time), backend, time, 1);
            let on_skin = compare_gbuffers(&name, &r.scene, &img, &cpu);
            assert!(on_skin > 100, "{name}: only {on_skin} pixels on skinned meshes");
            // The pose differs from the bind pose: skinning did move the picture.
            let mut bind_pose = r.scene.clone();
            bind_pose.skinned.clear();
            let (_, bind) = frame_images(&ctx, bind_pose, backend, time, 1);
            let moved = count_moved(&img, &bind);
            assert!(moved > 20, "{name}: only {moved} pixels differ from the bind pose");
            eprintln!("{name}: {on_skin} skinned pixels match CPU skinning; {moved} differ from the bind pose");
        }
    }
    common::assert_validation_clean(ctx);
}
