//! Instance and device: the one place that talks to the Vulkan loader. Creates the instance
//! (with the Khronos validation layer and synchronization validation when asked), probes the
//! device's capabilities, and creates the logical device with exactly the features the
//! renderer uses, so that `hybrid-rt info` can say what the device can do and why a backend
//! was picked.

use super::validation::ValidationLog;
use anyhow::{Context as _, Result, anyhow, bail};
use ash::vk;
use std::ffi::{CStr, CString, c_char};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How the context is created.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable the Khronos validation layer with synchronization validation.
    pub validate: bool,
    /// With `validate`, leave synchronization validation out (core validation only). For long
    /// runs: the layer's submit-time synchronization checks keep a history that grows by about
    /// 14 KiB a frame here (measured over 10,000 frames; flat without them), which would hide
    /// the renderer's own memory behaviour.
    pub without_sync_validation: bool,
    /// Pretend the device lacks ray query and acceleration structures (tests, fall-back path).
    pub hide_ray_tracing: bool,
    /// The display a window will be shown on (the viewer): the instance gets the surface
    /// extensions it needs and the device VK_KHR_swapchain. `None` (headless) changes nothing.
    pub window: Option<raw_window_handle::RawDisplayHandle>,
    /// Most bytes of device memory the renderer may allocate (tests: `HYBRID_RT_MEMORY_LIMIT_MIB`);
    /// past it an allocation fails exactly as on a full device (see memory.rs).
    pub memory_limit: Option<u64>,
}

/// The oldest Vulkan hybrid-rt runs on: dynamic rendering and synchronization2 come from core
/// 1.3 or from their KHR extensions on 1.2.
const MIN_VULKAN: u32 = vk::API_VERSION_1_2;

/// The version the loader and the device must reach: 1.2, or more when
/// `HYBRID_RT_REQUIRE_VULKAN=MAJOR.MINOR` asks. Tests raise it to drive the two version checks
/// (loader, device) on a machine whose Vulkan is new enough; it can only raise the bar.
fn required_version() -> Result<u32> {
    let Some(v) = std::env::var_os("HYBRID_RT_REQUIRE_VULKAN") else {
        return Ok(MIN_VULKAN);
    };
    let s = v.to_string_lossy();
    let parsed = s.split_once('.').and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)));
    match parsed {
        // The field widths of VK_MAKE_API_VERSION.
        Some((major, minor)) if major < 128 && minor < 1024 => {
            Ok(vk::make_api_version(0, major, minor, 0).max(MIN_VULKAN))
        }
        _ => bail!("HYBRID_RT_REQUIRE_VULKAN={s}: expected MAJOR.MINOR, e.g. 1.3"),
    }
}

fn version_text(v: u32) -> String {
    format!("{}.{}", vk::api_version_major(v), vk::api_version_minor(v))
}

/// Ray-tracing extensions the probe pretends the device lacks: `HYBRID_RT_HIDE_RAY_TRACING`
/// set to `acceleration_structure` or `ray_query` hides that one, any other value all of them
/// (with deferred host operations), as does `ContextOptions::hide_ray_tracing`.
#[derive(Clone, Copy, Default)]
struct Hidden {
    acceleration_structure: bool,
    ray_query: bool,
    deferred_host_operations: bool,
}

impl Hidden {
    fn new(all: bool) -> Self {
        let every = Self { acceleration_structure: true, ray_query: true, deferred_host_operations: true };
        if all {
            return every;
        }
        match std::env::var("HYBRID_RT_HIDE_RAY_TRACING").ok().as_deref() {
            None => Self::default(),
            Some("acceleration_structure") => Self { acceleration_structure: true, ..Self::default() },
            Some("ray_query") => Self { ray_query: true, ..Self::default() },
            Some(_) => every,
        }
    }

    fn any(&self) -> bool {
        self.acceleration_structure || self.ray_query || self.deferred_host_operations
    }
}

