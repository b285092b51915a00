//! Determinism: the same scene, settings, seed and backend give bit-identical output on the
//! same machine.
//! - In one process, two renderers of the animated default scene (TAA and both SVGF chains
//!   carrying history across frames) agree bit for bit on every pass output, composite.color
//!   and tonemap.color included, on every backend the device has.
//! - Across processes with different numbers of lavapipe worker threads (LP_NUM_THREADS=1 and
//!   2), so that the order in which threads finish differs: the hybrid frame's dumped
//!   composite.color and tonemap.color, and the reference path tracer's EXR, are bit-identical.
//!   (tests/reference.rs checks equal seeds in one process.)

mod common;

use hybrid_rt::backend::Backend;
use hybrid_rt::graph::Resource;
use hybrid_rt::image_io::{CpuImage, Texels};
use hybrid_rt::passes;
use hybrid_rt::render::Settings;
use std::path::Path;
use std::process::Command;

/// Raw bits of every value (floats by their bit patterns: -0.0 and NaN payloads count).
fn bits(img: &CpuImage) -> Vec<u32> {
    match &img.texels {
        Texels::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
        Texels::U32(v) => v.clone(),
    }
}

#[test]
fn same_settings_and_seed_give_identical_frames_on_each_backend() {
    let ctx = common::validated_context();
    let mut backends = vec![Backend::Compute];
    if ctx.caps.supports_ray_query() {
        backends.push(Backend::RayQuery);
    } else {
        eprintln!("note: {} has no ray query; the compute backend only", ctx.caps.device_name);
    }
    let scene = hybrid_rt::scene::load_gltf(&common::default_scene(), &Default::default()).unwrap();
    for backend in backends {
        let run = || {
            let settings = Settings { width: 40, height: 24, taa: true, seed: 7, ..Default::default() };
            let mut r = common::renderer(&ctx, scene.clone(), settings, backend);
            // Several frames: the ball moves and the temporal passes blend their histories.
            common::render_frames(&mut r, 4);
            let names = r.graph.output_order.clone();
            let images = r.read_outputs(&names).unwrap();
            names.into_iter().zip(images.iter().map(bits)).collect::<Vec<_>>()
        };
        let (a, b) = (run(), run());
        let names: Vec<Resource> = a.iter().map(|(n, _)| *n).collect();
        for expected in [passes::composite::COLOR.into(), passes::tonemap::COLOR.into()] {
            assert!(names.contains(&expected), "no {expected} among {names:?}");
        }
        for ((name, x), (_, y)) in a.iter().zip(&b) {
            let differ = x.iter().zip(y).filter(|(p, q)| p != q).count();
            assert!(differ == 0, "{} backend: {name} differs in {differ} of {} values", backend.variant(), x.len());
        }
    }
    common::assert_validation_clean(ctx);
}

fn run_with_threads(threads: &str, args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .args(args)
        .env("LP_NUM_THREADS", threads)
        .output()
        .expect("run hybrid-rt");
    let t = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "LP_NUM_THREADS={threads} {args:?}: {t}");
}

fn exr_bits(p: &Path) -> Vec<u32> {
    bits(&hybrid_rt::image_io::read_exr_channels(p).unwrap_or_else(|e| panic!("{}: {e:#}", p.display())))
}

#[test]
fn thread_count_does_not_change_the_hybrid_frame() {
    let dir = common::temp_dir("det-threads");
    for threads in ["1", "2"] {
        let d = dir.join(threads);
        let out = d.join("frame.exr");
        let dump = d.join("dump");
        #[rustfmt::skip]
        run_with_threads(threads, &[
            "render", "--size", "32x24", "--frames", "3", "--validate",
            "--out", out.to_str().unwrap(), "--dump-passes", dump.to_str().unwrap(),
        ]);
    }
    for file in ["frame.exr", "dump/composite.color.exr", "dump/tonemap.color.exr"] {
        let (a, b) = (exr_bits(&dir.join("1").join(file)), exr_bits(&dir.join("2").join(file)));
        assert!(a == b, "{file}: 1 and 2 lavapipe threads give different values");
    }
}

#[test]
fn thread_count_does_not_change_the_reference() {
    let dir = common::temp_dir("det-reference");
    for threads in ["1", "2"] {
        let out = dir.join(format!("ref-{threads}.exr"));
        #[rustfmt::skip]
        run_with_threads(threads, &[
            "reference", "--size", "24x16", "--spp", "16", "--seed", "3", "--validate",
            "--out", out.to_str().unwrap(),
        ]);
    }
    let (a, b) = (exr_bits(&dir.join("ref-1.exr")), exr_bits(&dir.join("ref-2.exr")));
    assert!(a.iter().any(|&v| v != 0), "the reference is black");
    assert!(a == b, "1 and 2 lavapipe threads give different references");
}
