//! What the environment fit works on: the surface points with their
//! near-field light and the field's box, and the light scales derived from
//! them (shared by the fit, its share prior and the pruning of unseen
//! lobes).

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
    /// The field's box (normalises the MLP's input).
    pub bounds: Aabb,
}

/// The mean radiance luminance of `points` (sets the starting environment
/// and the share prior's weight).
pub(super) fn mean_luminance(points: &[SurfacePoint]) -> f64 {
    let sum: f64 = points.iter().map(|p| luminance(p.radiance)).sum();
    sum / points.len().max(1) as f64
}

/// The mean near-field irradiance luminance over the points of `data`
/// (the scale of the field's own light at them).
pub(super) fn mean_near_luminance(data: &FitData) -> f64 {
    let sum: f64 = data.near.irradiance.iter().map(|e| luminance(*e)).sum();
    sum / data.points.len().max(1) as f64
}
