//! Adaptive soft shadows (Ray Tracing Gems ch. 13) on builtin:soft-shadow-test, a box on a
//! floor under a sphere light, against the true visibility integrated on the CPU:
//! - the filtered visibility converges to it, closer than a single frame's raw estimate;
//! - sample counts go up in the penumbra and down to 1 where nothing changes; a camera cut
//!   puts every sampled pixel at s_max; a tight budget lowers the counts;
//! - a hard light (builtin:shadow-test) stays at one ray and is not filtered: the frame plan
//!   leaves the filter passes out, and with `--full` they pass its visibility through;
//! - a mesh light (an emissive panel in place of the sphere) gets the same: visibility,
//!   adaptive counts, and a lit floor that matches the reference path tracer's; so does a
//!   closed one (an octahedron), whose shadow rays go only to the faces that face the floor;
//! - an unoccluded spot light under TAA's jitter: no penumbra at its cone's edge, one ray a
//!   frame everywhere, the far floor seen at a grazing angle included.

mod common;

use glam::{Vec2, Vec3};
use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::passes::shadows::{HARD_VISIBILITY, ShadowSettings, VISIBILITY};
use hybrid_rt::render::{Environment, RenderMode, Renderer, Settings};
use hybrid_rt::scene::builtin::{self, shadow_test_facts as facts};
use hybrid_rt::scene::{Instance, Material, Scene};

const W: u32 = 96;
const H: u32 = 72;

fn renderer(
    ctx: &std::sync::Arc<hybrid_rt::gpu::Context>,
    scene: hybrid_rt::scene::Scene,
    shadows: ShadowSettings,
) -> Renderer {
    renderer_with(ctx, scene, Settings { shadows, ..Default::default() })
}

fn renderer_with(
    ctx: &std::sync::Arc<hybrid_rt::gpu::Context>,
    scene: hybrid_rt::scene::Scene,
    settings: Settings,
) -> Renderer {
    let settings = Settings { width: W, height: H, ..settings };
    common::renderer(ctx, scene, settings, common::auto_backend(ctx))
}

/// Fraction of the sphere light's solid angle seen from floor point p past the box, by a
/// stratified grid of directions in the cone the sphere subtends (uniform in solid angle, as the
/// shader samples it).
fn true_visibility(p: Vec3) -> f32 {
    let to = facts::SPHERE_LIGHT - p;
    let d = to.length();
    let axis = to / d;
    let cos_max = (1.0 - (facts::SPHERE_RADIUS / d).powi(2)).sqrt();
    let (t, b) = axis.any_orthonormal_pair();
    let n = 48;
    let mut visible = 0;
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let cos = 1.0 - u * (1.0 - cos_max);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * v;
            let dir = (t * phi.cos() * sin + b * phi.sin() * sin + axis * cos).normalize();
            if !facts::ray_hits_box(p, dir, d) {
                visible += 1;
            }
        }
    }
    visible as f32 / (n * n) as f32
}

/// The emissive panel of `panel_shadow_test`: side and radiance. Its centre is the sphere
/// light's.
const PANEL_SIDE: f32 = 0.8;
const PANEL_RADIANCE: f32 = 12.0;

/// soft_shadow_test with the sphere light replaced by a square emissive panel facing down
/// (two triangles, one-sided): no punctual light, so the panel takes the shadows chain's first
/// channel as a mesh light. Nothing lights the scene from outside.
fn panel_shadow_test() -> Scene {
    emitter_shadow_test("panel", |material| {
        builtin::quad(Vec3::ZERO, Vec3::X * PANEL_SIDE, Vec3::Z * PANEL_SIDE, material)
    })
}

/// soft_shadow_test with the sphere light replaced by a one-sided emissive octahedron of the
/// sphere's radius (8 triangles facing out): from any floor point, at most half of its faces
/// emit toward it.
fn octahedron_shadow_test() -> Scene {
    emitter_shadow_test("octahedron", |material| {
        let r = facts::SPHERE_RADIUS;
        let corners = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|c| c * r);
        let vertices = corners
            .iter()
            .map(|&c| hybrid_rt::scene::Vertex {
                position: c.into(),
                normal: c.normalize().into(),
                ..Default::default()
            })
            .collect();
        let mut indices = Vec::new();
        for x in [0u32, 1] {
            for y in [2u32, 3] {
                for z in [4u32, 5] {
                    // Counter-clockwise seen from outside: (x, y, z) is right-handed when an
                    // even number of the three corners is negative.
                    let flips = (x == 1) as u32 + (y == 3) as u32 + (z == 5) as u32;
                    indices.extend_from_slice(&if flips & 1 == 0 { [x, y, z] } else { [x, z, y] });
                }
            }
        }
        hybrid_rt::scene::Mesh {
            name: "octahedron".into(),
            vertices,
            indices,
            material,
            bounds_min: Vec3::splat(-r),
            bounds_max: Vec3::splat(r),
        }
    })
}