/// `HYBRID_RT_MEMORY_LIMIT_MIB`, in bytes.
fn memory_limit_from_env() -> Result<Option<u64>> {
    let Some(v) = std::env::var_os("HYBRID_RT_MEMORY_LIMIT_MIB") else {
        return Ok(None);
    };
    let s = v.to_string_lossy();
    match s.parse::<u64>() {
        Ok(mib) => Ok(Some(mib.saturating_mul(1 << 20))),
        Err(_) => bail!("HYBRID_RT_MEMORY_LIMIT_MIB={s}: expected a whole number of MiB"),
    }
}

/// What the device can do, as far as the renderer cares.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Capabilities {
    pub device_name: String,
    pub device_type: String,
    pub driver: String,
    pub api_version: String,
    pub acceleration_structure: bool,
    pub ray_query: bool,
    pub buffer_device_address: bool,
    pub deferred_host_operations: bool,
    pub push_descriptor: bool,
    pub dynamic_rendering: bool,
    pub synchronization2: bool,
    /// Nanoseconds per timestamp tick; 0 when the queue has no timestamps.
    pub timestamp_period_ns: f32,
    pub max_color_attachments: u32,
    pub max_image_dimension_2d: u32,
    /// Bytes one storage-buffer binding may span (the skinning pass's joint matrices).
    pub max_storage_buffer_range: u32,
    /// Ray tracing hidden by request (`HYBRID_RT_HIDE_RAY_TRACING` or the option).
    pub ray_tracing_hidden: bool,
    /// Dynamic rendering and synchronization2 come from core Vulkan 1.3 (else from the KHR
    /// extensions).
    pub core_1_3: bool,
}

impl Capabilities {
    /// Ray query needs all of: the acceleration-structure and ray-query extensions and buffer
    /// device addresses (acceleration-structure builds take device addresses).
    pub fn supports_ray_query(&self) -> bool {
        self.acceleration_structure && self.ray_query && self.buffer_device_address && self.deferred_host_operations
    }
}

/// Device extensions the renderer enables when present.
struct Extensions {
    push_descriptor: bool,
    dynamic_rendering_ext: bool,
    synchronization2_ext: bool,
    acceleration_structure: bool,
    ray_query: bool,
    deferred_host_operations: bool,
    swapchain: bool,
}

/// The Vulkan instance, device and allocator. Resources hold an `Arc<Context>`, so the device
/// outlives every object made from it and teardown happens in the right order.
pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub caps: Capabilities,
    pub allocator: ManuallyDrop<Mutex<gpu_allocator::vulkan::Allocator>>,
    /// See `ContextOptions::memory_limit`.
    pub(super) memory_limit: Option<u64>,
    pub push_descriptor: ash::khr::push_descriptor::Device,
    dynamic_rendering: ash::khr::dynamic_rendering::Device,
    sync2: ash::khr::synchronization2::Device,
    pub accel: Option<ash::khr::acceleration_structure::Device>,
    debug_utils: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    debug_device: Option<ash::ext::debug_utils::Device>,
    pub validation: Arc<ValidationLog>,
}

