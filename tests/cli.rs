//! The command line end to end: pass capture (files, manifest, exact values), frame lists,
//! refusal to overwrite a capture, `info`, the compute fall-back when ray tracing is hidden,
//! runtime shader compilation errors that point at file and line, and output read through a
//! pipe that closes early.

mod common;

use hybrid_rt::passes;
use std::path::Path;
use std::process::{Command, Output};

fn hybrid_rt(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run hybrid-rt")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn manifest(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).expect("manifest.json")).expect("valid JSON")
}

#[test]
fn dump_passes_writes_every_output_with_exact_values() {
    let dir = common::temp_dir("capture");
    let dump = dir.join("dump");
    let out = dir.join("frame.exr");
    let o =
        hybrid_rt(&["render", "builtin:gbuffer-test", "--size", "40x30", "--frames", "2", "--validate", "--out"], &[]);
    assert!(!o.status.success(), "render without --out value must fail");
    let o = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            // Every pass, so that every kind of output is dumped (the plan would leave the
            // soft-shadow chain out: this scene's lights are punctual).
            "--full",
            "--size",
            "40x30",
            "--frames",
            "2",
            "--validate",
            "--out",
            out.to_str().unwrap(),
            "--dump-passes",
            dump.to_str().unwrap(),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    let m = manifest(&dump);
    let entries = m["entries"].as_array().unwrap();
    let names: Vec<&str> = entries.iter().map(|e| e["output"].as_str().unwrap()).collect();
    for expected in [
        passes::gbuffer::DEPTH,
        passes::gbuffer::NORMAL,
        passes::gbuffer::MOTION,
        passes::gbuffer::IDS,
        passes::shadows::trace::SAMPLE_COUNT,
        passes::shadows::penumbra::DV_RAW,
        passes::shadows::filter::VISIBILITY,
        passes::shadows::filter::KERNEL,
        passes::composite::COLOR,
        passes::tonemap::COLOR,
    ] {
        let expected = expected.to_string();
        assert!(names.contains(&expected.as_str()), "manifest lacks {expected}: {names:?}");
    }
    for e in entries {
        assert_eq!(e["frame"], 2, "the last frame is dumped by default");
        let size = (e["width"].as_u64(), e["height"].as_u64());
        // Statistics (sums, counters) are 1x1; everything else is frame-sized.
        assert!(size == (Some(40), Some(30)) || size == (Some(1), Some(1)), "{e}");
        assert!(e["pass"].as_str().is_some_and(|p| e["output"].as_str().unwrap().starts_with(&format!("{p}."))));
        assert!(e["gpu_ms"].as_f64().is_some_and(|t| t >= 0.0), "{e}");
        for key in ["exr", "png"] {
            let f = dump.join(e[key].as_str().unwrap());
            assert!(f.is_file() && f.metadata().unwrap().len() > 0, "missing {}", f.display());
        }
    }
    // The EXR holds exact values: the plane of the test scene sits at depth 10 exactly.
    let depth = hybrid_rt::image_io::read_exr_channels(&dump.join("gbuffer.depth.exr")).unwrap();
    let at = depth.get(2, 2, 0);
    assert!((at - 10.0).abs() < 1e-5, "gbuffer.depth.exr at (2,2) = {at}");
    // The HDR output is linear EXR.
    assert!(hybrid_rt::image_io::read_exr_channels(&out).is_ok());

    // A second capture into the same folder is refused without --force.
    let again = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            "--size",
            "8x8",
            "--out",
            dir.join("b.png").to_str().unwrap(),
            "--dump-passes",
            dump.to_str().unwrap(),
        ],
        &[],
    );
    assert!(!again.status.success());
    assert!(text(&again).contains("--force"), "{}", text(&again));
}

#[test]
fn dump_frames_writes_one_folder_per_listed_frame() {
    let dir = common::temp_dir("dump-frames");
    let dump = dir.join("dump");
    let o = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            "--size",
            "16x16",
            "--frames",
            "4",
            "--out",
            dir.join("x.png").to_str().unwrap(),
            "--dump-passes",
            dump.to_str().unwrap(),
            "--dump-frames",
            "1,3",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(dump.join("frame_0001/gbuffer.ids.exr").is_file());
    assert!(dump.join("frame_0003/gbuffer.ids.png").is_file());
    assert!(!dump.join("frame_0002").exists() && !dump.join("frame_0004").exists());
    let frames: Vec<u64> =
        manifest(&dump)["entries"].as_array().unwrap().iter().map(|e| e["frame"].as_u64().unwrap()).collect();
    assert!(frames.contains(&1) && frames.contains(&3) && !frames.contains(&2));
    let bad = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            "--frames",
            "2",
            "--dump-passes",
            dump.to_str().unwrap(),
            "--dump-frames",
            "5",
            "--force",
        ],
        &[],
    );
    assert!(!bad.status.success() && text(&bad).contains("--dump-frames 5"), "{}", text(&bad));
}

