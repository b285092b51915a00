//! Which ray backend traces the ray-traced passes, and why.

use crate::gpu::Capabilities;
use anyhow::{Result, bail};

/// What the user asked for (`--backend`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendChoice {
    /// Ray query where the device has it, else the compute BVH.
    #[default]
    Auto,
    /// VK_KHR_ray_query against BLAS/TLAS built with VK_KHR_acceleration_structure.
    Rayquery,
    /// The project's own BVH traversed in compute shaders; works on any Vulkan 1.2 device.
    Compute,
}

/// The backend actually used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    RayQuery,
    Compute,
}

impl Backend {
    /// The shader variant suffix (`name.comp:rayquery`).
    pub fn variant(self) -> &'static str {
        match self {
            Backend::RayQuery => "rayquery",
            Backend::Compute => "compute",
        }
    }
}

/// Picks the backend for a device and says why.
pub fn resolve(caps: &Capabilities, choice: BackendChoice) -> Result<(Backend, String)> {
    let missing = || {
        let mut m = Vec::new();
        if !caps.acceleration_structure {
            m.push("no VK_KHR_acceleration_structure");
        }
        if !caps.ray_query {
            m.push("no VK_KHR_ray_query");
        }
        if !caps.buffer_device_address {
            m.push("no bufferDeviceAddress");
        }
        if !caps.deferred_host_operations {
            m.push("no VK_KHR_deferred_host_operations");
        }
        let m = m.join(", ");
        if caps.ray_tracing_hidden { format!("{m}: hidden by request (HYBRID_RT_HIDE_RAY_TRACING)") } else { m }
    };
    match choice {
        BackendChoice::Compute => Ok((Backend::Compute, "forced by --backend compute".into())),
        BackendChoice::Rayquery if caps.supports_ray_query() => {
            Ok((Backend::RayQuery, "forced by --backend rayquery".into()))
        }
        BackendChoice::Rayquery => bail!(
            "--backend rayquery: the device '{}' cannot trace with ray queries ({}); use --backend compute or auto",
            caps.device_name,
            missing()
        ),
        BackendChoice::Auto if caps.supports_ray_query() => Ok((
            Backend::RayQuery,
            "auto: the device has acceleration structures, ray query and buffer device addresses".into(),
        )),
        BackendChoice::Auto => Ok((Backend::Compute, format!("auto: ray query unavailable ({})", missing()))),
    }
}
