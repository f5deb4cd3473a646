//! The object's reflectance (METHOD.md §4.4 step 2): the simplified Disney
//! BRDF evaluated exactly ([`disney`], for the brute-force references and
//! the path tracer), its GGX distribution as a mixture of SGs
//! ([`NdfLobes`]), and shading as a sum of SG inner products with the
//! fitted incident light ([`shade_sg`], mirrored by
//! `shaders/brdf/sg_shading.wgsl`).

pub mod disney;
mod ndf_lobes;
mod sg_shading;
#[cfg(test)]
mod tests;

pub use disney::{SurfaceMaterial, DIELECTRIC_F0, MIN_ROUGHNESS};
pub use ndf_lobes::{NdfLobes, MAX_NDF_LOBES};
pub use sg_shading::{shade_sg, shade_sg_split, ShadingTerms};
