//! Deforming meshes (morph targets, builtin:morph-test) through both ray backends, frame after
//! frame, across the periodic rebuild of their bottom levels:
//! - primary rays agree with the G-buffer on the deformed sheet (raster and rays read the same
//!   deformed vertices);
//! - compute BVH (refit on the CPU) and ray query (BLAS updates) agree hit for hit after
//!   refits, on the frame of the rebuild and after it;
//! - the compute backend's refit tree finds exactly the hits of a tree built from scratch over
//!   the deformed vertices;
//! - the refit/rebuild schedule runs as [`REBUILD_EVERY`] says, and validation stays clean;
//! - the G-buffer's motion vectors carry the morphed motion, and none once the weights hold.
//!
//! The agreement rules (and the edge ties they allow) are those of tests/backends.rs.

mod common;

use glam::Vec3;
use hybrid_rt::accel::REBUILD_EVERY;
use hybrid_rt::accel::bvh::rays::{Ray, SplitMix64};
use hybrid_rt::accel::bvh::{SceneBvh, accept_all, closest_hit};
use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::{Context, ShaderLibrary};
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::passes::{gbuffer::NO_ID, primary_rays};
use hybrid_rt::render::{Renderer, Settings};
use hybrid_rt::scene::builtin::{self, morph_test_facts as facts};
use hybrid_rt::scene::{Pose, Scene};
use std::sync::Arc;

const W: u32 = 80;
const H: u32 = 60;
/// Enough frames for one rebuild and refits on either side of it.
const FRAMES: u32 = REBUILD_EVERY + 4;
/// Frame 0 is the first deformation (the one at upload), so deformation k happens on frame
/// k - 1: frame 2 has seen refits only, frame REBUILD_EVERY - 1 rebuilt, the last refit the
/// rebuilt tree.
const CHECKED: [u32; 3] = [2, REBUILD_EVERY - 1, FRAMES - 1];
/// Animation seconds per frame: the weights change every frame.
const FRAME_DT: f32 = 0.09;

/// Renders FRAMES frames; returns the renderer and the checked frames' images.
fn render(ctx: &Arc<Context>, backend: Backend) -> (Renderer, Vec<Vec<CpuImage>>) {
    let settings = Settings {
        width: W,
        height: H,
        primary_rays: true,
        frame_dt: FRAME_DT,
        start_time: 0.05,
        // Not under test here, and the slowest pass of a frame on lavapipe.
        denoiser: false,
        ..Default::default()
    };
    let scene = builtin::morph_test();
    let mut r = common::renderer(ctx, scene, settings, backend);
    let mut images = Vec::new();
    for frame in 0..FRAMES {
        r.render_frame().unwrap();
        if CHECKED.contains(&frame) {
            let names = [
                primary_rays::HIT,
                primary_rays::DEPTH,
                passes::gbuffer::IDS,
                passes::gbuffer::DEPTH,
                primary_rays::BARY,
            ];
            images.push(r.read_outputs(&names).unwrap());
        }
    }
    (r, images)
}

/// Primary rays see the G-buffer's instance and depth away from silhouettes, on the sheet
/// in particular.
fn check_against_gbuffer(name: &str, img: &[CpuImage]) {
    let (hit, depth, ids, gdepth) = (&img[0], &img[1], &img[2], &img[3]);
    let mut on_sheet = 0;
    for y in 0..H {
        for x in 0..W {
            if !common::interior(ids, x, y) {
                continue;
            }
            let gid = ids.get_u32(x, y, 0);
            assert_eq!(hit.get_u32(x, y, 0), gid, "{name}: instance at ({x},{y})");
            if gid == NO_ID {
                continue;
            }
            let (d, gd) = (depth.get(x, y, 0), gdepth.get(x, y, 0));
            assert!((d - gd).abs() <= 1e-3 * gd, "{name}: depth at ({x},{y}): ray {d}, G-buffer {gd}");
            on_sheet += usize::from(gid == facts::SHEET_INSTANCE);
        }
    }
    assert!(on_sheet > 300, "{name}: only {on_sheet} interior pixels on the sheet");
}

/// The renderer's scene with the sheet deformed as at `pose`: what a BVH built from scratch
/// for that frame would see.
fn deformed(scene: &Scene, pose: &Pose) -> Scene {
    let mut s = scene.clone();
    for morph in &scene.morphs {
        let mesh = &mut s.meshes[morph.mesh as usize];
        mesh.vertices = morph.deform(&mesh.vertices, &morph.weights_at(pose.time));
    }
    s
}

/// Rays from near the camera at random points of the sheet's (deformed) extent.
fn sheet_rays(n: usize) -> Vec<Ray> {
    let mut rng = SplitMix64::new(11);
    (0..n)
        .map(|_| {
            let target = Vec3::new(
                (rng.unit() * 2.0 - 1.0) * facts::HALF * 1.1,
                (rng.unit() * 2.0 - 1.0) * facts::HALF * 1.1,
                facts::SHEET_Z,
            );
            let origin = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, 0.0);
            Ray { origin: origin.to_array(), tmin: 0.0, dir: (target - origin).to_array(), tmax: 1e30 }
        })
        .collect()
}

