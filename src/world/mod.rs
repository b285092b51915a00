//! The scene on the GPU, which every pass reads: vertex, index, material and instance buffers,
//! textures, the lights and their sampling tables, the environment, the BRDF's tabulated data,
//! deformed (morphed or skinned) vertices and the ray backend's structures over them, all bound as descriptor set 0
//! (common/scene.glsl). It sits below graph and passes, which take a `&SceneGpu` when they
//! record, and above the ray backends it builds.

pub mod brdf;
mod deform;
pub mod environment;
pub mod light_grid;
pub mod lights;
mod mips;
pub mod scene_gpu;
pub mod skinning;

pub use scene_gpu::{FrameUniforms, SceneGpu};