impl Context {
    pub fn new(opts: &ContextOptions) -> Result<Arc<Self>> {
        // SAFETY: loading libvulkan runs its initialisers; the loader is the system's Vulkan
        // loader, loaded once per context and kept in `entry` for as long as the context lives.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            anyhow!("cannot load the Vulkan loader (libvulkan.so.1): {e}; run tools/setup.sh or install libvulkan1")
        })?;
        // Checked before anything is created, so a bad value needs no clean-up.
        let memory_limit = match opts.memory_limit {
            Some(limit) => Some(limit),
            None => memory_limit_from_env()?,
        };
        let validation = Arc::new(ValidationLog::default());
        let (instance, debug_utils, api_version) = create_instance(&entry, opts, &validation)?;
        let parts = match open_device(&instance, opts, api_version) {
            Ok(p) => p,
            Err(e) => {
                // SAFETY: the instance and messenger were made just above and nothing else
                // holds them (open_device destroyed what it made); messenger before instance.
                unsafe {
                    if let Some((loader, messenger)) = debug_utils {
                        loader.destroy_debug_utils_messenger(messenger, None);
                    }
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        let DeviceParts { physical_device, queue_family, device, caps, allocator } = parts;
        // SAFETY: the device was created with one queue of `queue_family` (create_device).
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let accel =
            caps.supports_ray_query().then(|| ash::khr::acceleration_structure::Device::new(&instance, &device));
        let debug_device = debug_utils.as_ref().map(|_| ash::ext::debug_utils::Device::new(&instance, &device));
        Ok(Arc::new(Self {
            push_descriptor: ash::khr::push_descriptor::Device::new(&instance, &device),
            dynamic_rendering: ash::khr::dynamic_rendering::Device::new(&instance, &device),
            sync2: ash::khr::synchronization2::Device::new(&instance, &device),
            accel,
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            caps,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            memory_limit,
            debug_utils,
            debug_device,
            validation,
        }))
    }

    /// Gives a Vulkan object a name that validation messages and capture tools show.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(d) = &self.debug_device {
            let name = CString::new(name).unwrap_or_default();
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // Naming is a debugging aid; failure to name is not an error worth surfacing.
            // SAFETY: `handle` is an object of this device (every caller names what it just
            // made); `info` and the name string live across the call.
            let _ = unsafe { d.set_debug_utils_object_name(&info) };
        }
    }

    pub(super) fn cmd_pipeline_barrier2(&self, cmd: vk::CommandBuffer, dep: &vk::DependencyInfo) {
        // SAFETY: `cmd` is a command buffer of this device in the recording state (callers pass
        // a `Recorder`'s or a `CommandPool::run` buffer). The core entry point is used only
        // when device and instance are 1.3 with synchronization2 enabled, else the KHR one,
        // whose extension create_device enabled.
        unsafe {
            if self.caps.core_1_3 {
                self.device.cmd_pipeline_barrier2(cmd, dep)
            } else {
                self.sync2.cmd_pipeline_barrier2(cmd, dep)
            }
        }
    }

    pub(super) fn cmd_write_timestamp2(&self, cmd: vk::CommandBuffer, pool: vk::QueryPool, index: u32) {
        let stage = vk::PipelineStageFlags2::ALL_COMMANDS;
        // SAFETY: `cmd` is recording (as above); `pool` is a live timestamp pool of this
        // device and `index` is below its capacity (asserted by TimestampPool::write).
        unsafe {
            if self.caps.core_1_3 {
                self.device.cmd_write_timestamp2(cmd, stage, pool, index)
            } else {
                self.sync2.cmd_write_timestamp2(cmd, stage, pool, index)
            }
        }
    }

    pub(super) fn cmd_begin_rendering(&self, cmd: vk::CommandBuffer, info: &vk::RenderingInfo) {
        // SAFETY: `cmd` is recording and outside a render pass instance; the attachments in
        // `info` are views of live images owned by the caller. Core or KHR entry as above.
        unsafe {
            if self.caps.core_1_3 {
                self.device.cmd_begin_rendering(cmd, info)
            } else {
                self.dynamic_rendering.cmd_begin_rendering(cmd, info)
            }
        }
    }

    pub(super) fn cmd_end_rendering(&self, cmd: vk::CommandBuffer) {
        // SAFETY: `cmd` is recording inside the rendering begun by cmd_begin_rendering (every
        // caller pairs the two in one function).
        unsafe {
            if self.caps.core_1_3 {
                self.device.cmd_end_rendering(cmd)
            } else {
                self.dynamic_rendering.cmd_end_rendering(cmd)
            }
        }
    }

    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: the device is live for `&self`; waiting needs no other handle. The queue is
        // only submitted to from the thread that owns the frame, which is this one.
        unsafe { self.device.device_wait_idle() }.map_err(|e| super::commands::device_error("vkDeviceWaitIdle", e))
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: the last `Arc<Context>` is gone, so every object made from this device has
        // been dropped (each holds an Arc) and nothing can use it again. After the wait the
        // device is idle; the allocator (its memory blocks) goes before the device, the device
        // and the messenger before the instance. `allocator` is never touched after this.
        unsafe {
            let _ = self.device.device_wait_idle();
            // The allocator frees its memory blocks, which needs the device alive.
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug_utils.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

type DebugUtils = Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>;

/// A created device and what came with it; on error everything made so far is destroyed.
struct DeviceParts {
    physical_device: vk::PhysicalDevice,
    queue_family: u32,
    device: ash::Device,
    caps: Capabilities,
    allocator: gpu_allocator::vulkan::Allocator,
}

fn open_device(instance: &ash::Instance, opts: &ContextOptions, instance_api: u32) -> Result<DeviceParts> {
    let (physical_device, queue_family) = pick_physical_device(instance)?;
    let hidden = Hidden::new(opts.hide_ray_tracing);
    let (exts, caps) = probe(instance, physical_device, queue_family, hidden, instance_api);
    if !caps.push_descriptor || !caps.dynamic_rendering || !caps.synchronization2 {
        bail!(
            "the Vulkan device '{}' lacks a required feature (push descriptors: {}, dynamic rendering: {}, synchronization2: {})",
            caps.device_name,
            caps.push_descriptor,
            caps.dynamic_rendering,
            caps.synchronization2
        );
    }
    let swapchain = opts.window.is_some();
    if swapchain && !exts.swapchain {
        bail!("the Vulkan device '{}' cannot present to a window (no VK_KHR_swapchain)", caps.device_name);
    }
    let device = create_device(instance, physical_device, queue_family, &exts, &caps, swapchain)?;
    let allocator = gpu_allocator::vulkan::Allocator::new(&gpu_allocator::vulkan::AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings: Default::default(),
        // Device addresses are enabled only for the ray-query backend (create_device).
        buffer_device_address: caps.supports_ray_query(),
        allocation_sizes: Default::default(),
    });
    match allocator {
        Ok(allocator) => Ok(DeviceParts { physical_device, queue_family, device, caps, allocator }),
        Err(e) => {
            // SAFETY: the device was created above and nothing was made from it yet.
            unsafe { device.destroy_device(None) };
            bail!("gpu-allocator: {e}")
        }
    }
}