#[test]
fn deforming_mesh_agrees_across_backends_refits_and_rebuilds() {
    let ctx = common::validated_context();
    let shaders = ShaderLibrary::embedded();
    let (mut rc, compute) = render(&ctx, Backend::Compute);
    let stats = rc.scene_gpu.accel.stats();
    assert_eq!((stats.blas_refits, stats.blas_rebuilds), (u64::from(FRAMES) - 1, 1), "compute refit schedule");
    eprintln!("compute: BVH refit {:.3} ms, rebuild {:.3} ms (CPU)", stats.blas_refit_ms, stats.blas_rebuild_ms);
    for (frame, img) in CHECKED.iter().zip(&compute) {
        check_against_gbuffer(&format!("compute, frame {frame}"), img);
    }
    // The GPU traversal of the refit tree against a CPU tree built from scratch.
    let pose = rc.pose_of(FRAMES - 1);
    let fresh = SceneBvh::build(&deformed(&rc.scene, &pose), &pose);
    let rays = sheet_rays(4096);
    let (hits, _) = rc.trace_rays(&shaders, &rays, false, 0).unwrap();
    let mut on_sheet = 0;
    for (ray, hit) in rays.iter().zip(&hits) {
        let cpu = closest_hit(&fresh, ray.origin.into(), ray.dir.into(), ray.tmin, ray.tmax, 0xff, accept_all);
        let gpu = hit.is_hit().then_some((hit.instance, hit.primitive));
        assert_eq!(gpu, cpu.map(|h| (h.instance, h.primitive)), "refit tree vs fresh tree: {ray:?}");
        if let Some(h) = cpu {
            assert!((h.t - hit.t).abs() <= 1e-5 * h.t, "t {} vs {}", hit.t, h.t);
            on_sheet += usize::from(h.instance == facts::SHEET_INSTANCE);
        }
    }
    assert!(on_sheet > 2000, "only {on_sheet} of {} rays hit the sheet", rays.len());
    let compute_hits = hits;
    drop(rc);
    if ctx.caps.supports_ray_query() {
        let (mut rq, query) = render(&ctx, Backend::RayQuery);
        let stats = rq.scene_gpu.accel.stats();
        assert_eq!((stats.blas_refits, stats.blas_rebuilds), (u64::from(FRAMES) - 1, 1), "BLAS update schedule");
        eprintln!(
            "ray query: BLAS update {:.3} ms, rebuild {:.3} ms (GPU)",
            stats.blas_refit_ms, stats.blas_rebuild_ms
        );
        for ((frame, c), q) in CHECKED.iter().zip(&compute).zip(&query) {
            check_against_gbuffer(&format!("ray query, frame {frame}"), q);
            let ties = common::compare_primary_hits(&format!("frame {frame}"), (&c[0], &c[4]), (&q[0], &q[4]), false);
            assert!(ties < (W * H / 50) as usize, "frame {frame}: {ties} edge ties");
        }
        let (hits, _) = rq.trace_rays(&shaders, &rays, false, 0).unwrap();
        let mut ties = 0;
        for ((ray, a), b) in rays.iter().zip(&compute_hits).zip(&hits) {
            assert_eq!(a.is_hit(), b.is_hit(), "{ray:?}");
            if a.is_hit() {
                assert!((a.t - b.t).abs() <= 1e-4 * a.t, "{ray:?}: t {} vs {}", a.t, b.t);
                if (a.instance, a.primitive) != (b.instance, b.primitive) {
                    let edge = |h: &hybrid_rt::render::ray_batch::HitRecord| h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-4;
                    assert!(edge(a) && edge(b), "{ray:?}: different triangles away from an edge");
                    ties += 1;
                }
            }
        }
        assert!(ties < 20, "{ties} edge ties of {} rays", rays.len());
    } else {
        assert_ne!(std::env::var("CI").as_deref(), Ok("true"), "CI machines have Mesa >= 24.1 with ray query");
        eprintln!("ray query unavailable on this device: checked the compute backend only");
    }
    common::assert_validation_clean(ctx);
}