/// soft_shadow_test with its sphere light replaced by the emissive mesh `mesh(material)`,
/// centred where the sphere was, of radiance PANEL_RADIANCE and black otherwise.
fn emitter_shadow_test(name: &str, mesh: impl FnOnce(u32) -> hybrid_rt::scene::Mesh) -> Scene {
    let mut s = builtin::shadow_test();
    s.name = format!("{name}-shadow-test");
    s.lights.clear();
    let material = s.materials.len() as u32;
    s.materials.push(Material {
        name: name.into(),
        base_color_factor: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive_factor: Vec3::splat(PANEL_RADIANCE),
        ..Material::default()
    });
    let mesh = mesh(material);
    s.meshes.push(mesh);
    let node = s.nodes.len() as u32;
    s.nodes.push(common::node(name, facts::SPHERE_LIGHT));
    s.instances.push(Instance { mesh: s.meshes.len() as u32 - 1, node });
    s
}

/// The share of the panel's light that reaches floor point p past the box: a stratified grid
/// on the panel, each point weighed by what it brings (both cosines over the squared distance),
/// as the shader weighs its rays.
fn true_panel_visibility(p: Vec3) -> f32 {
    let n = 48;
    let (mut visible, mut all) = (0.0f32, 0.0f32);
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f32 + 0.5) / n as f32 - 0.5, (j as f32 + 0.5) / n as f32 - 0.5);
            let q = facts::SPHERE_LIGHT + Vec3::new(u * PANEL_SIDE, 0.0, v * PANEL_SIDE);
            let to = q - p;
            let d = to.length();
            // The panel faces straight down onto the floor: both cosines are the height over d.
            let weight = (to.y / d).powi(2) / (d * d);
            all += weight;
            if !facts::ray_hits_box(p, to / d, d) {
                visible += weight;
            }
        }
    }
    visible / all
}

/// Floor pixels (centre on the floor) with their floor point.
fn floor_points(r: &Renderer, ids: &CpuImage) -> Vec<(u32, u32, Vec3)> {
    let view = r.last_view.unwrap();
    let size = Vec2::new(W as f32, H as f32);
    let mut out = Vec::new();
    for y in 0..H {
        for x in 0..W {
            if ids.get_u32(x, y, 0) != facts::FLOOR_INSTANCE {
                continue;
            }
            let d = view.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), size);
            out.push((x, y, view.position + d * (-view.position.y / d.y)));
        }
    }
    out
}

/// What the chain made of a light's penumbra on the floor, against the true visibility.
#[derive(Debug)]
struct Penumbra {
    /// Pixels with a true visibility strictly between 0 and 1, and the filtered and the raw
    /// (this frame's rays) visibility's mean absolute error over them.
    pixels: usize,
    mae: f64,
    mae_raw: f64,
    /// Pixels well inside the penumbra (true visibility 0.2..0.8) and their mean ray count.
    deep: usize,
    deep_count: f64,
    /// Unshadowed pixels, and how many of them came down to 1 ray.
    open: usize,
    open_at_one: usize,
}

impl Penumbra {
    fn measure(
        points: &[(u32, u32, Vec3)],
        truth: impl Fn(Vec3) -> f32,
        filtered: &CpuImage,
        raw: &CpuImage,
        counts: &CpuImage,
        s_max: u32,
    ) -> Self {
        let (mut err, mut err_raw, mut deep_sum) = (0.0f64, 0.0f64, 0.0f64);
        let mut p = Penumbra { pixels: 0, mae: 0.0, mae_raw: 0.0, deep: 0, deep_count: 0.0, open: 0, open_at_one: 0 };
        for &(x, y, point) in points {
            let truth = truth(point);
            if truth > 0.0 && truth < 1.0 {
                err += (filtered.get(x, y, 0) - truth).abs() as f64;
                err_raw += (raw.get(x, y, 0) - truth).abs() as f64;
                p.pixels += 1;
            }
            let count = counts.get(x, y, 0);
            assert!((1.0..=s_max as f32).contains(&count), "count {count} at ({x},{y})");
            if truth > 0.2 && truth < 0.8 {
                deep_sum += count as f64;
                p.deep += 1;
            } else if truth == 1.0 {
                p.open += 1;
                p.open_at_one += (count == 1.0) as usize;
            }
        }
        p.mae = err / p.pixels.max(1) as f64;
        p.mae_raw = err_raw / p.pixels.max(1) as f64;
        p.deep_count = deep_sum / p.deep.max(1) as f64;
        p
    }

