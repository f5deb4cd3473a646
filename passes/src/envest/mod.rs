//! Environment light estimation by inverse rendering (METHOD.md
//! "Environment light estimation", eq. 3-4), offline: surface points from
//! random views of the field ([`views`], [`quality`], [`surface`]), their
//! near-field irradiance and cached opacity on the GPU ([`near_field`],
//! its CPU mirror [`near_field_reference`], the ray set [`hemisphere`]),
//! and the joint Adam fit of a 6-layer albedo MLP ([`mlp`]) and M SG lobes
//! ([`env_model`], [`fit`], with [`share_prior`] and [`prune`]), kept only
//! when the points need light from outside the field ([`outside_light`]),
//! the lights the field's photographs saw past its bounds given, not
//! fitted ([`known_lights`]);
//! [`witnesses`] keeps a trained field's points to what its photographs
//! saw; `estimate` runs them in order, `file` stores the lobes, and
//! [`truth`] checks them against a recipe's lights ([`recovery`]: did it
//! find each hidden emitter).

pub mod adam;
pub mod env_model;
pub mod estimate;
pub mod file;
pub mod fit;
pub mod fit_data;
pub mod hemisphere;
pub mod knobs;
pub mod known_lights;
pub mod mlp;
pub mod near_field;
pub mod near_field_reference;
pub mod near_lights;
pub mod outside_light;
pub mod prune;
pub mod quality;
pub mod recovery;
pub mod share_prior;
pub mod surface;
pub mod truth;
pub mod views;
pub mod witnesses;

#[cfg(test)]
mod tests;

pub use estimate::{
    estimate_environment, sample_surface, EnvEstimate, Progress, Stage, SurfaceSample,
};
pub use file::{
    environment_file_text, load_environment_file, parse_environment_file, EnvFileError,
    EstimatedLight, ENV_FILE_VERSION,
};
pub use fit::{fit_environment, fit_from, params_of, FitData, FitResult};
pub use knobs::EnvEstimateKnobs;
pub use near_field::{NearField, NearFieldTracer};
pub use near_lights::PointLight;
pub use quality::{view_quality, QualityScore, ViewImage};
pub use recovery::{emitter_recovery, EmitterRecovery};
pub use surface::{
    covered_median, draw_points, emitter_limit, keep_seen, view_candidates, SurfaceNormals,
    SurfacePoint, SurfaceTest, ViewPoints,
};
pub use truth::{
    field_light_irradiance, hidden_light_lobes, hidden_light_lobes_except, hidden_light_model,
    light_irradiance, lobes_irradiance, point_lights_irradiance, test_points, Lights, Validation,
};
pub use views::ViewSource;
pub use witnesses::{Witness, Witnesses};
