//! Spherical Gaussians G(v; p, λ, μ) = μ·exp(λ(v·p − 1)) (METHOD.md eq. 2):
//! evaluation, product, sphere integral, inner product and the clamped-cosine
//! lobe, in f64 and f32 (`math`), mirrored by `shaders/common/sg.wgsl`;
//! importance sampling for the path tracer; adaptive quadrature over the
//! sphere that the tests check every identity against.

mod math;
pub mod quadrature;
mod sampling;
#[cfg(test)]
mod tests;

pub use math::{Sg32, Sg64, COSINE_SHARPNESS, SERIES_BELOW};

/// The lobe type of scene files and CPU references.
pub type SgLobe = Sg64;