    /// Close to the truth, closer than one frame's rays, more rays in the penumbra and 1 where
    /// nothing changes; over at least `pixels` penumbra pixels, `deep` of them well inside.
    fn check(&self, pixels: usize, deep: usize) {
        let Penumbra { pixels: n, mae, mae_raw, deep_count, .. } = *self;
        assert!(n > pixels, "only {n} penumbra pixels");
        assert!(mae < 0.05, "filtered visibility is off the true visibility by {mae} on average in the penumbra");
        assert!(mae < 0.7 * mae_raw, "history and filtering did not help: {mae} vs raw {mae_raw}");
        assert!(self.deep > deep && deep_count > 2.5, "penumbra: {} pixels, mean count {deep_count}", self.deep);
        assert!(
            self.open_at_one as f64 > 0.8 * self.open as f64,
            "only {} of {} unshadowed pixels came down to 1 ray",
            self.open_at_one,
            self.open
        );
    }
}

#[test]
fn soft_shadows_converge_with_adaptive_counts() {
    let ctx = common::validated_context();
    // The chapter's standard tier, above the default, so that the counts have four steps to fall.
    let settings = ShadowSettings { s_max: 5, ..Default::default() };
    let mut r = renderer(&ctx, builtin::soft_shadow_test(), settings);
    r.render_frame().unwrap();
    let first = r
        .read_outputs(&[passes::gbuffer::IDS, passes::shadows::trace::RING0, passes::shadows::trace::SAMPLE_COUNT])
        .unwrap();
    // Frame 1: nothing cached, so every lit floor pixel traced s_max rays.
    let points = floor_points(&r, &first[0]);
    for &(x, y, _) in &points {
        let c = first[2].get(x, y, 0);
        assert!(c == settings.s_max as f32, "first frame: count {c} at ({x},{y}), expected s_max");
    }
    // From s_max the count steps down by one after each 4 stable frames: 21 frames reach 1.
    common::render_frames(&mut r, 25);
    let imgs =
        r.read_outputs(&[VISIBILITY, passes::shadows::trace::SAMPLE_COUNT, passes::shadows::trace::RING0]).unwrap();
    let p = Penumbra::measure(&points, true_visibility, &imgs[0], &imgs[2], &imgs[1], settings.s_max);
    eprintln!("sphere light: {p:?}");
    p.check(100, 50);

    // A camera cut invalidates every cache: all sampled pixels go to s_max.
    r.camera_cut();
    r.render_frame().unwrap();
    let counts = r.read_output(passes::shadows::trace::SAMPLE_COUNT).unwrap();
    for &(x, y, _) in &points {
        assert_eq!(counts.get(x, y, 0), settings.s_max as f32, "after the cut at ({x},{y})");
    }
    drop(r);
    common::assert_validation_clean(ctx);
}

#[test]
fn a_tight_budget_lowers_the_counts() {
    let ctx = common::validated_context();
    let tight = ShadowSettings { budget_fraction: 0.002, ..Default::default() };
    let mut r = renderer(&ctx, builtin::soft_shadow_test(), tight);
    common::render_frames(&mut r, 4);
    let counts = r.read_output(passes::shadows::trace::SAMPLE_COUNT).unwrap();
    let max = (0..W * H).map(|i| counts.get(i % W, i / W, 0)).fold(0.0f32, f32::max);
    assert!(max < tight.s_max as f32, "the budget did not cap the counts (max {max})");
    drop(r);
    common::assert_validation_clean(ctx);
}

