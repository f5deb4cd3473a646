//! Captures every validation-layer message: logs it and counts errors so tests
//! can fail on any of them.

use std::ffi::{c_void, CStr};
use std::sync::Mutex;

use ash::vk;

/// The messages the validation layer (and the loader) reported, with the
/// number of errors among them.
#[derive(Debug, Default)]
pub struct ValidationLog {
    inner: Mutex<LogInner>,
}

#[derive(Debug, Default)]
struct LogInner {
    errors: Vec<String>,
    warnings: usize,
}

/// Keeps at most this many error texts; the count goes on past it.
const KEPT_ERRORS: usize = 64;

impl ValidationLog {
    /// Number of error-severity messages seen so far.
    pub fn error_count(&self) -> usize {
        self.inner.lock().map(|l| l.errors.len()).unwrap_or(0)
    }

    /// Number of warning-severity messages seen so far.
    pub fn warning_count(&self) -> usize {
        self.inner.lock().map(|l| l.warnings).unwrap_or(0)
    }

    /// Removes and returns the error messages seen so far.
    pub fn take_errors(&self) -> Vec<String> {
        self.inner
            .lock()
            .map(|mut l| std::mem::take(&mut l.errors))
            .unwrap_or_default()
    }

    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, text: String) {
        if let Ok(mut l) = self.inner.lock() {
            if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
                if l.errors.len() < KEPT_ERRORS {
                    l.errors.push(text);
                } else {
                    l.errors.push(String::new());
                }
            } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
                l.warnings += 1;
            }
        }
    }
}

/// The debug-utils callback: forwards every message to the `log` crate and
/// records it in the [`ValidationLog`] passed as user data.
pub(crate) unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let message = if data.is_null() || (*data).p_message.is_null() {
        String::from("(no message)")
    } else {
        CStr::from_ptr((*data).p_message)
            .to_string_lossy()
            .into_owned()
    };
    let text = format!("[{kind:?}] {message}");
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        log::error!(target: "vulkan", "{text}");
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        log::warn!(target: "vulkan", "{text}");
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::INFO) {
        log::debug!(target: "vulkan", "{text}");
    } else {
        log::trace!(target: "vulkan", "{text}");
    }
    if !user.is_null() {
        let log = &*(user as *const ValidationLog);
        log.record(severity, text);
    }
    vk::FALSE
}
