//! Shared test helpers: a validated Vulkan context, the shared scenes folder, temp folders.
#![allow(dead_code)] // each test binary uses a different subset of these helpers

use hybrid_rt::gpu::{Context, ContextOptions};
use std::path::PathBuf;
use std::sync::Arc;

/// A context with the Khronos validation layer and synchronization validation on.
pub fn validated_context() -> Arc<Context> {
    Context::new(&ContextOptions { validate: true, ..Default::default() }).expect("Vulkan context with validation")
}

/// Tears the context down and fails the test if the validation layer said anything, teardown
/// (leak reports) included.
pub fn assert_validation_clean(ctx: Arc<Context>) {
    let log = ctx.validation.clone();
    assert_eq!(Arc::strong_count(&ctx), 1, "something still holds the Vulkan context");
    drop(ctx);
    let messages = log.messages();
    assert!(messages.is_empty(), "validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"));
}

/// ../shared/scenes beside the repository. Missing: the test fails under CI=true and is
/// skipped (returns None, with a note) elsewhere.
pub fn shared_scenes() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("{} is missing: CI must provide ../shared/scenes beside the checkout", dir.display());
    }
    eprintln!("skipping: {} is missing (set CI=true to make this a failure)", dir.display());
    None
}

/// A fresh empty folder under the system temp dir, unique to this test process and name.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hybrid-rt-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

pub fn default_scene() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/default/cornell.gltf")
}

/// The backend `--backend auto` would pick on this device.
pub fn auto_backend(ctx: &Context) -> hybrid_rt::backend::Backend {
    hybrid_rt::backend::resolve(&ctx.caps, hybrid_rt::backend::BackendChoice::Auto).expect("auto backend").0
}