#[test]
fn hard_lights_use_one_ray_and_no_filter() {
    let ctx = common::validated_context();
    // The plan: the trace pass alone, its ring read directly.
    let mut r = renderer(&ctx, builtin::shadow_test(), ShadowSettings::default());
    r.render_frame().unwrap();
    assert_eq!(r.shadow_visibility(), HARD_VISIBILITY);
    assert!(!r.graph.pass_names().iter().any(|p| p.starts_with("shadows_")), "{:?}", r.graph.pass_names());
    let counts = r.read_output(passes::shadows::trace::SAMPLE_COUNT).unwrap();
    for y in 0..H {
        for x in 0..W {
            let c = counts.get(x, y, 0);
            assert!(c == 1.0 || c == 0.0, "hard light: count {c} at ({x},{y})");
        }
    }
    drop(r);
    // Every pass (`--full`): the filter runs and leaves hard lights alone.
    let mut r = renderer_with(&ctx, builtin::shadow_test(), Settings { full: true, ..Default::default() });
    common::render_frames(&mut r, 3);
    let imgs = r
        .read_outputs(&[
            passes::gbuffer::IDS,
            passes::shadows::trace::SAMPLE_COUNT,
            passes::shadows::filter::KERNEL,
            passes::shadows::trace::RING0,
            VISIBILITY,
        ])
        .unwrap();
    for y in 0..H {
        for x in 0..W {
            if imgs[0].get_u32(x, y, 0) == u32::MAX {
                continue;
            }
            let c = imgs[1].get(x, y, 0);
            assert!(c == 1.0 || c == 0.0, "hard light: count {c} at ({x},{y})");
            assert_eq!(imgs[2].get(x, y, 0), 1.0, "hard light filtered at ({x},{y})");
            assert_eq!(imgs[3].get(x, y, 0), imgs[4].get(x, y, 0), "hard light visibility changed by the filter");
        }
    }
    drop(r);
    common::assert_validation_clean(ctx);
}

/// A soft spot light over an open floor, a still camera with TAA: nothing occludes the light,
/// so no pixel is a penumbra and every lit one settles at one ray a frame.
/// - The cone's edge on the floor is not a shadow's edge: the jitter moves pixels across it
///   every frame, and while the pixels outside the cone stored visibility 0 that edge counted
///   as a penumbra (0 and 1 in turn) and drew s_max rays a frame and the widest filter (1,226
///   pixels taken for a penumbra).
/// - On the far floor, seen at a grazing angle, the jitter moved a pixel's depth past Eq.
///   13.7's test, which restarted 861 pixels' counts at s_max every frame, until the test
///   allowed the depth's own change over the jitter's reach.
#[test]
fn an_unoccluded_spot_takes_one_ray_and_no_penumbra() {
    let ctx = common::validated_context();
    let mut scene = builtin::soft_shadow_test();
    // The floor alone: no box.
    scene.instances.truncate(facts::FLOOR_INSTANCE as usize + 1);
    let lamp = scene.lights[0].node as usize;
    scene.nodes[lamp].translation = Vec3::new(0.6, 3.0, 0.4);
    scene.nodes[lamp].rotation = glam::Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::NEG_Y);
    scene.lights[0].kind = hybrid_rt::scene::LightKind::Spot { inner_cone: 0.5, outer_cone: 0.7 };
    // TAA on, as the CLI has it: its jitter is what moves pixels across the edge.
    let mut r = renderer_with(&ctx, scene, Settings { taa: true, ..Default::default() });
    common::render_frames(&mut r, 24);
    let imgs = r
        .read_outputs(&[passes::gbuffer::IDS, passes::shadows::filter::DV, passes::shadows::trace::SAMPLE_COUNT])
        .unwrap();
    let (mut lit, mut dark, mut penumbra, mut above_one) = (0, 0, 0, 0);
    for y in 0..H {
        for x in 0..W {
            if imgs[0].get_u32(x, y, 0) == u32::MAX {
                continue;
            }
            let (dv, count) = (imgs[1].get(x, y, 0), imgs[2].get(x, y, 0));
            *(if count == 0.0 { &mut dark } else { &mut lit }) += 1;
            penumbra += usize::from(dv > 0.0);
            above_one += usize::from(count > 1.0);
        }
    }
    eprintln!(
        "unoccluded spot: {lit} pixels inside the cone, {dark} outside, {penumbra} taken for a penumbra, {above_one} above one ray"
    );
    // The cone's edge lies on the floor in view: pixels on both sides of it.
    assert!(lit > 200 && dark > 200, "{lit} pixels inside the cone, {dark} outside");
    assert_eq!(penumbra, 0, "pixels of an unoccluded spot taken for a penumbra");
    assert_eq!(above_one, 0, "pixels of an unoccluded spot traced more than one ray a frame");
    drop(r);
    common::assert_validation_clean(ctx);
}

