//! Collects what the Khronos validation layer says. Every warning or error it prints is kept
//! and counted: tests fail on any, and `--validate` turns a non-empty log into a non-zero exit.

use ash::vk;
use std::ffi::{CStr, c_void};
use std::sync::Mutex;

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
        unsafe { CStr::from_ptr(data.p_message) }.to_string_lossy().into_owned()
    };
    let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) { "error" } else { "warning" };
    log::error!("validation {level}: {text}");
    log.push(format!("{level}: {text}"));
    vk::FALSE
}
