//! WGSL shaders: a library of source files, an `#include` step that composes
//! shared code into the shaders using it, and naga compilation to validated
//! SPIR-V with binding reflection. Every error names the original file and line.

mod compile;
mod compose;
mod layout;
mod library;
mod pipeline_cache;

pub use compile::{compile, CompiledShader, DescriptorKind, ReflectedBinding, ShaderStage};
pub use compose::{compose, Composed, Define};
pub use layout::{check_layout, compare_layout, struct_layouts, GpuStruct, StructLayout};
pub use library::ShaderLibrary;

/// A shader that failed to compose, parse or validate, located in its
/// original source file (not in the composed text).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}")]
pub struct ShaderError {
    /// The source file, relative to the shader library's root.
    pub file: String,
    /// 1-based line in `file` (0 when unknown).
    pub line: u32,
    /// 1-based column (0 when unknown).
    pub column: u32,
    /// What is wrong.
    pub message: String,
}
