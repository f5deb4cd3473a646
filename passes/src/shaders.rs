//! The WGSL shipped with inlay: embedded at build time from shaders/, or read
//! from the directory in `INLAY_SHADER_DIR` (edit shaders without rebuilding).

use inlay_engine::shader::ShaderLibrary;

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shader_files.rs"));
}

/// The environment variable naming a shader directory to use instead of the
/// embedded copy.
pub const SHADER_DIR_ENV: &str = "INLAY_SHADER_DIR";

/// The shader library: from `INLAY_SHADER_DIR` when set, else embedded.
pub fn library() -> anyhow::Result<ShaderLibrary> {
    match std::env::var_os(SHADER_DIR_ENV) {
        Some(dir) => Ok(ShaderLibrary::from_dir(std::path::Path::new(&dir))?),
        None => Ok(embedded_library()),
    }
}

/// The shaders embedded in this binary.
pub fn embedded_library() -> ShaderLibrary {
    ShaderLibrary::from_pairs(embedded::FILES.iter().copied())
}
