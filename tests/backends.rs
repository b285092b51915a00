//! The two ray backends against each other and against the rasteriser:
//! - primary rays through pixel centres agree with the G-buffer (instance id, depth);
//! - compute BVH and ray query agree hit for hit (instance, primitive, t), and their shadow
//!   masks are equal;
//! - rays aimed exactly at shared edges and vertices of closed meshes never leak;
//! - alpha-masked geometry casts shadows only where its texture is opaque.
//!
//! Ties: a ray through an edge shared by two triangles may report either triangle (same
//! instance and t); such pixels are counted as ties, not as disagreements, and bounded.

mod common;

use glam::Vec3;
use hybrid_rt::accel::bvh::rays::Ray;
use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::{Context, ShaderLibrary};
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::passes::{gbuffer::NO_ID, primary_rays};
use hybrid_rt::render::{Renderer, Settings};
use hybrid_rt::scene::{LoadOptions, Scene, builtin, load_gltf};
use std::sync::Arc;

const W: u32 = 96;
const H: u32 = 72;

fn render(ctx: &Arc<Context>, scene: Scene, backend: Backend) -> Renderer {
    let settings = Settings { width: W, height: H, primary_rays: true, start_time: 0.5, ..Default::default() };
    let mut r = common::renderer(ctx, scene, settings, backend);
    r.render_frame().unwrap();
    r
}

fn images(r: &mut Renderer) -> Vec<CpuImage> {
    r.read_outputs(&[
        primary_rays::HIT,
        primary_rays::DEPTH,
        passes::gbuffer::IDS,
        passes::gbuffer::DEPTH,
        r.shadow_visibility(),
        primary_rays::BARY,
    ])
    .unwrap()
}

/// Instances whose material is alpha-tested. The rasteriser picks their texture's mip level
/// from screen derivatives and rays read level 0, so near the cutoff the two can disagree on
/// alpha; the G-buffer comparison skips them (alpha testing itself is checked against the
/// texture by `masked_shadows_follow_the_alpha_texture`, and backend against backend).
fn masked_instances(r: &Renderer) -> Vec<u32> {
    let s = &r.scene;
    (0..s.instances.len() as u32)
        .filter(|&i| {
            let mesh = &s.meshes[s.instances[i as usize].mesh as usize];
            s.materials[mesh.material as usize].alpha_mode.cutoff().is_some()
        })
        .collect()
}

/// Primary rays agree with the G-buffer away from silhouettes.
fn check_against_gbuffer(name: &str, img: &[CpuImage], masked: &[u32]) {
    let (hit, depth, ids, gdepth) = (&img[0], &img[1], &img[2], &img[3]);
    let mut checked = 0;
    for y in 0..H {
        for x in 0..W {
            if !common::interior(ids, x, y) {
                continue;
            }
            let gid = ids.get_u32(x, y, 0);
            if masked.contains(&gid) || masked.contains(&hit.get_u32(x, y, 0)) {
                continue;
            }
            assert_eq!(hit.get_u32(x, y, 0), gid, "{name}: instance at ({x},{y})");
            if gid == NO_ID {
                continue;
            }
            let (d, gd) = (depth.get(x, y, 0), gdepth.get(x, y, 0));
            assert!((d - gd).abs() <= 1e-3 * gd, "{name}: depth at ({x},{y}): ray {d}, G-buffer {gd}");
            checked += 1;
        }
    }
    assert!(checked > 100, "{name}: only {checked} interior pixels");
}

/// Compares two backends' primary hits (see `common::compare_primary_hits`; coincident
/// surfaces of two instances, as in some models, are ties) and their shadow masks, which must
/// be equal; returns the number of ties.
fn check_backends_agree(name: &str, a: &[CpuImage], b: &[CpuImage]) -> usize {
    let ties = common::compare_primary_hits(name, (&a[0], &a[5]), (&b[0], &b[5]), true);
    // Shadow rays start from the G-buffer, so both backends trace identical shadow rays.
    let mut shadow_diff = 0;
    for y in 0..H {
        for x in 0..W {
            for c in 0..4 {
                if a[4].get(x, y, c) != b[4].get(x, y, c) {
                    shadow_diff += 1;
                }
            }
        }
    }
    assert_eq!(shadow_diff, 0, "{name}: shadow masks differ in {shadow_diff} samples");
    eprintln!("{name}: backends agree; {ties} edge ties of {} pixels", W * H);
    ties
}

fn scenes() -> Vec<(String, Scene)> {
    let mut list = vec![
        ("default".to_string(), load_gltf(&common::default_scene(), &LoadOptions::default()).unwrap()),
        ("gbuffer-test".to_string(), builtin::gbuffer_test()),
    ];
    if let Some(dir) = common::shared_scenes() {
        for f in [
            "khronos/DamagedHelmet/DamagedHelmet.glb",
            "khronos/SimpleInstancing/SimpleInstancing.glb",
            "nvpro-cornell-box/cornellBox.gltf",
            "khronos/AlphaBlendModeTest/AlphaBlendModeTest.glb",
        ] {
            list.push((f.to_string(), load_gltf(&dir.join(f), &LoadOptions::default()).unwrap()));
        }
    }
    list
}

