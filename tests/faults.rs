//! Faults end in a clear message and a clean exit (non-zero, no panic) or a clean fall-back.
//! Each is forced for real where that can be done on any machine:
//! - no Vulkan driver: the loader is pointed at a driver file that does not exist, or at an
//!   empty folder;
//! - too old a Vulkan: `HYBRID_RT_REQUIRE_VULKAN` raises the version the loader and device
//!   checks demand (the checks themselves are the ones every run makes);
//! - no validation layer with `--validate`: the loader's layer path is pointed at an empty folder;
//! - no ray query, or no acceleration structures: `HYBRID_RT_HIDE_RAY_TRACING` hides one;
//! - out of device memory: `HYBRID_RT_MEMORY_LIMIT_MIB` caps what may be allocated, failing
//!   over it exactly as gpu-allocator fails on a full device;
//! - a shader that no longer compiles at hot reload: the library keeps serving the old SPIR-V.
//!
//! Device loss cannot be caused on demand (lavapipe never loses its device): its message is a
//! unit test in src/gpu/commands.rs.

mod common;

use hybrid_rt::backend::Backend;
use hybrid_rt::gpu::ShaderLibrary;
use hybrid_rt::render::{CameraChoice, Renderer, Settings};
use std::path::Path;
use std::process::{Command, Output};

