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
//! candidate's luminance over all the views (brighter points are light
//! sources in the field, which no reflector explains). The median was
//! each view's own: a view that saw mostly the dark outside of ROOM's
//! walls took the lit room inside for a light source (3168 of ROOM's
//! pixels left out at 8×, the estimate's error 288 %).

use glam::DVec3;

use super::quality::ViewImage;
use crate::camera::CameraFrame;
use crate::field::{GridField, RadianceField};
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

/// Whether a pixel of `radiance` whose surface point is `x`, seen along
/// `dir`, mixes light from elsewhere: its luminance and the field's colour
/// at `x` along `dir` differ by more than [`MAX_MIXED_DIFFERENCE`] of the
/// larger.
fn is_mixed(field: &GridField, x: DVec3, dir: DVec3, radiance: DVec3) -> bool {
    let own = luminance(field.colour(x, dir));
    let seen = luminance(radiance);
    (seen - own).abs() > MAX_MIXED_DIFFERENCE * seen.max(own)
}

/// Every candidate surface point of `view` (rendered from `frame`),
/// `view_index` naming it, before light sources are left out.
pub fn view_candidates(
    field: &GridField,
    frame: &CameraFrame,
    view: &ViewImage,
    view_index: u32,
) -> ViewPoints {
    let h = field.spacing().min_element();
    let mut out = ViewPoints::default();
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
        if is_mixed(field, x, ray.dir, radiance) {
            out.mixed += 1;
            continue;
        }
        out.points.push(SurfacePoint {
            position: x,
            normal,
            radiance: radiance.max(DVec3::ZERO),
            view: view_index,
        });
    }
    out
}

/// The luminance above which a candidate is a light source:
/// `emitter_ratio` × the median candidate's over all `views` (0 when
/// there are none).
pub fn emitter_limit<'a>(
    views: impl IntoIterator<Item = &'a ViewPoints>,
    emitter_ratio: f64,
) -> f64 {
    let mut lum: Vec<f64> = views
        .into_iter()
        .flat_map(|v| v.points.iter().map(|c| luminance(c.radiance)))
        .collect();
    if lum.is_empty() {
        return 0.0;
    }
    let mid = lum.len() / 2;
    let (_, median, _) = lum.select_nth_unstable_by(mid, f64::total_cmp);
    emitter_ratio * *median
}

/// Leaves out `view`'s candidates brighter than `limit` (counted as
/// light sources) and keeps `count` of the rest, chosen with `rng`.
pub fn draw_points(mut view: ViewPoints, limit: f64, count: usize, rng: &mut Pcg32) -> ViewPoints {
    let before = view.points.len();
    view.points.retain(|c| luminance(c.radiance) <= limit);
    view.emitters += before - view.points.len();
    let take = count.min(view.points.len());
    for i in 0..take {
        let j = i + (rng.next_u32() as usize % (view.points.len() - i));
        view.points.swap(i, j);
    }
    view.points.truncate(take);
    view
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(index: u32, luminances: &[f64]) -> ViewPoints {
        ViewPoints {
            points: luminances
                .iter()
                .map(|&l| SurfacePoint {
                    position: DVec3::ZERO,
                    normal: DVec3::Y,
                    radiance: DVec3::splat(l),
                    view: index,
                })
                .collect(),
            covered: luminances.len(),
            ..Default::default()
        }
    }

    /// A view of mostly dark surfaces does not make the lit ones light
    /// sources: the limit is one median over all the views; only what
    /// exceeds it is left out, and counted.
    #[test]
    fn light_sources_are_judged_against_all_the_views() {
        let dark = view(0, &[0.01, 0.01, 0.01, 0.5, 0.5]);
        let lit = view(1, &[0.4, 0.5, 0.5, 0.6, 9.0]);
        // Its own median (0.01) would leave out the dark view's lit points.
        assert!((emitter_limit([&dark], 8.0) - 0.08).abs() < 1e-6);
        let limit = emitter_limit([&dark, &lit], 8.0);
        assert!((limit - 8.0 * 0.5).abs() < 1e-6);
        let mut rng = Pcg32::new(1, 2);
        let drawn = draw_points(dark, limit, 10, &mut rng);
        assert_eq!((drawn.points.len(), drawn.emitters), (5, 0));
        let drawn = draw_points(lit, limit, 3, &mut rng);
        assert_eq!((drawn.points.len(), drawn.emitters), (3, 1));
        assert!(drawn.points.iter().all(|p| p.radiance.x < 1.0));
        assert_eq!(emitter_limit([], 8.0), 0.0);
    }
}
