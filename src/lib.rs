//! hybrid-rt: a Vulkan hybrid ray-tracing renderer. A raster G-buffer feeds ray-traced passes
//! (written once against a trace interface, compiled for ray query and for a compute BVH),
//! followed by denoising and tonemapping. See ../README.md for the tour.
//!
//! Dependencies point one way, down this list; a module uses only modules below it (modules
//! on one line do not use each other). `tests/layering.rs` reads every `crate::` path in src/
//! and fails on one that points up.
//!
//! ```text
//! cli                          the command line
//! app                          the viewer (window, egui overlay and its painter, scripts)
//! bench                        rays, frame, sweep, stability, soak
//! capture                      pass dumps of a renderer's frame graph
//! render                       camera, default light, frame plan, the frame loop
//! passes                       one module per pass
//! graph                        the frame graph: named outputs, barriers, timestamps
//! world                        the scene on the GPU: buffers, textures, lights, set 0
//! accel                        the two ray backends (hardware BLAS/TLAS, compute BVH)
//! backend                      which backend traces, and why
//! scene, metrics               glTF -> Scene; HDR-FLIP, PSNR, SSIM, temporal measures
//! gpu, image_io, progress      the thin Vulkan layer; EXR/PNG/HDR files; progress bars
//! ```
//!
//! `unsafe` code is denied everywhere but in `gpu`, where every unsafe block says why it is
//! sound (`clippy::undocumented_unsafe_blocks` is denied there).

#![deny(unsafe_code)]

pub mod accel;
pub mod app;
pub mod backend;
pub mod bench;
pub mod capture;
pub mod cli;
#[allow(unsafe_code)]
pub mod gpu;
pub mod graph;
pub mod image_io;
pub mod metrics;
pub mod passes;
pub mod progress;
pub mod render;
pub mod scene;
pub mod world;
