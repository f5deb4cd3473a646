//! Surface points drawn from a rendered view (METHOD.md eq. 4): the point
//! at the ray's expected depth, x = o + (D̂/Ô)·d, its normal −∇σ/|∇σ|, and
//! the pixel's radiance Ĉ/Ô as the value the Lambertian model must explain.
//!
//! A pixel is a candidate when its ray passes through the field (Ô ≥ 0.5)
//! and the point is on a surface the model describes: the density there
//! rises like a surface's (|∇σ|·h² ≥ [`MIN_SURFACE_GRADIENT`] with h the
//! node spacing; inside semi-transparent matter such as foliage or glass it
//! does not, and the Lambertian surface model does not hold), the normal
//! faces the camera, the pixel is not mixed (its radiance's luminance and
//! that of the field's own colour at the point differ by at most
//! [`MAX_MIXED_DIFFERENCE`] of the larger: a ray that grazes a lamp's glow
//! or a silhouette on its way collects light the point does not reflect),
//! and the radiance is no more than `emitter_ratio` × the median
//! candidate's luminance (brighter points are light sources in the field,
//! which no reflector explains).

use glam::DVec3;

use super::quality::ViewImage;
use crate::camera::CameraFrame;
use crate::field::GridField;
use crate::rng::Pcg32;
use crate::sgfit::model::luminance;

/// Smallest |∇σ|·h² of a surface point (an opaque surface of the bundled
/// recipes reaches about 5 at its expected depth; a medium's edge about
/// 0.05).
pub const MIN_SURFACE_GRADIENT: f64 = 0.5;

/// Largest relative difference between a pixel's luminance and the field's
/// colour at its surface point before the pixel counts as mixed. On PLANTS
/// a floor pixel whose ray grazed the lamp differs by 0.76 (and alone made
/// most of the fit's loss); unmixed pixels of the bundled recipes stay
/// under 0.45.
pub const MAX_MIXED_DIFFERENCE: f64 = 0.5;

/// One surface point of the field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// x_surf, at the ray's expected depth.
    pub position: DVec3,
    /// Unit normal −∇σ/|∇σ|.
    pub normal: DVec3,
    /// The pixel's radiance Ĉ/Ô (what a(x)/π·E must reproduce).
    pub radiance: DVec3,
    /// The view it came from.
    pub view: u32,
}

/// What one view gave.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ViewPoints {
    /// The points drawn (at most the number asked for).
    pub points: Vec<SurfacePoint>,
    /// Pixels whose ray passes through the field.
    pub covered: usize,
    /// Covered pixels left out as light sources.
    pub emitters: usize,
    /// Covered pixels left out as not on a surface.
    pub not_surface: usize,
    /// Covered pixels left out as mixed ([`MAX_MIXED_DIFFERENCE`]).
    pub mixed: usize,
}

/// Whether a pixel of `radiance` whose surface point is `x` mixes light
/// from elsewhere: its luminance and the field's colour at `x` differ by
/// more than [`MAX_MIXED_DIFFERENCE`] of the larger.
fn is_mixed(field: &GridField, x: DVec3, radiance: DVec3) -> bool {
    let c = field.interpolate(x);
    let own = luminance(DVec3::new(c[0], c[1], c[2]));
    let seen = luminance(radiance);
    (seen - own).abs() > MAX_MIXED_DIFFERENCE * seen.max(own)
}

/// Draws up to `count` surface points from `view` (rendered from `frame`),
/// `view_index` naming it; the pixels are chosen with `rng`.
pub fn surface_points(
    field: &GridField,
    frame: &CameraFrame,
    view: &ViewImage,
    view_index: u32,
    count: usize,
    emitter_ratio: f64,
    rng: &mut Pcg32,
) -> ViewPoints {
    let h = field.spacing().min_element();
    let mut out = ViewPoints::default();
    let mut candidates = Vec::new();
    for (i, (p, d)) in view.colour_opacity.iter().zip(&view.depth).enumerate() {
        let opacity = p[3] as f64;
        if opacity < 0.5 {
            continue;
        }
        out.covered += 1;
        let (px, py) = (i as u32 % view.width, i as u32 / view.width);
        let ray = frame.pixel_ray(px, py);
        let x = ray.at(*d as f64 / opacity);
        let g = field.density_gradient(x);
        let radiance = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) / opacity;
        let surface = g.length() * h * h >= MIN_SURFACE_GRADIENT;
        let normal = -g.normalize_or_zero();
        if !surface || normal.dot(ray.dir) >= 0.0 || !radiance.is_finite() {
            out.not_surface += 1;
            continue;
        }
        if is_mixed(field, x, radiance) {
            out.mixed += 1;
            continue;
        }
        candidates.push(SurfacePoint {
            position: x,
            normal,
            radiance: radiance.max(DVec3::ZERO),
            view: view_index,
        });
    }
    if candidates.is_empty() {
        return out;
    }
    let mut lum: Vec<f64> = candidates.iter().map(|c| luminance(c.radiance)).collect();
    lum.sort_by(f64::total_cmp);
    let limit = emitter_ratio * lum[lum.len() / 2];
    let before = candidates.len();
    candidates.retain(|c| luminance(c.radiance) <= limit);
    out.emitters = before - candidates.len();
    let take = count.min(candidates.len());
    for i in 0..take {
        let j = i + (rng.next_u32() as usize % (candidates.len() - i));
        candidates.swap(i, j);
    }
    candidates.truncate(take);
    out.points = candidates;
    out
}
