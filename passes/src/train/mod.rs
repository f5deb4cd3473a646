//! Training a grid radiance field from posed photographs (issue 25, in
//! progress): differentiable volume rendering with exactly the march's
//! quadrature, its gradient with respect to every node, and the losses
//! that compare a rendered pixel with what a photograph says of it. This
//! module holds the f64 CPU reference the GPU trainer is checked against;
//! the gradient itself is checked by finite differences.

pub mod adam;
pub mod behind;
pub mod completing;
pub mod depth;
pub mod geometry;
pub mod gpu;
pub mod knobs;
pub mod lattice;
pub mod loss;
pub mod past_bounds;
pub mod pixels;
pub mod plane_colour;
pub mod planes;
pub mod prune;
pub mod render;
pub mod seen_lights;
pub mod sh_pages;
pub mod sparse_stage;
pub mod spread;
pub mod step_times;
pub mod trainer;
pub mod tv;
pub mod view_pixel;
pub mod visibility;

pub use crate::field::Sky;
pub use adam::{adam_step, AdamKnobs};
pub use behind::Behind;
pub use depth::{depth_penalty, ray_depth, DepthTerm};
pub use geometry::{
    depth_error_colour, depth_pixels, geometry_score, known_depth, recipe_along, score_pixels,
    GeometryScore, KnownAlong, KnownContent, KnownDepth, MediumSpan, PixelDepth, HAZE_MARGIN,
};
pub use gpu::{check_train_rays, GpuTrainer, GradientScatter, TrainRay};
pub use knobs::{
    default_iterations, TrainKnobs, REFINE_EXPONENT_BEHIND_RANDOM, SPARSITY_BEHIND_RANDOM,
    VIEW_DEPENDENT_START_DEGREE,
};
pub use loss::{pixel_loss, PixelTarget};
pub use pixels::{held_out_frames, held_out_poses};
pub use render::{
    render_pixel_with_gradient, render_ray_with_gradient, render_ray_with_gradient_gated,
    DensityGate, RayGradient,
};
pub use step_times::StepTimes;
pub use trainer::{
    resample, train, transparent_pixels, view_march, with_sh_degree, HeldOutView, TrainControl,
    TrainProgress, Trained, TransparentPixels,
};
