//! hybrid-rt: a Vulkan hybrid ray-tracing renderer. A raster G-buffer feeds ray-traced passes
//! (written once against a trace interface, compiled for ray query and for a compute BVH),
//! followed by denoising and tonemapping. See ../README.md for the tour.

pub mod accel;
pub mod app;
pub mod backend;
pub mod bench;
pub mod capture;
pub mod cli;
pub mod gpu;
pub mod graph;
pub mod image_io;
pub mod metrics;
pub mod passes;
pub mod render;
pub mod scene;
