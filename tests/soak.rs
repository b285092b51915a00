//! Long runs: 10,000 frames of the animated default scene (the Cornell box's ball moves; TAA and
//! both SVGF chains carry history), headless at 32x32 with the validation layer on throughout:
//! its core checks, not synchronization validation, whose submit-time history grows by about
//! 14 KiB a frame in the layer itself (measured: 141,852 KiB over 9,500 frames with it, flat
//! without; see `ContextOptions::without_sync_validation`). Every other test runs this same
//! frame with synchronization validation on.
//! Memory is sampled after a 500-frame warm-up and every 500 frames after (src/bench/soak.rs,
//! also `hybrid-rt bench soak`, which runs it at any size):
//! - device memory (what gpu-allocator holds: live allocations and memory blocks) must not
//!   change at all: every resource is made before the first frame and reused;
//! - host memory (VmRSS) must not trend upwards: the least-squares slope over the second half
//!   of the run is at most `soak::HOST_TREND_BOUND` (640 bytes a frame; its derivation and unit
//!   tests are in src/bench/soak.rs). Not a bound on total growth: on a fresh machine the
//!   allocators settle in 1 MiB steps for the first few thousand frames (4,228 KiB by frame
//!   4,500, flat after), which says nothing about a leak; a leak shows as a steady slope;
//! - the validation layer says nothing, teardown included.
//!
//! On lavapipe (2 cores) this takes about 2.5 minutes; 32x32 is chosen so the full frame count
//! fits in the test's time, the work per frame being mostly fixed cost (recording, validation,
//! submission), not pixels.

mod common;

use hybrid_rt::bench::soak;
use hybrid_rt::render::Settings;

#[test]
fn ten_thousand_frames_keep_memory_flat_and_validation_silent() {
    let ctx = hybrid_rt::gpu::Context::new(&hybrid_rt::gpu::ContextOptions {
        validate: true,
        without_sync_validation: true,
        ..Default::default()
    })
    .expect("Vulkan context with core validation");
    let backend = common::auto_backend(&ctx);
    let scene = hybrid_rt::scene::load_gltf(&common::default_scene(), &Default::default()).unwrap();
    assert!(scene.is_animated(), "the soak needs a moving scene");
    let settings = Settings { width: 32, height: 32, taa: true, ..Default::default() };
    let mut r = common::renderer(&ctx, scene, settings, backend);
    let opts = soak::Options { frames: 10_000, warmup: 500, every: 500 };
    let result = soak::run(&mut r, &opts, &|_| {}).unwrap();
    eprintln!("{} backend\n{}", backend.variant(), soak::table(&result));
    drop(r);

    assert_eq!(result.samples.len(), 20, "a baseline and 19 samples");
    let base = &result.samples[0];
    for s in &result.samples {
        assert_eq!(s.gpu, base.gpu, "device memory changed between frames {} and {}", base.frame, s.frame);
    }
    let host: Vec<(u32, u64)> = result.samples.iter().map(|s| (s.frame, s.host_rss_bytes)).collect();
    if let Err(e) = soak::check_host_trend(&host) {
        panic!("{e}");
    }
    common::assert_validation_clean(ctx);
}
