//! An object's SSDF field (METHOD.md "SSDF field", §4.3): its spherical
//! signed distance S(d; x) to its own silhouette, exact from the mesh
//! ([`silhouette`]), baked on the GPU at the nodes of a grid around it
//! ([`bake`], [`grid`]), compressed by PCA ([`pca`]), read anywhere
//! ([`field`]) and stored in `.inlayssdf` files ([`format`](mod@format)); and the
//! brute-force ray casting it is judged by ([`reference`](mod@reference)). The shadows
//! that read it are in [`crate::shadow`].

pub mod bake;
pub mod coarse;
pub mod field;
pub mod format;
pub mod grid;
pub mod pca;
pub mod reference;
pub mod silhouette;

pub use bake::{
    bake_reference, check_bake_fits, check_outline_fits, grid_for, lookup_points, object_scene,
    SsdfBaker, SsdfKnobs, SsdfSamples, BAKE_BYTES_PER_TRIANGLE,
};
pub use field::{OutsideMode, SsdfField};
pub use format::{
    check_ssdf_object, load_ssdf, parse_ssdf, save_ssdf, ssdf_bytes, SsdfFormatError, SSDF_VERSION,
};
pub use grid::SsdfGrid;
pub use silhouette::{angle_between, angle_to_arc, SilhouetteEdge, SilhouetteMesh, SilhouetteView};

#[cfg(test)]
pub(crate) mod tests;
