//! The thin Vulkan layer. Everything `unsafe` in hybrid-rt lives in this module: the rest of the
//! renderer builds passes from the safe types here (contexts, buffers, images, pipelines,
//! descriptor sets, a command recorder, timestamps).

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
mod swapchain;
mod timestamps;
pub mod upload;
mod validation;

pub use accel_struct::{
    AccelStruct, BlasBuildStats, BlasGeometry, BlasRefit, BlasRefitter, Tlas, TlasInstance, build_blases,
};
pub use commands::{CommandPool, image_barrier, memory_barrier};
pub use context::{Capabilities, Context, ContextOptions};
pub use descriptors::{Binding, BindingKind, DescriptorSet, DescriptorSetLayout, PushResource};
pub use memory::{Buffer, Image, MemoryUsage, OutOfDeviceMemory, aspect_of, texel_size};
pub use pipeline::{Pipeline, RasterDesc};
pub use present::{Overlay, Presenter, Screenshot, Shown};
pub use recorder::Recorder;
pub use sampler::{Sampler, SamplerDesc};
pub use shader::ShaderLibrary;
pub use swapchain::{Swapchain, Target};
pub use timestamps::TimestampPool;
pub use validation::ValidationLog;

pub use ash::vk;
pub use gpu_allocator::MemoryLocation;
