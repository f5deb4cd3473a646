//! Shadows (METHOD.md §4.4 steps 3 and 5): the half-space visibility
//! integral f_h ([`fh`]), the self-shadow factors and the cast-shadow pass
//! with their CPU mirrors ([`runtime`]), the direct lobes' ray-cast
//! shadows ([`direct`]), the light the object sends back ([`bounce`]) and
//! the shadow data on the GPU ([`gpu`]); far from the object, the light
//! it can block is integrated over its bounding sphere's cone ([`cone`]).
//! The object's visibility they read
//! is its SSDF field ([`crate::ssdf`]).

pub mod bounce;
pub mod cast;
pub mod cone;
pub mod direct;
pub mod fh;
pub mod gpu;
pub mod runtime;
pub mod upsample;

pub use bounce::{bounce_parts, Bounce, ObjectReflectance};
pub use cast::{
    CastShadowPass, CAST_SHADOW, CAST_SHADOW_INFO, CAST_SHADOW_SWITCH, SHADOW_FORMAT,
    SHADOW_REFINE, SHADOW_REFINE_INFO, SHADOW_UPSAMPLE, SHADOW_UPSAMPLE_INFO,
};
pub use cone::{ConeQuadrature, CONE_POINTS, CONE_RESOLUTION};
pub use direct::{DirectOcclusion, DIRECT_RAY_OFFSET};
pub use fh::{fh_exact, hemisphere_integral, FhTable};
pub use gpu::{object_block, shadow_defines, GpuFhTable, GpuSsdf, SsdfBindings};
pub use runtime::{
    cast_shadow_factor, field_normal, self_shadow_factors, shadow_point, sphere_clear_of,
    sphere_share, world_ssdf, ShadowPoint, SphereView, CAST_SKIP_SHARE, HORIZON_FLOOR,
};
pub use upsample::{upsample_shadow, CastScale, MAX_CAST_SCALE};