#[test]
fn backends_agree_with_gbuffer_and_each_other() {
    let ctx = common::validated_context();
    let has_rq = ctx.caps.supports_ray_query();
    for (name, scene) in scenes() {
        let mut rc = render(&ctx, scene.clone(), Backend::Compute);
        let c = images(&mut rc);
        let masked = masked_instances(&rc);
        check_against_gbuffer(&format!("{name} (compute)"), &c, &masked);
        drop(rc);
        if has_rq {
            let mut rq = render(&ctx, scene, Backend::RayQuery);
            let q = images(&mut rq);
            check_against_gbuffer(&format!("{name} (ray query)"), &q, &masked);
            check_backends_agree(&name, &c, &q);
        }
    }
    if !has_rq {
        assert_ne!(std::env::var("CI").as_deref(), Ok("true"), "CI machines have Mesa >= 24.1 with ray query");
        eprintln!("ray query unavailable on this device: compared the compute backend with the G-buffer only");
    }
    common::assert_validation_clean(ctx);
}

/// Rays from outside a closed mesh aimed exactly at its vertices and edge midpoints must hit
/// it: a watertight intersector lets nothing through the cracks.
#[test]
fn closed_meshes_do_not_leak_at_edges_and_vertices() {
    let ctx = common::validated_context();
    let mut scene = Scene { name: "watertight".into(), ..Default::default() };
    scene.materials.push(Default::default());
    scene.meshes.push(builtin::uv_sphere(1.0, 24, 12, 0));
    scene.meshes.push(builtin::cuboid(Vec3::splat(0.5), 0));
    let node = |t: Vec3| hybrid_rt::scene::Node {
        name: String::new(),
        parent: None,
        translation: t,
        rotation: glam::Quat::from_rotation_y(0.3),
        scale: Vec3::ONE,
    };
    scene.nodes.push(node(Vec3::ZERO));
    scene.nodes.push(node(Vec3::new(5.0, 0.0, 0.0)));
    scene.instances.push(hybrid_rt::scene::Instance { mesh: 0, node: 0 });
    scene.instances.push(hybrid_rt::scene::Instance { mesh: 1, node: 1 });
    let pose = scene.evaluate(0.0);
    // Targets: every vertex and every edge midpoint, in world space, with the mesh centre.
    let mut rays = Vec::new();
    for inst in &scene.instances {
        let m = pose.world[inst.node as usize];
        let mesh = &scene.meshes[inst.mesh as usize];
        let centre = m.transform_point3(Vec3::ZERO);
        for t in mesh.indices.chunks(3) {
            let p = |i: u32| m.transform_point3(Vec3::from(mesh.vertices[i as usize].position));
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                for target in [p(a), (p(a) + p(b)) * 0.5] {
                    let dir = (target - centre).normalize();
                    // Start outside, aim back through the target toward the centre.
                    let origin = centre + dir * 3.0;
                    rays.push(Ray { origin: origin.to_array(), tmin: 0.0, dir: (-dir).to_array(), tmax: 10.0 });
                }
            }
        }
    }
    let backends: Vec<Backend> =
        if ctx.caps.supports_ray_query() { vec![Backend::Compute, Backend::RayQuery] } else { vec![Backend::Compute] };
    for backend in backends {
        let settings = Settings { width: 8, height: 8, ..Default::default() };
        let shaders = ShaderLibrary::embedded();
        let mut r = common::renderer(&ctx, scene.clone(), settings, backend);
        let (hits, _) = r.trace_rays(&shaders, &rays, false, 1).unwrap();
        let leaks = hits.iter().filter(|h| !h.is_hit()).count();
        assert_eq!(leaks, 0, "{backend:?}: {leaks} of {} rays leaked through edges or vertices", rays.len());
        let (any, _) = r.trace_rays(&shaders, &rays, true, 1).unwrap();
        assert!(any.iter().all(|h| h.is_hit()), "{backend:?}: shadow rays leaked");
    }
    common::assert_validation_clean(ctx);
}