fn create_instance(
    entry: &ash::Entry,
    opts: &ContextOptions,
    log: &Arc<ValidationLog>,
) -> Result<(ash::Instance, DebugUtils, u32)> {
    let validate = opts.validate;
    let required = required_version()?;
    // SAFETY: a global query on a loaded entry; no handles involved.
    let loader_version = unsafe { entry.try_enumerate_instance_version() }?.unwrap_or(vk::API_VERSION_1_0);
    if loader_version < required {
        bail!(
            "the Vulkan loader is version {}, hybrid-rt needs {} or newer: update libvulkan1",
            version_text(loader_version),
            version_text(required)
        );
    }
    let api_version = loader_version.min(vk::API_VERSION_1_3);
    let app_name = c"hybrid-rt";
    let app = vk::ApplicationInfo::default().application_name(app_name).engine_name(app_name).api_version(api_version);

    // SAFETY: a global query on a loaded entry (no layer name: the implicit set).
    let available_exts = unsafe { entry.enumerate_instance_extension_properties(None) }?;
    let has_ext = |name: &CStr| available_exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
    let mut ext_ptrs: Vec<*const c_char> = Vec::new();
    let mut layer_ptrs: Vec<*const c_char> = Vec::new();
    let debug_utils_available = has_ext(ash::ext::debug_utils::NAME);
    if debug_utils_available {
        ext_ptrs.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    if let Some(display) = opts.window {
        let surface_exts = ash_window::enumerate_required_extensions(display)
            .context("this windowing system has no Vulkan surface support")?;
        ext_ptrs.extend_from_slice(surface_exts);
    }
    if validate {
        // SAFETY: a global query on a loaded entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
        if !layers.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
            bail!(
                "validation was requested but the Khronos validation layer is not installed: run tools/setup.sh (Debian package vulkan-validationlayers)"
            );
        }
        if !debug_utils_available {
            bail!("validation was requested but VK_EXT_debug_utils is missing");
        }
        layer_ptrs.push(VALIDATION_LAYER.as_ptr());
        ext_ptrs.push(ash::ext::validation_features::NAME.as_ptr());
    }
    let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let enabled_features: &[vk::ValidationFeatureEnableEXT] = if opts.without_sync_validation { &[] } else { &sync };
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(enabled_features);
    let mut messenger_info = messenger_create_info(log);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_extension_names(&ext_ptrs)
        .enabled_layer_names(&layer_ptrs);
    if validate {
        // Chained at creation too, so messages from vkCreateInstance/vkDestroyInstance are caught.
        info = info.push_next(&mut features).push_next(&mut messenger_info);
    }
    // SAFETY: `info` and everything it points at (names, extension and layer name pointers
    // into 'static C strings, the chained validation features and messenger info) live on
    // this stack frame across the call; only extensions and layers found above are named.
    // The messenger's user data is `log`, which the caller keeps alive (in the Context)
    // until after the instance is destroyed.
    let instance = match unsafe { entry.create_instance(&info, None) } {
        Ok(i) => i,
        // What the loader answers when it finds no driver (ICD) at all.
        Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => bail!("no Vulkan device found: {}", no_driver_hint()),
        Err(e) => return Err(e).context("vkCreateInstance"),
    };
    let debug_utils = if validate {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        // SAFETY: the instance was made with VK_EXT_debug_utils (checked above); the callback
        // reads `log` through its user-data pointer, and the Context keeps that Arc alive
        // until after it destroys the messenger.
        let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_create_info(log), None) };
        match messenger {
            Ok(m) => Some((loader, m)),
            Err(e) => {
                // SAFETY: made above, nothing made from it yet.
                unsafe { instance.destroy_instance(None) };
                bail!("vkCreateDebugUtilsMessengerEXT: {e}");
            }
        }
    } else {
        None
    };
    Ok((instance, debug_utils, api_version))
}

