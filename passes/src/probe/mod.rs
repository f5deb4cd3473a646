//! The incident-light probe (METHOD.md eq. 1, per-frame step 1): the field
//! traced from the object's centre over a direction map, plus the
//! environment light where the field is transparent. GPU pass and f64 CPU
//! reference.

mod direction_map;
mod knobs;
mod pass;
mod reference;

pub use direction_map::{
    octahedral_bilinear, octahedral_uv, wrap_octahedral, DirectionMap, MapKind,
};
pub use knobs::ProbeKnobs;
pub use pass::{ProbePass, PROBE_FORMAT};
pub use reference::trace_probe;
