//! Shadows (METHOD.md §4.3, §4.4 steps 3 and 5): the half-space visibility
//! integral f_h ([`fh`]).

pub mod bake;
pub mod bounce;
pub mod cast;
pub mod direct;
pub mod fh;
pub mod field;
pub mod format;
pub mod gpu;
pub mod grid;
pub mod pca;
pub mod silhouette;

pub use bake::{
    bake_reference, grid_for, lookup_points, object_scene, SsdfBaker, SsdfKnobs, SsdfSamples,
};
pub use bounce::{bounce_irradiance, ObjectReflectance};
pub use cast::{CastShadowPass, CAST_SHADOW, CAST_SHADOW_INFO, CAST_SHADOW_SWITCH, SHADOW_FORMAT};
pub use direct::{DirectOcclusion, DIRECT_RAY_OFFSET};
pub use fh::{fh_exact, hemisphere_integral, FhTable};
pub use field::{OutsideMode, SsdfField};
pub use format::{load_ssdf, parse_ssdf, save_ssdf, ssdf_bytes, SsdfFormatError, SSDF_VERSION};
pub use gpu::{object_block, shadow_defines, world_to_object, GpuFhTable, GpuSsdf, SsdfBindings};
pub use grid::SsdfGrid;
pub use runtime::{
    cast_shadow_factor, field_normal, self_shadow_factors, sphere_clear_of, sphere_share,
    world_ssdf, CAST_SKIP_SHARE, HORIZON_FLOOR,
};
pub use silhouette::{angle_between, angle_to_arc, SilhouetteEdge, SilhouetteMesh, SilhouetteView};
pub mod reference;
pub mod runtime;

#[cfg(test)]
mod tests;