/// The shadow of an alpha-masked checkerboard on the floor is the same checkerboard.
#[test]
fn masked_shadows_follow_the_alpha_texture() {
    use hybrid_rt::scene::builtin::alpha_shadow_facts as facts;
    let ctx = common::validated_context();
    let backends: Vec<Backend> =
        if ctx.caps.supports_ray_query() { vec![Backend::Compute, Backend::RayQuery] } else { vec![Backend::Compute] };
    for backend in backends {
        let settings = Settings { width: 128, height: 128, ..Default::default() };
        let mut r = common::renderer(&ctx, builtin::alpha_shadow(), settings, backend);
        r.render_frame().unwrap();
        let img = r.read_outputs(&[passes::gbuffer::IDS, r.shadow_visibility()]).unwrap();
        let view = r.last_view.unwrap();
        let size = glam::Vec2::new(128.0, 128.0);
        let (mut lit, mut shadowed) = (0, 0);
        for y in 0..128 {
            for x in 0..128 {
                if img[0].get_u32(x, y, 0) != facts::FLOOR_INSTANCE {
                    continue;
                }
                let d = view.ray_dir(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5), size);
                let p = view.position + d * (-view.position.y / d.y);
                // Stay clear of cell borders, where a pixel straddles two cells.
                let cell = 2.0 * facts::HALF / facts::CELLS as f32;
                let near_border = |c: f32| {
                    let f = ((c + facts::HALF) / cell).fract();
                    !(0.05..0.95).contains(&f)
                };
                if near_border(p.x) || near_border(p.z) {
                    continue;
                }
                let expected = match facts::opaque_at(p.x, p.z) {
                    Some(true) => 0.0,
                    _ => 1.0,
                };
                let got = img[1].get(x, y, 0);
                assert_eq!(got, expected, "{backend:?}: floor at ({:.2}, {:.2}) pixel ({x},{y})", p.x, p.z);
                if expected == 0.0 { shadowed += 1 } else { lit += 1 }
            }
        }
        assert!(
            shadowed > 50 && lit > 50,
            "{backend:?}: too few floor pixels checked ({shadowed} shadowed, {lit} lit)"
        );
    }
    common::assert_validation_clean(ctx);
}

/// Hard shadows: a floor seen at a grazing angle is lit everywhere outside the box's shadow
/// (no acne speckle), and the shadow touches the box (no peter-panning): every floor pixel
/// whose footprint lies wholly inside or outside the analytic shadow gets that visibility.
#[test]
fn hard_shadows_have_no_acne_and_keep_contact() {
    use hybrid_rt::scene::builtin::shadow_test_facts as facts;
    let ctx = common::validated_context();
    let backends: Vec<Backend> =
        if ctx.caps.supports_ray_query() { vec![Backend::Compute, Backend::RayQuery] } else { vec![Backend::Compute] };
    let (w, h) = (160u32, 120u32);
    for backend in backends {
        let settings = Settings { width: w, height: h, ..Default::default() };
        let mut r = common::renderer(&ctx, builtin::shadow_test(), settings, backend);
        r.render_frame().unwrap();
        let img = r.read_outputs(&[passes::gbuffer::IDS, r.shadow_visibility()]).unwrap();
        let view = r.last_view.unwrap();
        let size = glam::Vec2::new(w as f32, h as f32);
        let floor_at = |px: glam::Vec2| {
            let d = view.ray_dir(px, size);
            (d.y < 0.0).then(|| view.position + d * (-view.position.y / d.y))
        };
        let (mut lit, mut shadowed, mut contact) = (0, 0, 0);
        for y in 0..h {
            for x in 0..w {
                if img[0].get_u32(x, y, 0) != facts::FLOOR_INSTANCE {
                    continue;
                }
                // A 5x5 grid over the pixel must agree, else it straddles the shadow's edge.
                let corners: Vec<Option<bool>> = (0..25)
                    .map(|i| {
                        let (dx, dy) = ((i % 5) as f32 / 4.0, (i / 5) as f32 / 4.0);
                        floor_at(glam::Vec2::new(x as f32 + dx, y as f32 + dy)).map(facts::shadowed)
                    })
                    .collect();
                if corners.iter().any(|c| *c != corners[0]) || corners[0].is_none() {
                    continue;
                }
                let centre = floor_at(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).unwrap();
                let expect_shadow = corners[0] == Some(true);
                let got = img[1].get(x, y, 0);
                assert_eq!(
                    got,
                    if expect_shadow { 0.0 } else { 1.0 },
                    "{backend:?}: floor ({:.3}, {:.3})",
                    centre.x,
                    centre.z
                );
                if expect_shadow {
                    shadowed += 1;
                    // Within 6 cm (about 1.5 pixels here) of the box's base, on the floor outside it.
                    let gap = (centre.x.abs() - facts::HALF).max(centre.z.abs() - facts::HALF);
                    if gap < 0.06 {
                        contact += 1;
                    }
                } else {
                    lit += 1;
                }
            }
        }
        assert!(lit > 2000 && shadowed > 80, "{backend:?}: coverage lit {lit}, shadowed {shadowed}");
        assert!(contact > 3, "{backend:?}: only {contact} shadowed floor pixels touch the box");
        eprintln!("{backend:?}: {lit} lit and {shadowed} shadowed floor pixels as expected, {contact} at the contact");
    }
    common::assert_validation_clean(ctx);
}
