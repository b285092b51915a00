//! The scene limits from the command line: every flag of `scene::limits::FLAGS` is accepted,
//! and set too low it stops the load with an error that names the file, the limit, its value
//! and the flag to raise, and a non-zero exit. The scene fails to load before any GPU work,
//! so these tests need no Vulkan device.

use base64::Engine;
use hybrid_rt::scene::limits::FLAGS;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::Command;

fn default_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default/cornell.gltf")
}

/// A one-triangle glTF whose buffer is a `data:` URI (the default scene has none).
fn data_uri_scene(dir: &Path) -> PathBuf {
    let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let gltf = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": uri, "byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
    });
    let path = dir.join("data_uri.gltf");
    std::fs::write(&path, serde_json::to_vec(&gltf).unwrap()).unwrap();
    path
}

/// The same triangle skinned to two joints (the default scene has no skin).
fn skinned_scene(dir: &Path) -> PathBuf {
    let floats = |v: &[f32]| v.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([0u16, 1, 0, 0].repeat(3).iter().flat_map(|v| v.to_le_bytes()));
    bin.extend(floats(&[0.5, 0.5, 0.0, 0.0].repeat(3)));
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let gltf = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": uri, "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": 60, "byteLength": 48},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "VEC4"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2}}]}],
        "skins": [{"joints": [1, 2]}],
        "nodes": [{"mesh": 0, "skin": 0}, {"children": [2]}, {}],
        "scenes": [{"nodes": [0, 1]}],
    });
    let path = dir.join("skinned.gltf");
    std::fs::write(&path, serde_json::to_vec(&gltf).unwrap()).unwrap();
    path
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hybrid-rt-limits-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `hybrid-rt render SCENE ARGS`; returns the exit code and stderr.
fn render(scene: &Path, args: &[&str], out_dir: &Path) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"))
        .arg("render")
        .arg(scene)
        .args(["--size", "16x16", "--force", "--out"])
        .arg(out_dir.join("out.png"))
        .args(args)
        .output()
        .expect("run hybrid-rt");
    (output.status.code(), String::from_utf8_lossy(&output.stderr).into_owned())
}

#[test]
fn each_limit_flag_stops_the_load_with_a_clear_error() {
    let dir = temp_dir();
    let cornell = default_scene();
    let data_uri = data_uri_scene(&dir);
    let skinned = skinned_scene(&dir);
    // (flag, a value too small for the scene, the limit and value the message must give). The
    // default scene has 17 nodes two deep, meshes of 6 to 2880 indices, two textures and one
    // animation.
    let cases: [(&str, &str, &Path, &str); 12] = [
        ("--max-triangles", "1", &cornell, "3 * max_triangles + 2 = 5"),
        ("--max-vertices", "3", &cornell, "max_vertices = 3"),
        ("--max-texture-size", "1", &cornell, "max_texture_dimension = 1"),
        ("--max-texture-pixels", "1", &cornell, "max_texture_pixels_total = 1"),
        ("--max-buffer-mib", "0", &cornell, "max_buffer_bytes = 0"),
        ("--max-total-mib", "0", &cornell, "max_total_bytes = 0"),
        ("--max-node-depth", "1", &cornell, "max_node_depth = 1"),
        ("--max-nodes", "1", &cornell, "max_nodes = 1"),
        ("--max-data-uri-mib", "0", &data_uri, "max_data_uri_bytes = 0"),
        ("--max-instances", "1", &cornell, "max_instances = 1"),
        ("--max-animation-keys", "1", &cornell, "max_animation_keys = 1"),
        ("--max-joints", "1", &skinned, "max_joints = 1"),
    ];
    let tested: Vec<&str> = cases.iter().map(|c| c.0).collect();
    for (_, flag) in FLAGS {
        assert!(tested.contains(&flag), "{flag} (scene::limits::FLAGS) has no case here");
    }
    for (flag, value, scene, limit) in cases {
        let (code, stderr) = render(scene, &[flag, value], &dir);
        let file = scene.file_name().unwrap().to_string_lossy();
        let context = format!("{flag} {value}: exit code {code:?}, stderr:\n{stderr}");
        assert_eq!(code, Some(1), "{context}");
        assert!(!stderr.contains("panicked"), "{context}");
        assert!(stderr.contains(&*file), "the message must name the file; {context}");
        assert!(stderr.contains(&format!("exceeds the limit {limit}")), "the message must give the limit; {context}");
        assert!(stderr.contains(&format!("(raise it with {flag})")), "the message must name the flag; {context}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn help_gives_the_defaults() {
    let output = Command::new(env!("CARGO_BIN_EXE_hybrid-rt")).args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&output.stdout);
    for (_, flag) in FLAGS {
        let line = help.lines().skip_while(|l| !l.contains(flag)).take(6).collect::<Vec<_>>().join("\n");
        assert!(line.contains("[default: "), "{flag} has no default in --help:\n{help}");
    }
    assert!(help.contains("[default: 20000000]"), "--max-triangles default:\n{help}");
}