fn messenger_create_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        // Performance advice is left out: it flags choices made on purpose (storage images
        // live in GENERAL layout, see memory.rs); every correctness message is collected.
        .message_type(vk::DebugUtilsMessageTypeFlagsEXT::GENERAL | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION)
        .pfn_user_callback(Some(super::validation::debug_callback))
        .user_data(Arc::as_ptr(log) as *mut std::ffi::c_void)
}

/// Why no driver was found and what to do, naming the loader's driver overrides when set
/// (a stale override is a common cause).
fn no_driver_hint() -> String {
    let overrides: Vec<String> = ["VK_DRIVER_FILES", "VK_ICD_FILENAMES", "VK_ADD_DRIVER_FILES"]
        .iter()
        .filter_map(|k| std::env::var(k).ok().map(|v| format!("{k}={v}")))
        .collect();
    let looked = if overrides.is_empty() {
        String::new()
    } else {
        format!(" (it looked only where {} says)", overrides.join(", "))
    };
    format!(
        "the Vulkan loader found no driver{looked}; install a Vulkan driver (tools/setup.sh installs Mesa's lavapipe)"
    )
}

fn pick_physical_device(instance: &ash::Instance) -> Result<(vk::PhysicalDevice, u32)> {
    let required = required_version()?;
    // SAFETY: physical-device queries on a live instance; the physical devices they return
    // belong to it and need no destruction (as for every query below).
    let devices = unsafe { instance.enumerate_physical_devices() }.context("vkEnumeratePhysicalDevices")?;
    if devices.is_empty() {
        bail!("no Vulkan device found: {}", no_driver_hint());
    }
    let score = |pd: vk::PhysicalDevice| {
        // SAFETY: `pd` is one of this instance's physical devices.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        match props.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => 3,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 2,
            vk::PhysicalDeviceType::CPU => 1,
            _ => 0,
        }
    };
    let mut best: Option<(i32, vk::PhysicalDevice, u32)> = None;
    let mut rejected = Vec::new();
    for pd in devices {
        // SAFETY: `pd` is one of this instance's physical devices.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().unwrap_or(c"?").to_string_lossy().into_owned();
        if props.api_version < required {
            rejected.push(format!(
                "{name}: Vulkan {} (needs {})",
                version_text(props.api_version),
                version_text(required)
            ));
            continue;
        }
        // SAFETY: as above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let Some(family) =
            families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        else {
            rejected.push(format!("{name}: no graphics+compute queue"));
            continue;
        };
        let s = score(pd);
        if best.is_none_or(|(b, _, _)| s > b) {
            best = Some((s, pd, family as u32));
        }
    }
    best.map(|(_, pd, f)| (pd, f)).ok_or_else(|| anyhow!("no usable Vulkan device: {}", rejected.join("; ")))
}

