//! Feeds arbitrary bytes to the glTF loader through `load_gltf_bytes`, the entry point the
//! deterministic harness in ../tests/fuzz_loader.rs uses. Any panic, hang or allocation over
//! libFuzzer's limits is a bug in the loader.
#![no_main]

// Only the loader is exercised; the rest of the scene module is unused here.
#[allow(dead_code, unused_imports)]
#[path = "../../src/scene/mod.rs"]
mod scene;

use libfuzzer_sys::fuzz_target;
use scene::{Limits, LoadOptions};
use std::path::Path;

/// The inputs are loaded as if they lay in the committed corpus folder, so relative URIs
/// resolve to files that exist (and never outside it: `allow_outside_uris` is off).
const VIRTUAL_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/corpus/gltf/fuzz-input.glb");

/// The limits of tests/fuzz_loader.rs: small enough that no legitimate load comes near
/// libFuzzer's 2 GiB memory limit, so any report of one is an unbounded allocation.
fn fuzz_limits() -> Limits {
    Limits {
        max_triangles: 1 << 20,
        max_vertices: 1 << 20,
        max_texture_dimension: 4096,
        max_texture_pixels_total: 32 << 20,
        max_buffer_bytes: 64 << 20,
        max_total_bytes: 256 << 20,
        max_node_depth: 64,
        max_nodes: 1 << 16,
        max_data_uri_bytes: 16 << 20,
        max_instances: 1 << 20,
        max_animation_keys: 4 << 20,
        max_joints: 1 << 12,
    }
}

fuzz_target!(|data: &[u8]| {
    let opts = LoadOptions { allow_outside_uris: false, limits: fuzz_limits() };
    // Ok and Err are both fine answers to arbitrary bytes.
    let _ = scene::load_gltf_bytes(data, Path::new(VIRTUAL_PATH), &opts);
});
