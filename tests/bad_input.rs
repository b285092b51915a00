//! Bad input through the command line: each case gives a clear error that names the file and
//! the problem, a non-zero exit, and no panic. The files are made here from a small valid
//! glTF, each with one defect.

mod common;

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One triangle: positions as a base64-free external buffer "tri.bin".
fn valid_gltf(positions: [[f32; 3]; 3], indices: [u32; 3]) -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    for p in positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let gltf = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": "tri.bin", "byteLength": 48}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ]
    });
    (gltf, bin)
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn write_case(dir: &Path, name: &str, gltf: &Value, bin: &[u8]) -> PathBuf {
    let case = dir.join(name);
    std::fs::create_dir_all(&case).unwrap();
    std::fs::write(case.join("tri.bin"), bin).unwrap();
    let path = case.join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec_pretty(gltf).unwrap()).unwrap();
    path
}

/// A GLB container holding the JSON with an embedded BIN chunk.
fn glb(gltf: &Value, bin: &[u8]) -> Vec<u8> {
    let mut g = gltf.clone();
    g["buffers"] = json!([{"byteLength": bin.len()}]);
    let mut json = serde_json::to_vec(&g).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Runs `hybrid-rt render FILE` and returns (success, stderr).
fn render(path: &Path, extra: &[&str]) -> (bool, String) {
    let out_png = path.with_extension("out.png");
    let output = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .arg("render")
        .arg(path)
        .args(["--size", "16x16", "--out"])
        .arg(&out_png)
        .args(extra)
        .output()
        .expect("run hybrid-rt");
    (output.status.success(), String::from_utf8_lossy(&output.stderr).into_owned())
}

/// Fails the test unless the command failed cleanly with a message naming `file` and one of
/// the `problem` words.
fn expect_error(path: &Path, file: &str, problem: &[&str]) {
    let (ok, stderr) = render(path, &[]);
    assert!(!ok, "{}: expected an error, the render succeeded", path.display());
    assert!(!stderr.contains("panicked"), "{}: panicked:\n{stderr}", path.display());
    assert!(stderr.contains(file), "{}: message does not name {file}:\n{stderr}", path.display());
    let lower = stderr.to_lowercase();
    assert!(
        problem.iter().any(|w| lower.contains(&w.to_lowercase())),
        "{}: message does not name the problem (one of {problem:?}):\n{stderr}",
        path.display()
    );
}

#[test]
fn bad_scene_files_fail_cleanly() {
    let dir = common::temp_dir("bad-input");
    let (good, bin) = valid_gltf(TRI, [0, 1, 2]);

    // The valid file loads and renders, so each failure below is the defect's doing.
    let ok = write_case(&dir, "valid", &good, &bin);
    let (success, stderr) = render(&ok, &[]);
    assert!(success, "the valid triangle must render:\n{stderr}");

    expect_error(
        &dir.join("missing.gltf"),
        "missing.gltf",
        &["not found", "no such file", "cannot open", "cannot read"],
    );

    let glb_bytes = glb(&good, &bin);
    let truncated = dir.join("truncated.glb");
    std::fs::write(&truncated, &glb_bytes[..glb_bytes.len() / 2]).unwrap();
    expect_error(&truncated, "truncated.glb", &["truncated", "too short", "length", "shorter"]);

    let mut wrong = glb_bytes.clone();
    wrong[..4].copy_from_slice(b"gLTX");
    let wrong_magic = dir.join("wrong_magic.glb");
    std::fs::write(&wrong_magic, &wrong).unwrap();
    expect_error(&wrong_magic, "wrong_magic.glb", &["magic", "not a gltf", "not glTF"]);

    let mut g = good.clone();
    g["bufferViews"][1]["byteLength"] = json!(4000);
    expect_error(&write_case(&dir, "view_out_of_range", &g, &bin), "scene.gltf", &["range", "beyond", "exceeds"]);

    let (g, b) = valid_gltf(TRI, [0, 1, 99]);
    expect_error(&write_case(&dir, "index_out_of_range", &g, &b), "scene.gltf", &["index", "range"]);

    let (g, b) = valid_gltf([[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 2]);
    expect_error(&write_case(&dir, "nan", &g, &b), "scene.gltf", &["nan", "not finite", "non-finite"]);

    let mut g = good.clone();
    g["meshes"][0]["primitives"][0]["mode"] = json!(0);
    expect_error(&write_case(&dir, "no_triangles", &g, &bin), "scene.gltf", &["zero triangles", "no triangles"]);

    let mut g = good.clone();
    g["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    g["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    expect_error(&write_case(&dir, "required_ext", &g, &bin), "scene.gltf", &["KHR_draco_mesh_compression"]);

    let mut g = good.clone();
    g["buffers"][0]["uri"] = json!("../outside.bin");
    let outside = write_case(&dir, "outside", &g, &bin);
    std::fs::write(dir.join("outside.bin"), &bin).unwrap();
    expect_error(&outside, "scene.gltf", &["outside", "allow-outside-uris"]);
    let (allowed, stderr) = render(&outside, &["--allow-outside-uris", "--force"]);
    assert!(allowed, "--allow-outside-uris must let the file load:\n{stderr}");

    let mut g = good.clone();
    g["images"] = json!([{"uri": "broken.png"}]);
    g["textures"] = json!([{"source": 0}]);
    g["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    g["meshes"][0]["primitives"][0]["material"] = json!(0);
    let broken = write_case(&dir, "broken_image", &g, &bin);
    std::fs::write(broken.parent().unwrap().join("broken.png"), b"\x89PNG\r\n\x1a\nthis is not a png").unwrap();
    expect_error(&broken, "broken.png", &["decode", "image"]);

    let not_json = dir.join("garbage.gltf");
    std::fs::write(&not_json, b"{ this is not json").unwrap();
    expect_error(&not_json, "garbage.gltf", &["json", "parse", "syntax"]);
}

#[test]
fn existing_output_is_not_overwritten_without_force() {
    let dir = common::temp_dir("overwrite");
    let (good, bin) = valid_gltf(TRI, [0, 1, 2]);
    let scene = write_case(&dir, "valid", &good, &bin);
    let out = dir.join("keep.png");
    std::fs::write(&out, b"precious").unwrap();
    let run = |force: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
        c.arg("render").arg(&scene).args(["--size", "8x8", "--out"]).arg(&out);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    let refused = run(false);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--force"));
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
    assert!(run(true).status.success());
    assert_ne!(std::fs::read(&out).unwrap(), b"precious");
}
