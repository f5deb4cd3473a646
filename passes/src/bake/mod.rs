//! Turning recipes into fields and ground truth: the path tracer over
//! analytic primitives and placed objects (triangles in a BVH), the grid
//! bake, and reference camera images.

mod emitter_power;
mod grid_bake;
mod knobs;
mod light_sample;
mod path_tracer;
mod reference_image;

pub use emitter_power::{calibrate_emitters, field_power};
pub use grid_bake::{bake_grid, edge_profile, grid_resolution, BAKE_REVISION};
pub use knobs::BakeKnobs;
pub use light_sample::{emitter_cone, sample_emitter, LightSample};
pub use path_tracer::{Event, PathTracer, Scatter};
pub use reference_image::{render_reference, ReferenceOptions};