#[test]
fn info_reports_the_backend_and_falls_back_without_ray_tracing() {
    let o = hybrid_rt(&["info", "--validate"], &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("ray backend:"), "{}", text(&o));
    let hidden = hybrid_rt(&["info", "--json"], &[("HYBRID_RT_HIDE_RAY_TRACING", "1")]);
    assert!(hidden.status.success(), "{}", text(&hidden));
    let v: serde_json::Value = serde_json::from_slice(&hidden.stdout).unwrap();
    assert_eq!(v["backend"], "compute", "auto must fall back to the compute backend: {v}");
    assert!(v["reason"].as_str().unwrap().contains("hidden"), "{v}");
    // Rendering works on the fall-back, and asking for ray query explains why it cannot.
    let dir = common::temp_dir("fallback");
    let r = hybrid_rt(
        &["render", "--size", "24x24", "--validate", "--out", dir.join("a.png").to_str().unwrap()],
        &[("HYBRID_RT_HIDE_RAY_TRACING", "1")],
    );
    assert!(r.status.success(), "{}", text(&r));
    assert!(text(&r).contains("compute backend"), "{}", text(&r));
    let rq = hybrid_rt(
        &["render", "--backend", "rayquery", "--out", dir.join("b.png").to_str().unwrap()],
        &[("HYBRID_RT_HIDE_RAY_TRACING", "1")],
    );
    assert!(!rq.status.success() && text(&rq).contains("cannot trace with ray queries"), "{}", text(&rq));
}

#[test]
#[cfg_attr(
    not(feature = "shader-compiler"),
    ignore = "compiles GLSL at run time: needs --features shader-compiler (tools/test.sh)"
)]
fn runtime_shader_errors_name_file_and_line() {
    let dir = common::temp_dir("shaders");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders-glsl");
    let copy = dir.join("shaders-glsl");
    common::copy_dir(&src, &copy);
    // The unchanged copy compiles and renders.
    let ok = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            "--size",
            "8x8",
            "--out",
            dir.join("a.png").to_str().unwrap(),
            "--shader-dir",
            copy.to_str().unwrap(),
        ],
        &[],
    );
    assert!(ok.status.success(), "{}", text(&ok));
    // Break line 3 of tonemap.comp.
    let path = copy.join("tonemap.comp");
    let mut lines: Vec<String> = std::fs::read_to_string(&path).unwrap().lines().map(String::from).collect();
    lines.insert(2, "this is not glsl;".into());
    std::fs::write(&path, lines.join("\n")).unwrap();
    let bad = hybrid_rt(
        &[
            "render",
            "builtin:gbuffer-test",
            "--size",
            "8x8",
            "--out",
            dir.join("b.png").to_str().unwrap(),
            "--shader-dir",
            copy.to_str().unwrap(),
        ],
        &[],
    );
    assert!(!bad.status.success());
    let msg = text(&bad);
    assert!(msg.contains("tonemap.comp:3:") && msg.contains("error"), "{msg}");
    assert!(!msg.contains("panicked"), "{msg}");
}

/// A build without the runtime compiler refuses `--shader-dir` with the way to get one, no
/// panic. (tools/test.sh builds with the compiler, so only a plain `cargo test` runs this.)
#[cfg(not(feature = "shader-compiler"))]
#[test]
fn without_the_shader_compiler_shader_dir_says_how_to_rebuild() {
    let dir = common::temp_dir("no-compiler");
    let glsl = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders-glsl");
    let out = dir.join("a.png");
    let r = hybrid_rt(&["render", "--out", out.to_str().unwrap(), "--shader-dir", glsl.to_str().unwrap()], &[]);
    let msg = text(&r);
    assert!(!r.status.success() && msg.contains("--features shader-compiler"), "{msg}");
    assert!(!msg.contains("panicked") && !out.exists(), "{msg}");
}

/// Output read only in part (`hybrid-rt plan | head`): the command stops quietly, with success
/// and no panic, where `println!` panicked on the closed pipe ("failed printing to stdout:
/// Broken pipe") with a backtrace.
#[test]
fn a_reader_that_stops_early_ends_the_command_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .args(["plan", "builtin:many-lights"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes away before the plan (which takes a tenth of a second) is printed.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked") && stderr.is_empty(), "{stderr}");
}
