//! What the environment fit works on: the surface points with their
//! near-field light, the light of lights known beside the field, and the
//! field's box, and the light scales derived from them (shared by the fit,
//! its share prior and the pruning of dim near lights).

use glam::DVec3;

use super::near_field::NearField;
use super::surface::SurfacePoint;
use crate::geometry::Aabb;
use crate::sgfit::model::luminance;

/// What the fit needs per point.
pub struct FitData<'a> {
    /// The surface points.
    pub points: &'a [SurfacePoint],
    /// Their near-field light.
    pub near: &'a NearField,
    /// The irradiance each point gets from the lights known beside the
    /// field ([`super::known_lights`]); empty when there are none.
    pub known: &'a [DVec3],
    /// The field's box (normalises the MLP's input).
    pub bounds: Aabb,
}

impl FitData<'_> {
    /// The light point `i` is given, not fitted: the field's (E_nerf)
    /// and the known lights'.
    pub fn given(&self, i: usize) -> DVec3 {
        self.near.irradiance[i] + self.known.get(i).copied().unwrap_or(DVec3::ZERO)
    }
}

/// The mean radiance luminance of `points` (sets the starting environment
/// and the share prior's weight).
pub(super) fn mean_luminance(points: &[SurfacePoint]) -> f64 {
    let sum: f64 = points.iter().map(|p| luminance(p.radiance)).sum();
    sum / points.len().max(1) as f64
}

/// The mean luminance of the light the points of `data` are given
/// ([`FitData::given`]: the scale of the known light at them).
pub(super) fn mean_given_luminance(data: &FitData) -> f64 {
    let sum: f64 = (0..data.points.len())
        .map(|i| luminance(data.given(i)))
        .sum();
    sum / data.points.len().max(1) as f64
}