/// Runs the binary with the loader's driver and layer overrides of the calling environment
/// removed (so each test sets exactly the ones it means), plus `env`.
fn hybrid_rt(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.args(args);
    for k in ["VK_DRIVER_FILES", "VK_ICD_FILENAMES", "VK_ADD_DRIVER_FILES", "VK_LAYER_PATH", "VK_ADD_LAYER_PATH"] {
        c.env_remove(k);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run hybrid-rt")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A clean failure: non-zero exit, `error:` followed by `expected`, no panic.
fn assert_clean_failure(o: &Output, expected: &str) {
    let t = text(o);
    assert!(!o.status.success(), "expected a failure, got success:\n{t}");
    assert_eq!(o.status.code(), Some(1), "expected exit code 1 (a signal or panic is not clean):\n{t}");
    assert!(t.contains("error: ") && t.contains(expected), "expected '{expected}' in:\n{t}");
    assert!(!t.contains("panicked"), "{t}");
}

#[test]
fn no_vulkan_driver_is_named() {
    let empty = common::temp_dir("no-driver");
    let missing = empty.join("no-such-driver.json");
    for (var, value) in [
        ("VK_DRIVER_FILES", missing.to_str().unwrap()),
        ("VK_ICD_FILENAMES", missing.to_str().unwrap()),
        ("VK_DRIVER_FILES", empty.to_str().unwrap()),
    ] {
        for args in [&["info"][..], &["render", "--size", "8x8", "--out", empty.join("x.png").to_str().unwrap()][..]] {
            let o = hybrid_rt(args, &[(var, value)]);
            assert_clean_failure(&o, "no Vulkan device found");
            // The override is named: a stale one is the usual cause.
            assert!(text(&o).contains(var) && text(&o).contains("install a Vulkan driver"), "{}", text(&o));
        }
    }
    assert!(!empty.join("x.png").exists());
}

#[test]
fn too_old_a_vulkan_is_refused_by_the_version_checks() {
    // No Vulkan 1.9 exists, so the loader check fails (the device check, after it, uses the same
    // required version; a loader older than the device, as on this machine's Debian 12, fails
    // first).
    let o = hybrid_rt(&["info"], &[("HYBRID_RT_REQUIRE_VULKAN", "1.9")]);
    assert_clean_failure(&o, "needs 1.9 or newer");
    // The renderer's own minimum passes (the variable only raises the bar), and nonsense is refused.
    let ok = hybrid_rt(&["info"], &[("HYBRID_RT_REQUIRE_VULKAN", "1.0")]);
    assert!(ok.status.success(), "{}", text(&ok));
    let bad = hybrid_rt(&["info"], &[("HYBRID_RT_REQUIRE_VULKAN", "new")]);
    assert_clean_failure(&bad, "expected MAJOR.MINOR");
}

#[test]
fn validation_without_the_layer_is_refused() {
    let empty = common::temp_dir("no-layer");
    let o = hybrid_rt(&["info", "--validate"], &[("VK_LAYER_PATH", empty.to_str().unwrap())]);
    assert_clean_failure(&o, "the Khronos validation layer is not installed");
}

#[test]
fn a_device_missing_one_ray_tracing_extension_falls_back_to_compute() {
    let full = hybrid_rt(&["info", "--json"], &[]);
    assert!(full.status.success(), "{}", text(&full));
    let caps: serde_json::Value = serde_json::from_slice(&full.stdout).unwrap();
    let dir = common::temp_dir("hide-one");
    for (hide, missing) in
        [("acceleration_structure", "no VK_KHR_acceleration_structure"), ("ray_query", "no VK_KHR_ray_query")]
    {
        let env = [("HYBRID_RT_HIDE_RAY_TRACING", hide)];
        let info = hybrid_rt(&["info", "--json"], &env);
        assert!(info.status.success(), "{}", text(&info));
        let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
        assert_eq!(v["backend"], "compute", "{v}");
        let reason = v["reason"].as_str().unwrap();
        assert!(reason.contains(missing) && reason.contains("hidden"), "{reason}");
        // Only the named extension is hidden: the other keeps what the device reports.
        let other = if hide == "ray_query" { "acceleration_structure" } else { "ray_query" };
        assert_eq!(v["device"][other], caps["device"][other], "{v}");
        assert_eq!(v["device"][hide], false, "{v}");
        let out = dir.join(format!("{hide}.png"));
        let r = hybrid_rt(&["render", "--size", "16x16", "--validate", "--out", out.to_str().unwrap()], &env);
        assert!(r.status.success() && text(&r).contains("compute backend"), "{}", text(&r));
        let rq = hybrid_rt(&["render", "--backend", "rayquery", "--out", dir.join("rq.png").to_str().unwrap()], &env);
        assert_clean_failure(&rq, missing);
    }
}

#[test]
fn out_of_device_memory_names_the_allocation_and_suggests_a_smaller_size() {
    let dir = common::temp_dir("oom");
    let cap = [("HYBRID_RT_MEMORY_LIMIT_MIB", "64")];
    // Under the cap a small frame renders, validation clean.
    let small = dir.join("small.png");
    let ok = hybrid_rt(&["render", "--size", "32x32", "--validate", "--out", small.to_str().unwrap()], &cap);
    assert!(ok.status.success(), "{}", text(&ok));
    // A 2048x2048 frame needs far more than 64 MiB (one RGBA32F image alone is 64 MiB): the
    // run stops at the first allocation past the cap, names it, frees what it made (validation
    // stays silent through the teardown) and writes nothing.
    let big = dir.join("big.png");
    let o = hybrid_rt(&["render", "--size", "2048x2048", "--validate", "--out", big.to_str().unwrap()], &cap);
    assert_clean_failure(&o, "out of memory allocating image ");
    let t = text(&o);
    assert!(t.contains("2048x2048") && t.contains("MiB") && t.contains("a smaller --size"), "{t}");
    assert!(!t.contains("validation error") && !t.contains("validation warning"), "{t}");
    assert!(!big.exists());
    let bad = hybrid_rt(&["info"], &[("HYBRID_RT_MEMORY_LIMIT_MIB", "lots")]);
    assert_clean_failure(&bad, "HYBRID_RT_MEMORY_LIMIT_MIB=lots");
}

#[test]
#[cfg_attr(
    not(feature = "shader-compiler"),
    ignore = "compiles GLSL at run time: needs --features shader-compiler (tools/test.sh)"
)]
fn a_shader_broken_at_hot_reload_keeps_the_old_module() {
    let dir = common::temp_dir("reload");
    let copy = dir.join("shaders-glsl");
    common::copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders-glsl"), &copy);
    let mut lib = ShaderLibrary::from_dir(&copy).expect("the shipped shaders compile");
    let before = lib.get("tonemap.comp").unwrap();

    let path = copy.join("tonemap.comp");
    let good = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<&str> = good.lines().collect();
    lines.insert(2, "this is not glsl;");
    std::fs::write(&path, lines.join("\n")).unwrap();
    let err = format!("{:#}", lib.recompile().expect_err("a broken shader must not compile"));
    assert!(err.contains("tonemap.comp:3:") && err.contains("error"), "{err}");
    assert_eq!(lib.get("tonemap.comp").unwrap(), before, "the old SPIR-V must stay in use");

    // The library still builds a working frame from what it kept.
    let ctx = common::validated_context();
    let settings = Settings { width: 16, height: 16, ..Default::default() };
    let scene = hybrid_rt::scene::builtin::by_name("gbuffer-test").unwrap();
    let mut r = Renderer::new(&ctx, &lib, scene, settings, &CameraChoice::Default, Backend::Compute).unwrap();
    r.render_frame().unwrap();
    drop(r);
    common::assert_validation_clean(ctx);

    // Fixed again, the next reload succeeds.
    std::fs::write(&path, good).unwrap();
    lib.recompile().expect("the repaired shader compiles");
    assert_eq!(lib.get("tonemap.comp").unwrap(), before);
}
