//! Radiance fields: what every pass samples (density σ(x) and linear-HDR
//! colour c(x, d) inside axis-aligned bounds), and the kinds the engine has.
//!
//! The first kind is [`GridField`], a voxel grid read with trilinear
//! interpolation, its colour optionally view-dependent (spherical
//! harmonics of degree ≤ 2, [`sh_basis`]); fields trained from photos and instant-ngp snapshots are
//! later kinds behind the same trait.

pub mod bricks;
mod emitters;
mod format;
pub(crate) mod gpu_grid;
mod grid;
mod occupancy;
mod perturb;
pub mod seen_lights;
mod sh;
pub mod sh_half;
pub mod sky;

pub use emitters::{find_emitters, FieldEmitter, MAX_FIELD_EMITTERS, MIN_EMITTER_RATIO};
pub use format::{
    checked_field_bytes, field_bytes, load_field, parse_field, read_field_header, save_field,
    FieldFormatError, FieldHeader, FIELD_MAGIC, FIELD_VERSION,
};
pub use gpu_grid::{
    check_field_fits, check_field_may_fit, check_sparse_field_fits, device_values,
    general_field_library, library_marches_view_dependent, FieldIdentity, FieldLayout,
    GpuGridField, GridBindings, NodeStorage, SPARSE_DEFINE, VIEW_DEPENDENT_DEFINE,
};
pub use grid::{density_at, GridField};
pub use occupancy::{Occupancy, DEFAULT_OCCUPANCY_BLOCK};
pub use perturb::{perturb, Perturbation};
pub use seen_lights::{seen_lights_path, SeenLight};
pub use sh::{sh_basis, sh_colour_unclamped, sh_extra_coefficients, MAX_SH_DEGREE};
pub use sky::{sky_path, Sky};

use glam::DVec3;

use crate::geometry::Aabb;

/// A radiance field as the CPU references see it (f64).
pub trait RadianceField: Sync {
    /// The region outside which density is zero.
    fn bounds(&self) -> Aabb;
    /// Density σ at `x` (1/length; zero outside the bounds).
    fn density(&self, x: DVec3) -> f64;
    /// Linear-HDR colour emitted towards direction `d` from `x`.
    fn colour(&self, x: DVec3, d: DVec3) -> DVec3;
    /// Density and colour together (kinds that share the lookup override it).
    fn sample(&self, x: DVec3, d: DVec3) -> (f64, DVec3) {
        (self.density(x), self.colour(x, d))
    }
    /// Empty-space information: `Some(t)` when the density is zero along
    /// `origin + s·dir` for every s in [0, t) — the march may skip to `t`.
    /// `None` means "may be occupied here". The default skips nothing.
    fn empty_until(&self, _origin: DVec3, _dir: DVec3) -> Option<f64> {
        None
    }
}
