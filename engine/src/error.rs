//! The engine's error type: every failure names what failed and where.

use ash::vk;

/// Any failure the engine reports. Messages name the file, field, resource or
/// Vulkan call involved so the user can act on them.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The Vulkan loader (libvulkan) could not be loaded at run time.
    #[error("cannot load the Vulkan loader ({0}); on Debian/Ubuntu install it with `apt-get install libvulkan1 mesa-vulkan-drivers`")]
    Loader(String),
    /// A Vulkan call returned an error code.
    #[error("Vulkan call {call} failed: {result:?}")]
    Vulkan {
        /// The Vulkan function that failed.
        call: &'static str,
        /// The result code it returned.
        result: vk::Result,
    },
    /// No physical device fits the request.
    #[error("{0}")]
    NoDevice(String),
    /// A required layer or extension is missing.
    #[error("{0}")]
    Missing(String),
    /// Memory allocation through gpu-allocator failed.
    #[error("allocating memory for {what}: {message}")]
    Allocation {
        /// The buffer or image being allocated.
        what: String,
        /// The allocator's message.
        message: String,
    },
    /// A WGSL shader failed to compose, parse or validate.
    #[error(transparent)]
    Shader(#[from] crate::shader::ShaderError),
    /// The frame graph was declared inconsistently.
    #[error(transparent)]
    Graph(#[from] crate::graph::GraphError),
    /// A pass used the engine wrongly while recording (e.g. binding an
    /// undeclared resource).
    #[error("pass `{pass}`: {message}")]
    Pass {
        /// The pass being recorded.
        pass: String,
        /// What went wrong.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {message}")]
    File {
        /// The file involved.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// The validation layer reported errors.
    #[error("the Vulkan validation layer reported {count} error(s); first: {first}")]
    Validation {
        /// How many error messages were reported.
        count: usize,
        /// The first of them.
        first: String,
    },
    /// A window-system failure (surface, swapchain).
    #[error("window: {0}")]
    Window(String),
}

impl EngineError {
    /// The message without the file's name, for callers whose own errors
    /// name the file (and the field) themselves.
    pub fn detail(&self) -> String {
        match self {
            EngineError::File { message, .. } => message.clone(),
            other => other.to_string(),
        }
    }
}

/// Result alias used throughout the engine.
pub type Result<T> = std::result::Result<T, EngineError>;

/// Turns a raw `vk::Result` error into an [`EngineError`] naming the call.
pub(crate) trait VkContext<T> {
    /// Attaches the Vulkan function name to the error.
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| EngineError::Vulkan { call, result })
    }
}
