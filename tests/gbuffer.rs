//! G-buffer channels against closed-form values on builtin:gbuffer-test: the depth of a plane
//! facing the camera, the normals and depth of a sphere, and the motion vector of a moving cube.

mod common;

use glam::{Vec2, Vec3};
use hybrid_rt::passes;
use hybrid_rt::passes::gbuffer::NO_ID;
use hybrid_rt::render::{Renderer, Settings};
use hybrid_rt::scene::builtin::{self, gbuffer_test_facts as facts};

const W: u32 = 128;
const H: u32 = 96;

fn renderer(ctx: &std::sync::Arc<hybrid_rt::gpu::Context>, start_time: f32) -> Renderer {
    let settings = Settings { width: W, height: H, start_time, ..Default::default() };
    let backend = common::auto_backend(ctx);
    common::renderer(ctx, builtin::gbuffer_test(), settings, backend)
}

/// Ray-sphere intersection distance along a unit direction from the origin.
fn sphere_hit(dir: Vec3) -> Option<f32> {
    let c = facts::SPHERE_CENTRE;
    let b = dir.dot(c);
    let disc = b * b - (c.length_squared() - facts::SPHERE_RADIUS * facts::SPHERE_RADIUS);
    (disc > 0.0).then(|| b - disc.sqrt())
}

#[test]
fn gbuffer_matches_analytic_plane_sphere_and_motion() {
    let ctx = common::validated_context();
    let mut r = renderer(&ctx, 0.4);
    r.render_frame().unwrap();
    r.render_frame().unwrap();
    let names = [
        passes::gbuffer::DEPTH,
        passes::gbuffer::NORMAL,
        passes::gbuffer::NORMAL_GEO,
        passes::gbuffer::MOTION,
        passes::gbuffer::IDS,
    ];
    let imgs = r.read_outputs(&names).unwrap();
    let (depth, normal, normal_geo, motion, ids) = (&imgs[0], &imgs[1], &imgs[2], &imgs[3], &imgs[4]);
    let view = r.last_view.unwrap();
    let size = Vec2::new(W as f32, H as f32);

    let (mut plane_px, mut sphere_px, mut cube_px) = (0, 0, 0);
    let mut worst_sphere_normal = 1.0f32;
    let mut worst_sphere_depth = 0.0f32;
    let mut worst_plane_depth = 0.0f32;
    for y in 0..H {
        for x in 0..W {
            let id = ids.get_u32(x, y, 0);
            assert_ne!(id, NO_ID, "the plane covers the whole view");
            let dir = view.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), size);
            let d = depth.get(x, y, 0);
            // The SVGF passes weigh their taps by the normal and this depth in one texel.
            assert_eq!(normal.get(x, y, 3), d, "gbuffer.normal's alpha is the view depth at ({x},{y})");
            match id {
                facts::PLANE_INSTANCE => {
                    plane_px += 1;
                    worst_plane_depth =
                        worst_plane_depth.max((d - facts::PLANE_DISTANCE).abs() / facts::PLANE_DISTANCE);
                    let ng = Vec3::new(normal_geo.get(x, y, 0), normal_geo.get(x, y, 1), normal_geo.get(x, y, 2));
                    assert!(ng.dot(Vec3::Z) > 0.9999, "plane geometric normal at ({x},{y}) is {ng}");
                }
                facts::SPHERE_INSTANCE => {
                    // Skip the silhouette, where the tessellated and the true sphere disagree.
                    let Some(t) = sphere_hit(dir) else { continue };
                    let hit = dir * t;
                    let n_true = (hit - facts::SPHERE_CENTRE) / facts::SPHERE_RADIUS;
                    let cos = n_true.dot(-dir);
                    if cos < 0.3 {
                        continue;
                    }
                    sphere_px += 1;
                    let n = Vec3::new(normal.get(x, y, 0), normal.get(x, y, 1), normal.get(x, y, 2));
                    worst_sphere_normal = worst_sphere_normal.min(n.normalize().dot(n_true));
                    // The radial gap between mesh and sphere, seen along the ray, grows as 1/cos.
                    worst_sphere_depth = worst_sphere_depth.max((d - (-hit.z)).abs() * cos);
                }
                facts::CUBE_INSTANCE => cube_px += 1,
                other => panic!("unexpected instance id {other}"),
            }
        }
    }
    assert!(plane_px > 1000 && sphere_px > 200 && cube_px > 20, "coverage {plane_px} {sphere_px} {cube_px}");
    assert!(worst_plane_depth < 1e-5, "plane depth relative error {worst_plane_depth}");
    // 128x64 segments: the mesh's interpolated normals stay within ~1.4 degrees of the sphere's.
    assert!(worst_sphere_normal > 0.9997, "sphere normal: worst cosine {worst_sphere_normal}");
    // The inscribed mesh lies inside the sphere by at most the sagitta of a cell in both
    // directions: r (dtheta^2 + dphi^2) / 8 with dtheta = dphi = pi / 64, i.e. 6.0e-4.
    assert!(worst_sphere_depth < 6.2e-4, "sphere depth error (radial) {worst_sphere_depth}");

    // The cube's centre moved between the two frames by exactly its projected displacement.
    let centre_at = |t: f32| Vec3::new(-facts::CUBE_SPEED * 0.5 + facts::CUBE_SPEED * t, facts::CUBE_Y, facts::CUBE_Z);
    let (t0, t1) = (r.time_of(0), r.time_of(1));
    // The front face (z + half) is what the pixel sees; its centre moves like the cube's.
    let front = |t: f32| centre_at(t) + Vec3::Z * facts::CUBE_HALF;
    let p1 = view.project(front(t1), size);
    let expected = p1 - view.project(front(t0), size);
    let (px, py) = (p1.x.floor() as u32, p1.y.floor() as u32);
    assert_eq!(ids.get_u32(px, py, 0), facts::CUBE_INSTANCE);
    let got = Vec2::new(motion.get(px, py, 0), motion.get(px, py, 1));
    assert!(expected.x > 1.0, "the cube must move on screen ({expected})");
    assert!((got - expected).length() < 0.02, "motion vector {got}, expected {expected}");
    // Static geometry has no motion.
    let plane_motion = Vec2::new(motion.get(2, 2, 0), motion.get(2, 2, 1));
    assert!(plane_motion.length() < 1e-4, "static plane moved by {plane_motion}");

    drop(r);
    common::assert_validation_clean(ctx);
}
