//! The program's own host mirrors of WGSL structs (overlay, present,
//! demo), checked like the passes' ([`inlay_passes::shaders::gpu_layout_errors`]).

use inlay_engine::shader::{check_layout as check, ShaderLibrary};

/// The errors of this crate's mirrors against their shaders, one per
/// struct that differs.
pub fn gpu_layout_errors(lib: &ShaderLibrary) -> Vec<String> {
    [
        check::<crate::overlay::OverlayPush>(lib, &[]),
        check::<crate::present::PresentPush>(lib, &[]),
        check::<crate::demo::SkyPush>(lib, &[]),
        check::<crate::demo::QuadsPush>(lib, &[]),
    ]
    .into_iter()
    .filter_map(Result::err)
    .collect()
}
