//! The incident-light probe (METHOD.md eq. 1, per-frame step 1): the field
//! traced from the object's centre over a direction map, plus the
//! environment light where the field is transparent; each texel the mean
//! over its solid angle. GPU pass and f64 CPU
//! reference, and the irradiance a probe or its lobes deliver.

mod direction_map;
mod irradiance;
mod knobs;
pub(crate) mod pass;
mod reference;
mod texel_filter;

pub use direction_map::{
    octahedral_bilinear, octahedral_uv, wrap_octahedral, DirectionMap, MapKind, SOLID_ANGLE_CELLS,
};
pub use irradiance::{lobes_irradiance, probe_irradiance, AXES};
pub use knobs::ProbeKnobs;
pub use pass::{
    samples_per_dispatch, EnvironmentLobes, ProbePass, ProbeTexels, ENVIRONMENT_SWITCH,
    PROBE_FORMAT, PROBE_TRACE, PROBE_TRACE_INFO,
};
pub use reference::{trace_probe, trace_probe_without};
pub use texel_filter::{environment_kernel, texel_environment, BLUR_PER_SUBSAMPLE};
