//! TAA on builtin:gbuffer-test: a static view converges to anti-aliased edges while flat
//! regions keep their brightness; pixels uncovered by the moving cube take the new frame (no
//! ghost); a camera cut drops the history everywhere.

mod common;

use hybrid_rt::image_io::CpuImage;
use hybrid_rt::passes;
use hybrid_rt::render::{Renderer, Settings};
use hybrid_rt::scene::builtin::{self, gbuffer_test_facts as facts};

const W: u32 = 64;
const H: u32 = 48;

fn renderer(ctx: &std::sync::Arc<hybrid_rt::gpu::Context>, frame_dt: f32) -> Renderer {
    let settings = Settings { width: W, height: H, taa: true, frame_dt, start_time: 0.2, ..Default::default() };
    common::renderer(ctx, builtin::gbuffer_test(), settings, common::auto_backend(ctx))
}

fn lum(img: &CpuImage, x: u32, y: u32) -> f32 {
    0.2126 * img.get(x, y, 0) + 0.7152 * img.get(x, y, 1) + 0.0722 * img.get(x, y, 2)
}

#[test]
fn static_view_antialiases_edges_and_keeps_flat_regions() {
    let ctx = common::validated_context();
    let mut r = renderer(&ctx, 0.0);
    common::render_frames(&mut r, 16);
    let imgs = r.read_outputs(&[passes::taa::COLOR, passes::composite::COLOR, passes::gbuffer::IDS]).unwrap();
    let (taa, raw, ids) = (&imgs[0], &imgs[1], &imgs[2]);
    // Flat plane interior: the same brightness with and without TAA.
    let (mut flat_taa, mut flat_raw, mut n) = (0.0f64, 0.0f64, 0);
    // Sphere silhouette: with TAA, pixels take values between the two sides.
    let mut blended = 0;
    for y in 1..H - 1 {
        for x in 1..W - 1 {
            let id = ids.get_u32(x, y, 0);
            let uniform = (-1i32..=1).all(|d| {
                ids.get_u32((x as i32 + d) as u32, y, 0) == id && ids.get_u32(x, (y as i32 + d) as u32, 0) == id
            });
            if id == facts::PLANE_INSTANCE && uniform {
                flat_taa += lum(taa, x, y) as f64;
                flat_raw += lum(raw, x, y) as f64;
                n += 1;
            }
            let left = ids.get_u32(x - 1, y, 0);
            if id == facts::SPHERE_INSTANCE && left == facts::PLANE_INSTANCE {
                let (a, b, t) = (lum(raw, x - 1, y), lum(raw, x + 1, y), lum(taa, x, y));
                let (lo, hi) = (a.min(b), a.max(b));
                if t > lo + 0.05 * (hi - lo) && t < hi - 0.05 * (hi - lo) {
                    blended += 1;
                }
            }
        }
    }
    let rel = (flat_taa - flat_raw).abs() / flat_raw;
    assert!(n > 500 && rel < 0.01, "flat plane brightness changed by {:.3}% under TAA", rel * 100.0);
    assert!(blended >= 3, "only {blended} silhouette pixels were anti-aliased");
    drop(r);
    common::assert_validation_clean(ctx);
}

#[test]
fn disocclusion_and_camera_cut_drop_the_history() {
    let ctx = common::validated_context();
    let mut r = renderer(&ctx, 1.0 / 30.0);
    common::render_frames(&mut r, 8);
    let before = r.read_output(passes::gbuffer::IDS).unwrap();
    r.render_frame().unwrap();
    let imgs = r.read_outputs(&[passes::taa::COLOR, passes::composite::COLOR, passes::gbuffer::IDS]).unwrap();
    let mut uncovered = 0;
    for y in 0..H {
        for x in 0..W {
            if before.get_u32(x, y, 0) == facts::CUBE_INSTANCE && imgs[2].get_u32(x, y, 0) == facts::PLANE_INSTANCE {
                uncovered += 1;
                let (t, c) = (lum(&imgs[0], x, y), lum(&imgs[1], x, y));
                assert!((t - c).abs() <= 1e-4 + 1e-3 * c, "ghost at uncovered ({x},{y}): taa {t}, frame {c}");
            }
        }
    }
    assert!(uncovered > 0, "the cube uncovered nothing");
    r.camera_cut();
    r.render_frame().unwrap();
    let imgs = r.read_outputs(&[passes::taa::COLOR, passes::composite::COLOR]).unwrap();
    for y in 0..H {
        for x in 0..W {
            assert_eq!(imgs[0].get(x, y, 0), imgs[1].get(x, y, 0), "history survived the cut at ({x},{y})");
        }
    }
    drop(r);
    common::assert_validation_clean(ctx);
}
