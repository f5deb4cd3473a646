//! The WGSL shipped with inlay: embedded at build time from shaders/, or read
//! from the directory in `INLAY_SHADER_DIR` (edit shaders without rebuilding).

use inlay_engine::shader::{Define, ShaderLibrary};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shader_files.rs"));
}

/// The environment variable naming a shader directory to use instead of the
/// embedded copy.
pub const SHADER_DIR_ENV: &str = "INLAY_SHADER_DIR";

/// The shader library: from `INLAY_SHADER_DIR` when set, else embedded;
/// with the defines every pass's shaders may read
/// ([`crate::field::general_field_library`]).
pub fn library() -> anyhow::Result<ShaderLibrary> {
    match std::env::var_os(SHADER_DIR_ENV) {
        Some(dir) => Ok(crate::field::general_field_library(
            &ShaderLibrary::from_dir(std::path::Path::new(&dir))?,
        )),
        None => Ok(embedded_library()),
    }
}

/// The shaders embedded in this binary (with the defines of
/// [`library`]).
pub fn embedded_library() -> ShaderLibrary {
    crate::field::general_field_library(&ShaderLibrary::from_pairs(embedded::FILES.iter().copied()))
}

/// Every host mirror of a WGSL struct in this crate checked against the
/// shader that declares it ([`inlay_engine::shader::check_layout`]); the
/// errors, one per struct that differs. `defines` are the knob constants
/// the shaders expect from their passes.
pub fn gpu_layout_errors(lib: &ShaderLibrary, defines: &[Define]) -> Vec<String> {
    use inlay_engine::shader::check_layout as check;
    [
        check::<crate::lighting::direct_pass::DirectPush>(lib, defines),
        check::<crate::probe::pass::ProbePush>(lib, defines),
        check::<crate::envest::near_field::NearFieldPush>(lib, defines),
        check::<crate::edge_aa::EdgeAaPush>(lib, defines),
        check::<crate::sgfit::pass::FitPush>(lib, defines),
        check::<crate::train::gpu::TrainPush>(lib, defines),
        check::<crate::train::gpu::TrainRay>(lib, defines),
        check::<crate::train::gpu::AdamPush>(lib, defines),
        check::<crate::train::gpu::TvPush>(lib, defines),
        check::<crate::train::gpu::DescendPush>(lib, defines),
        check::<crate::sgfit::pass::FitState>(lib, defines),
        check::<crate::camera::CameraRays>(lib, defines),
        check::<crate::march::pass::MarchPush>(lib, defines),
        check::<crate::shade::ShadePush>(lib, defines),
        check::<crate::shadow::cast::CastPush>(lib, defines),
        check::<crate::field::gpu_grid::GridInfo>(lib, defines),
        check::<crate::composite::CompositePush>(lib, defines),
        check::<crate::gbuffer::GBufferCamera>(lib, defines),
        check::<crate::gbuffer::DrawRecord>(lib, defines),
        check::<crate::gbuffer::DrawPush>(lib, defines),
        check::<crate::ssdf::bake::BakePush>(lib, defines),
        check::<crate::shadow::gpu::SsdfObject>(lib, defines),
        check::<crate::object::ObjectRecord>(lib, defines),
    ]
    .into_iter()
    .filter_map(Result::err)
    .collect()
}
