//! Lights known beside the field (not in the paper): those its
//! photographs saw past its bounds ([`crate::field::seen_lights`]), which
//! the estimate takes as given instead of estimating them again. Each
//! lights a surface point as a point light of its intensity (π r² L) at
//! its centre, through the point's cached opacity, as the estimate's own
//! near lights do ([`super::near_lights`]); a sphere wholly above a
//! point's horizon gives exactly that irradiance. Their light joins the
//! field's as light the fit is given ([`super::FitData::given`]), so the
//! lobes and near lights fit only what no photograph saw, and the test of
//! whether the points need light from outside asks about that remainder.

use glam::DVec3;

use super::near_field::NearField;
use super::near_lights::{near_term, PointLight};
use super::surface::SurfacePoint;
use crate::field::SeenLight;

/// `seen` as point lights of their intensity at their centres.
pub fn as_point_lights(seen: &[SeenLight]) -> Vec<PointLight> {
    seen.iter()
        .map(|l| PointLight {
            position: l.centre,
            intensity: l.intensity(),
        })
        .collect()
}

/// The irradiance `lights` give each of `points`, through its cached
/// opacity in `near` (empty when there are no lights).
pub fn known_irradiance(
    points: &[SurfacePoint],
    near: &NearField,
    lights: &[PointLight],
) -> Vec<DVec3> {
    if lights.is_empty() {
        return Vec::new();
    }
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let visibility = |d: DVec3| 1.0 - near.opacity_at(i, d);
            near_term(lights, p.position, p.normal, &visibility).irradiance
        })
        .collect()
}
