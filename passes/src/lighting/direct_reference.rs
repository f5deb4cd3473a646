//! The CPU reference (f64) of the direct-light pass
//! (`shaders/lighting/direct.wgsl`): the object's shading lobes are the M
//! fitted lobes followed by each sharp lobe of L_env scaled by the field's
//! mean transmittance 1 − Ô along its rays ([`super::sharp::lobe_rays`]),
//! marched from the object's centre with the probe's quadrature; then each
//! local light ([`super::local`]) as the centre sees it.

use glam::DVec3;

use super::local::{self, LocalLight};
use super::sharp::{attenuated, lobe_rays};
use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};
use crate::sg::Sg64;

/// The field's mean transmittance from `origin` along `rays`.
pub fn transmittance(
    field: &dyn RadianceField,
    origin: DVec3,
    rays: &[DVec3],
    march: &MarchKnobs,
) -> f64 {
    if rays.is_empty() {
        return 1.0;
    }
    let sum: f64 = rays
        .iter()
        .map(|&dir| 1.0 - march_ray(field, &Ray { origin, dir }, f64::INFINITY, march).opacity)
        .sum();
    sum / rays.len() as f64
}

/// The lobes an object at `origin` is shaded with: `fitted`, then each of
/// `sharp` attenuated by the field along its `side`² rays.
pub fn direct_lights(
    field: &dyn RadianceField,
    origin: DVec3,
    fitted: &[Sg64],
    sharp: &[Sg64],
    side: u32,
    march: &MarchKnobs,
) -> Vec<Sg64> {
    direct_and_local_lights(field, origin, fitted, sharp, side, &[], 1, march).0
}

/// As [`direct_lights`], then each of the `local` lights as `origin` sees
/// it along `local_side`² rays (black while inactive,
/// [`LocalLight::active`]); also returns each local light's emission
/// towards `origin` (None while inactive), as the pass writes it.
#[allow(clippy::too_many_arguments)]
pub fn direct_and_local_lights(
    field: &dyn RadianceField,
    origin: DVec3,
    fitted: &[Sg64],
    sharp: &[Sg64],
    side: u32,
    local: &[LocalLight],
    local_side: u32,
    march: &MarchKnobs,
) -> (Vec<Sg64>, Vec<Option<local::Emission>>) {
    let mut lobes: Vec<Sg64> = fitted
        .iter()
        .copied()
        .chain(
            sharp
                .iter()
                .map(|g| attenuated(g, transmittance(field, origin, &lobe_rays(g, side), march))),
        )
        .collect();
    let mut intensities = Vec::new();
    for l in local {
        if !l.active(origin) {
            lobes.push(Sg64 {
                direction: DVec3::Y,
                sharpness: 1.0,
                amplitude: DVec3::ZERO,
            });
            intensities.push(None);
            continue;
        }
        let e = l.emission_towards(field, origin, march);
        lobes.push(local::lobe_at(field, l, origin, e, local_side, march));
        intensities.push(Some(e));
    }
    (lobes, intensities)
}
