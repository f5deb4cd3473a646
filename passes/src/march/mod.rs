//! The NeRF ray march (METHOD.md, "Volume rendering" and Fig. 2): per pixel
//! colour Ĉ, opacity Ô and depth D̂, clipped at the object's depth. The GPU
//! pass and its f64 CPU reference compute the same quadrature.

mod knobs;
pub mod loop_budget;
pub(crate) mod pass;
mod reference;
mod reuse;

pub use knobs::{
    MarchKnobs, MAX_SAMPLES_PER_RAY, SH_CORNER_LOOP_DEFINE, VIEW_DEPENDENT_SAMPLE_LOOPS,
};
pub use pass::{
    MarchOutputs, MarchPass, MARCH_COLOUR_FORMAT, MARCH_DEPTH_FORMAT, NERF_MARCH, NERF_MARCH_INFO,
    OCCLUSION_SWITCH,
};
pub use reference::{march_image, march_ray, march_samples, MarchResult, MarchSample};
pub use reuse::{MarchClip, MarchReuse};