fn probe(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    queue_family: u32,
    hidden: Hidden,
    instance_api: u32,
) -> (Extensions, Capabilities) {
    // SAFETY: `pd` is one of this instance's physical devices (pick_physical_device).
    let props = unsafe { instance.get_physical_device_properties(pd) };
    // SAFETY: as above.
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |name: &CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
    // Core 1.3 commands need both the device and the instance at 1.3.
    let is_13 = props.api_version >= vk::API_VERSION_1_3 && instance_api >= vk::API_VERSION_1_3;

    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let has_as = has(ash::khr::acceleration_structure::NAME);
    let has_rq = has(ash::khr::ray_query::NAME);
    {
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
        if is_13 {
            f2 = f2.push_next(&mut f13);
        }
        if has_as {
            f2 = f2.push_next(&mut fas);
        }
        if has_rq {
            f2 = f2.push_next(&mut frq);
        }
        // SAFETY: the chain holds only structs the device reports (1.3 features when it is
        // 1.3, extension features when the extension is present), all alive in this scope.
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    }
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    {
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: driver properties are core 1.2, which the device reaches (checked when it
        // was picked); the chained struct lives in this scope.
        unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    }
    // SAFETY: as above; `queue_family` indexes this list (found in it by pick_physical_device).
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let ts_bits = families[queue_family as usize].timestamp_valid_bits;

    let e = Extensions {
        push_descriptor: has(ash::khr::push_descriptor::NAME),
        dynamic_rendering_ext: !is_13 && has(ash::khr::dynamic_rendering::NAME),
        synchronization2_ext: !is_13 && has(ash::khr::synchronization2::NAME),
        acceleration_structure: !hidden.acceleration_structure && has_as && fas.acceleration_structure == vk::TRUE,
        ray_query: !hidden.ray_query && has_rq && frq.ray_query == vk::TRUE,
        deferred_host_operations: !hidden.deferred_host_operations && has(ash::khr::deferred_host_operations::NAME),
        swapchain: has(ash::khr::swapchain::NAME),
    };
    let c = Capabilities {
        device_name: props.device_name_as_c_str().unwrap_or(c"?").to_string_lossy().into_owned(),
        device_type: format!("{:?}", props.device_type),
        driver: format!(
            "{} {}",
            driver.driver_name_as_c_str().unwrap_or(c"?").to_string_lossy(),
            driver.driver_info_as_c_str().unwrap_or(c"").to_string_lossy()
        )
        .trim()
        .to_string(),
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version),
            vk::api_version_patch(props.api_version)
        ),
        acceleration_structure: e.acceleration_structure,
        ray_query: e.ray_query,
        buffer_device_address: f12.buffer_device_address == vk::TRUE,
        deferred_host_operations: e.deferred_host_operations,
        push_descriptor: e.push_descriptor,
        dynamic_rendering: if is_13 { f13.dynamic_rendering == vk::TRUE } else { e.dynamic_rendering_ext },
        synchronization2: if is_13 { f13.synchronization2 == vk::TRUE } else { e.synchronization2_ext },
        timestamp_period_ns: if ts_bits > 0 { props.limits.timestamp_period } else { 0.0 },
        max_color_attachments: props.limits.max_color_attachments,
        max_image_dimension_2d: props.limits.max_image_dimension2_d,
        max_storage_buffer_range: props.limits.max_storage_buffer_range,
        ray_tracing_hidden: hidden.any(),
        core_1_3: is_13,
    };
    (e, c)
}

