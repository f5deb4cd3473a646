//! The inlay engine: Vulkan context, memory, WGSL shaders, the frame graph,
//! GPU timing and render targets. It knows nothing about radiance fields; the
//! method's passes live in `inlay-passes` and run as passes of its graph.
//!
//! `unsafe` is confined to this crate: everything it exports is safe.
#![warn(missing_docs)]

mod context;
mod descriptors;
pub mod device_choice;
mod error;
pub mod graph;
mod image_io;
pub mod interrupt;
mod memory;
pub mod output;
mod pipeline;
pub mod push;
mod readback;
mod renderer;
pub mod shader;
pub mod timing;
pub mod tonemap;
mod transient_pool;
mod upload;
mod validation;
pub mod window;

pub use ash::vk;
pub use context::{
    Context, ContextOptions, DeviceInfo, MemoryUsage, WindowHandles, DEVICE_ENV,
    LLVMPIPE_LOOP_LIMIT,
};
pub use error::{EngineError, Result};
pub use image_io::{HdrImage, IMAGE_EXTENSIONS, MAX_EXR_PIXELS};
pub use memory::{is_depth_format, Buffer, BufferLocation, Image, ImageDesc};
pub use pipeline::{ComputePipeline, GraphicsDesc, GraphicsPipeline};
pub use push::{Push, PushConstants};
pub use readback::{BufferReadback, Readback};
pub use renderer::{FrameReport, FrameToken, Renderer, SubmitSync, DEFAULT_FRAMES_IN_FLIGHT};
pub use validation::ValidationLog;
