//! The thin Vulkan layer. Everything `unsafe` in hybrid-rt lives in this module (the crate
//! denies `unsafe_code` everywhere else): the rest of the renderer builds passes from the safe
//! types here (contexts, buffers, images, pipelines, descriptor sets, a command recorder,
//! timestamps, the viewer's presenter). It depends on nothing else in the crate.
//!
//! What the safe types guarantee, and what the `// SAFETY:` comment on every unsafe block
//! here argues from:
//! - Lifetimes. Every object holds an `Arc<Context>`, so the device (and instance) outlive
//!   every handle made from them; each object destroys only the handles it created, once, in
//!   `Drop`, after waiting for the work that may still use them where that can be pending.
//! - Handles. Handles passed to Vulkan come from this layer's own objects (`Buffer::raw`,
//!   `Image::view`, `Pipeline::layout`, ...), borrowed for the call, so they are live.
//! - Host memory. Create-info structs and slices handed to ash live on the stack or in a local
//!   `Vec` for the whole call; ash's builders tie their lifetimes to what they point at.
//! - Host synchronisation. A `Context` is shared, but each command buffer, pool, fence and
//!   query pool is used from one thread at a time (`&mut self`, or one recorder per frame).
//!
//! The limit: the command-stream rules of the Vulkan spec (a pipeline bound before a dispatch,
//! image layouts, barriers between passes, descriptor types matching the shader) are kept by
//! the renderer's usage, not by these types; the Khronos validation layer checks them in every
//! test, and any message fails it. Types that carry raw handles or device addresses from
//! outside (`Recorder`'s command buffer, `PushResource`, `TimestampPool::reset`,
//! `BlasGeometry` and `TlasInstance` addresses) require them to come from this layer's live
//! objects, and every caller in the crate passes such; the types cannot enforce it.

#![deny(clippy::undocumented_unsafe_blocks, clippy::missing_safety_doc)]

mod accel_struct;
mod commands;
mod context;
mod descriptors;
mod memory;
mod pipeline;
mod present;
mod recorder;
mod sampler;
pub mod shader;
#[cfg(feature = "shader-compiler")]
mod shader_compile;
pub mod shader_sources;
pub mod staged;
mod swapchain;
mod timestamps;
pub mod upload;
mod validation;

pub use accel_struct::{
    AccelStruct, BlasBuildStats, BlasGeometry, BlasRefit, BlasRefitter, Tlas, TlasInstance, build_blases,
};
pub use commands::CommandPool;
// Barriers on a raw command buffer stay inside this layer; passes use `Recorder::memory_barrier`.
use commands::{image_barrier, memory_barrier};
pub use context::{Capabilities, Context, ContextOptions};
pub use descriptors::{Binding, BindingKind, DescriptorSet, DescriptorSetLayout, PushResource};
pub use memory::{Buffer, Image, MemoryUsage, OutOfDeviceMemory, aspect_of, texel_size};
pub use pipeline::{Pipeline, RasterDesc};
pub use present::{
    Overlay, OverlayDraw, OverlayTextureId, OverlayTextureUpdate, OverlayVertex, Presenter, Screenshot, Shown,
};
pub use recorder::Recorder;
pub use sampler::{Sampler, SamplerDesc};
pub use shader::{RAY_VARIANTS, ShaderLibrary};
pub use swapchain::{Swapchain, Target};
pub use timestamps::TimestampPool;
pub use validation::{ValidationLog, finish_validation};

pub use ash::vk;
pub use gpu_allocator::MemoryLocation;