fn create_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    queue_family: u32,
    e: &Extensions,
    caps: &Capabilities,
    swapchain: bool,
) -> Result<ash::Device> {
    let mut names: Vec<*const c_char> = Vec::new();
    if swapchain {
        names.push(ash::khr::swapchain::NAME.as_ptr());
    }
    if e.push_descriptor {
        names.push(ash::khr::push_descriptor::NAME.as_ptr());
    }
    if e.dynamic_rendering_ext {
        names.push(ash::khr::dynamic_rendering::NAME.as_ptr());
    }
    if e.synchronization2_ext {
        names.push(ash::khr::synchronization2::NAME.as_ptr());
    }
    let rt = caps.supports_ray_query();
    if rt {
        names.push(ash::khr::acceleration_structure::NAME.as_ptr());
        names.push(ash::khr::ray_query::NAME.as_ptr());
        names.push(ash::khr::deferred_host_operations::NAME.as_ptr());
    }
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
    // SAFETY: `pd` is one of this instance's physical devices.
    let supported = unsafe { instance.get_physical_device_features(pd) };
    let core = vk::PhysicalDeviceFeatures::default()
        .shader_int64(supported.shader_int64 == vk::TRUE)
        .sampler_anisotropy(supported.sampler_anisotropy == vk::TRUE)
        .fragment_stores_and_atomics(supported.fragment_stores_and_atomics == vk::TRUE)
        .shader_storage_image_write_without_format(supported.shader_storage_image_write_without_format == vk::TRUE);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(rt)
        .runtime_descriptor_array(true)
        .shader_sampled_image_array_non_uniform_indexing(true)
        .descriptor_binding_partially_bound(true)
        .scalar_block_layout(true)
        .host_query_reset(true);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
    let mut dr = vk::PhysicalDeviceDynamicRenderingFeatures::default().dynamic_rendering(true);
    let mut s2 = vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true);
    let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut f2 = vk::PhysicalDeviceFeatures2::default().features(core).push_next(&mut f12);
    if e.dynamic_rendering_ext || e.synchronization2_ext {
        f2 = f2.push_next(&mut dr).push_next(&mut s2);
    } else {
        f2 = f2.push_next(&mut f13);
    }
    if rt {
        f2 = f2.push_next(&mut fas).push_next(&mut frq);
    }
    let info =
        vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_extension_names(&names).push_next(&mut f2);
    // SAFETY: `info` and its chain live on this stack frame, and the chain holds one struct
    // of each type (the 1.3 struct or the two KHR ones, never both). Every extension named
    // was found on the device by `probe`; a feature the device lacks makes the call return
    // VK_ERROR_FEATURE_NOT_PRESENT (the spec's defined answer), not misbehave. One queue, of
    // a family the device has.
    unsafe { instance.create_device(pd, &info, None) }.context("vkCreateDevice")
}
