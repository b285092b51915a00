//! Collects what the Khronos validation layer says. Every warning or error it prints is kept
//! and counted: tests fail on any, and `--validate` turns a non-empty log into a non-zero exit.

use super::Context;
use anyhow::{Result, bail};
use ash::vk;
use std::ffi::{CStr, c_void};
use std::sync::{Arc, Mutex};

#[derive(Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn count(&self) -> usize {
        self.messages.lock().map(|m| m.len()).unwrap_or(0)
    }

    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    fn push(&self, msg: String) {
        if let Ok(mut m) = self.messages.lock() {
            m.push(msg);
        }
    }
}

/// Drops the context (tearing down the device, which is when the layer reports leaks), then
/// fails when the validation layer printed anything. Every command ends through this.
pub fn finish_validation(ctx: Arc<Context>) -> Result<()> {
    let log = ctx.validation.clone();
    drop(ctx);
    let n = log.count();
    if n > 0 {
        bail!("the Vulkan validation layer reported {n} message(s) (see above)");
    }
    Ok(())
}

/// The messenger's callback (context.rs installs it).
///
/// # Safety
///
/// Called by the Vulkan loader only: `data` is null or a valid callback-data struct for the
/// duration of the call, and `user` is null or the `ValidationLog` the messenger was created
/// with, alive for as long as the messenger exists.
pub(super) unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _ty: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the loader passes a valid callback-data struct; `user` is the `ValidationLog`
    // the context keeps alive for as long as the messenger exists.
    let (data, log) = unsafe { (&*data, &*(user as *const ValidationLog)) };
    let text = if data.p_message.is_null() {
        String::from("(no message)")
    } else {
        // SAFETY: a non-null pMessage is a NUL-terminated string valid during the callback.
        unsafe { CStr::from_ptr(data.p_message) }.to_string_lossy().into_owned()
    };
    let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) { "error" } else { "warning" };
    log::error!("validation {level}: {text}");
    log.push(format!("{level}: {text}"));
    vk::FALSE
}
