//! Fitting M spherical Gaussians to the incident-light probe by
//! Levenberg–Marquardt (METHOD.md "Spherical Gaussians", per-frame step 1):
//! the model and parameterisation ([`model`]), the damped step
//! ([`solve`]), the f64 CPU reference and the GPU pass with its warm start.

mod energy;
mod knobs;
pub mod model;
pub(crate) mod pass;
pub mod probe_filter;
mod reference;
pub mod solve;
#[cfg(test)]
mod tests;

pub use energy::conserve_energy;
pub use knobs::{FitKnobs, MAX_ITERATIONS, MAX_LOBES};
pub use model::{fibonacci_axis, texel_valid, ProbeSamples};
pub use pass::{FitReport, FitStart, SgFitPass, SG_FIT, SG_FIT_INFO};
pub use reference::{
    fit_reference, relative_residual, FitOutcome, Start, DAMPING_DOWN, DAMPING_LIMIT, DAMPING_UP,
};