/// The project's glTF with morph targets (tools/make_morph_scene.py) loads as a deforming
/// mesh whose animated weights move its vertices and normals.
#[test]
fn gltf_morph_asset_loads_as_a_deforming_mesh() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/morph/morph_wave.gltf");
    let scene = hybrid_rt::scene::load_gltf(&path, &Default::default()).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(scene.is_animated());
    assert_eq!(scene.morphs.len(), 1);
    let morph = &scene.morphs[0];
    assert_eq!((morph.targets.len(), morph.channels.len()), (2, 1));
    assert!(morph.targets.iter().all(|t| t.normals.len() == t.positions.len()));
    // Weights (0, 0) at t = 0 and (1, 0) at t = 0.5: the bump alone.
    let base = &scene.meshes[morph.mesh as usize].vertices;
    assert_eq!(morph.deform(base, &morph.weights_at(0.0)), *base);
    let bumped = morph.deform(base, &morph.weights_at(0.5));
    let centre = bumped.iter().map(|v| v.position[2]).fold(0.0, f32::max);
    assert!((centre - 0.5).abs() < 1e-3, "bump height {centre}");
    assert!(bumped.iter().any(|v| v.normal != [0.0, 0.0, 1.0]));
}

/// The sheet's one morph target moves it sideways by this much at weight 1.
const SHIFT: f32 = 2.0;

/// Morphing is in the G-buffer's motion vectors, as skinning is: the morph test's sheet with one
/// target that shifts it along x (weight 0 -> 1 over the first second, then held), so that its
/// vertices move within the mesh while its node stands still. While it moves, the motion at a
/// sheet pixel is where the CPU's morph puts that point now against last frame (2.6 px a
/// frame here); the back wall does not move; once the weight holds, the sheet's motion is 0
/// again. Without last frame's morphed positions the sheet's motion read 0 while it moved.
#[test]
fn morph_motion_is_in_the_motion_vectors() {
    let mut scene = builtin::morph_test();
    let morph = &mut scene.morphs[0];
    let count = scene.meshes[morph.mesh as usize].vertices.len();
    morph.targets =
        vec![hybrid_rt::scene::MorphTarget { positions: vec![Vec3::X * SHIFT; count], normals: Vec::new() }];
    morph.weights = vec![0.0];
    morph.channels[0].times = vec![0.0, 1.0, facts::PERIOD];
    morph.channels[0].values = vec![0.0, 1.0, 1.0];
    let settings =
        Settings { width: W, height: H, frame_dt: 0.1, start_time: 0.05, denoiser: false, ..Default::default() };
    let ctx = common::validated_context();
    let mut r = common::renderer(&ctx, scene, settings, Backend::Compute);
    // Vertex (column 8, row 24) of the sheet: x = -1 at rest, in view wherever the shift puts it.
    let vertex = (facts::CELLS / 2 * (facts::CELLS + 1) + 8) as usize;
    let names = [passes::gbuffer::IDS, passes::gbuffer::MOTION];
    let check = |r: &mut Renderer, frames: u32| {
        common::render_frames(r, frames);
        let img = r.read_outputs(&names).unwrap();
        let morph = &r.scene.morphs[0];
        let base = &r.scene.meshes[morph.mesh as usize].vertices;
        let size = glam::Vec2::new(W as f32, H as f32);
        let at = |f: u32| {
            let pose = r.pose_of(f);
            let p = Vec3::from(morph.deform(base, &morph.weights_at(pose.time))[vertex].position);
            let world = pose.world[r.scene.instances[facts::SHEET_INSTANCE as usize].node as usize].transform_point3(p);
            let clip = r.view_of(&pose).view_proj() * world.extend(1.0);
            clip.truncate().truncate() / clip.w * 0.5 * size
        };
        let frame = r.frame_index - 1;
        let (now, before) = (at(frame), at(frame - 1));
        let expected = now - before;
        let pixel = now + size * 0.5;
        let (x, y) = (pixel.x as u32, pixel.y as u32);
        assert_eq!(img[0].get_u32(x, y, 0), facts::SHEET_INSTANCE, "frame {frame}: the point lands on the sheet");
        let motion = glam::Vec2::new(img[1].get(x, y, 0), img[1].get(x, y, 1));
        let wall = glam::Vec2::new(img[1].get(2, 2, 0), img[1].get(2, 2, 1));
        assert_eq!(img[0].get_u32(2, 2, 0), facts::BACK_INSTANCE);
        assert!(wall.length() < 1e-3, "frame {frame}: the wall moves {wall}");
        eprintln!("frame {frame}: sheet motion {motion} px at ({x},{y}), the CPU's morph {expected} px");
        (motion, expected)
    };
    // Frames 0..3 (t = 0.05 .. 0.35): moving.
    let (motion, expected) = check(&mut r, 4);
    assert!(expected.length() > 1.0, "the sheet moves {expected} px a frame: too little to test");
    assert!((motion - expected).length() < 0.1 * expected.length() + 0.3, "moving: {motion} against {expected}");
    // Frame 11 (t = 1.15): the weight has held at 1 since t = 1.
    let (motion, expected) = check(&mut r, 8);
    assert_eq!(expected, glam::Vec2::ZERO);
    assert!(motion.length() < 1e-3, "held: the sheet still moves {motion}");
    drop(r);
    common::assert_validation_clean(ctx);
}