/// The mean luminance of the floor points in `r`'s frame over a `base`-sized reference of
/// `scene` (256 spp), over the whole floor and over its penumbra, where `truth` is strictly
/// between 0.1 and 0.9.
fn lit_floor_against_reference(
    ctx: &std::sync::Arc<hybrid_rt::gpu::Context>,
    mut r: Renderer,
    scene: Scene,
    base: Settings,
    points: &[(u32, u32, Vec3)],
    truth: fn(Vec3) -> f32,
) -> (f64, f64) {
    let floor = |img: &CpuImage, penumbra: bool| {
        let (mut sum, mut count) = (0.0f64, 0);
        for &(x, y, p) in points {
            let t = truth(p);
            if penumbra && !(t > 0.1 && t < 0.9) {
                continue;
            }
            sum += (0.2126 * img.get(x, y, 0) + 0.7152 * img.get(x, y, 1) + 0.0722 * img.get(x, y, 2)) as f64;
            count += 1;
        }
        sum / count as f64
    };
    let frame = r.read_output(r.hdr_output()).unwrap();
    drop(r);
    let reference_settings = Settings { mode: RenderMode::Reference { seed: 3, max_bounces: 8 }, ..base };
    let mut reference = renderer_with(ctx, scene, reference_settings);
    common::render_frames(&mut reference, 256);
    let reference = reference.read_output(reference.hdr_output()).unwrap();
    (floor(&frame, false) / floor(&reference, false), floor(&frame, true) / floor(&reference, true))
}

/// The floor lit by `light` within 3% of the reference's light, its penumbra within
/// `penumbra_bound`.
fn assert_lit_floor(light: &str, (whole, penumbra): (f64, f64), penumbra_bound: f64) {
    eprintln!("{light}-lit floor against the reference (256 spp): whole {whole:.4}, penumbra {penumbra:.4}");
    assert!((whole - 1.0).abs() < 0.03, "{light}: the floor reads {whole} of the reference's light");
    assert!((penumbra - 1.0).abs() < penumbra_bound, "{light}: the penumbra reads {penumbra} of the reference's light");
}

#[test]
fn a_closed_mesh_light_is_sampled_where_it_faces() {
    let ctx = common::validated_context();
    let base = Settings { environment: Environment::default(), ..Default::default() };
    let mut r = renderer_with(&ctx, octahedron_shadow_test(), base.clone());
    assert_eq!(r.shadow_visibility(), VISIBILITY, "the octahedron is a mesh light");
    common::render_frames(&mut r, 26);
    let ids = r.read_output(passes::gbuffer::IDS).unwrap();
    let points = floor_points(&r, &ids);
    let lit = lit_floor_against_reference(&ctx, r, octahedron_shadow_test(), base, &points, true_visibility);
    // The sphere's penumbra, which the octahedron's nearly shares: 0.913 when the shadow rays'
    // points were drawn by area over all eight faces, 1.033 by each face's share of the light.
    assert_lit_floor("octahedron", lit, 0.05);
    common::assert_validation_clean(ctx);
}

#[test]
fn a_mesh_light_gets_adaptive_soft_shadows() {
    let ctx = common::validated_context();
    let settings = ShadowSettings::default();
    let base = Settings { shadows: settings, environment: Environment::default(), ..Default::default() };
    let mut r = renderer_with(&ctx, panel_shadow_test(), base.clone());
    assert_eq!(r.shadow_visibility(), VISIBILITY, "the panel's channel is soft: the whole chain runs");
    common::render_frames(&mut r, 26);
    let imgs = r
        .read_outputs(&[
            passes::gbuffer::IDS,
            VISIBILITY,
            passes::shadows::trace::SAMPLE_COUNT,
            passes::shadows::trace::RING0,
        ])
        .unwrap();
    let points = floor_points(&r, &imgs[0]);
    let p = Penumbra::measure(&points, true_panel_visibility, &imgs[1], &imgs[3], &imgs[2], settings.s_max);
    eprintln!("panel: {p:?}");
    p.check(60, 30);

    // The lit floor: the frame against the path tracer, over the whole floor and over the
    // penumbra (composite's closed-form light times the chain's visibility, and gi leaving the
    // panel out of its reservoirs: counted twice, the floor would read twice as bright).
    let lit = lit_floor_against_reference(&ctx, r, panel_shadow_test(), base, &points, true_panel_visibility);
    // The penumbra read 0.961 while every 3x3 block took the same points of the light
    // (shadows.comp block_shift).
    assert_lit_floor("panel", lit, 0.03);
    common::assert_validation_clean(ctx);
}
