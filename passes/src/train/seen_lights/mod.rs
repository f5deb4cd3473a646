//! Small bright lights the photographs show past the field's bounds: a
//! ceiling bulb above the box, a lamp beyond the far wall. A field cannot
//! hold them (they are outside it), nor can a sky learnt by direction (a
//! light at a finite distance moves against the background from view to
//! view), so without them their pixels ask the field for light it cannot
//! give, and a view that sees one is scored against light nothing
//! renders: ROOM's Cycles view 24 holds 95 % of its light in its bulb's
//! 20 pixels (`docs/benchmarks.md`, issue 25's twenty-ninth pass).
//!
//! Each is found from the training photographs alone, one image per pose
//! (a pose's exposure brackets merged, [`merge`]): bright spots
//! ([`blobs`]) whose rays meet in one point in several views
//! ([`triangulate`]), and a sphere whose coverage of the pixels around the
//! spots explains their light ([`fit`]). A meeting point within the bounds
//! is a light the field holds itself (a lamp in the room) and is left to
//! it. The lights' pixels are left out of training ([`mask_seen_lights`]);
//! the held-out views draw them ([`with_seen_lights`]), and `inlay train`
//! keeps them beside the field ([`crate::field::seen_lights`]).

pub mod blobs;
pub mod fit;
pub mod merge;
#[cfg(test)]
mod tests;
pub mod triangulate;

use glam::DVec3;
use rayon::prelude::*;

use crate::dataset::{Dataset, Frame, PixelState};
pub use crate::field::seen_lights::{with_seen_lights, SeenLight};
use crate::geometry::Aabb;
use merge::search_frames;

use super::pixels::pixel_ray_at;
use blobs::{bright_blobs, Blob};
use fit::fit_sphere;
use triangulate::{meetings, Sighting, MAX_SIGHTINGS};

/// A pixel is a candidate where its luminance is at least this many times
/// the knobs' scale (the photographs' mean in the bounds). ROOM's bulb
/// reads 3.7·10⁴ times its set's; a lamp inside a field (PLANTS', 1300
/// times) is found too and left to the field; a softbox (ROOM's, 30 times)
/// is not a candidate.
pub const LIGHT_RATIO: f64 = 100.0;

/// A meeting point is a light where at least this many frames see it.
pub const MIN_VIEWS: usize = 3;

/// A training pixel is left out where its centre ray passes within the
/// light's radius plus this many pixels' width of its centre: the light's
/// own pixels, those its edge shares, and a margin for the fit's error.
pub const MASK_PIXELS: f64 = 2.0;

/// What [`find_seen_lights`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeenLights {
    /// The lights past the bounds, the most seen first.
    pub lights: Vec<SeenLight>,
    /// Lights found within (or touching) the bounds, left to the field:
    /// their centres.
    pub inside: Vec<DVec3>,
    /// The candidates' luminance threshold.
    pub threshold: f64,
    /// The bright spots found in the frames read.
    pub spots: usize,
    /// Per light of `lights`, the pixels around its spots that saturated
    /// in every exposure: where any, its radiance is a lower bound.
    pub saturated: Vec<usize>,
}

/// The angle one pixel spans at pixel coordinates (`u`, `v`) of `frame`.
pub fn pixel_angle(frame: &Frame, u: f64, v: f64) -> f64 {
    let i = &frame.intrinsics;
    match (i.direction(u, v), i.direction(u + 1.0, v)) {
        (Some(a), Some(b)) => a.angle_between(b),
        // Past the lens model's reach: the pinhole's angle at the centre.
        _ => 1.0 / i.fx,
    }
}

/// Whether a sphere reaches into the box.
fn touches(bounds: &Aabb, centre: DVec3, radius: f64) -> bool {
    (centre.clamp(bounds.min, bounds.max) - centre).length() <= radius
}

/// The lights that `frames` of `dataset` show past `bounds`, one image
/// per pose ([`search_frames`]: brackets merged): spots of luminance at
/// least [`LIGHT_RATIO`] × `scale` whose rays meet in [`MIN_VIEWS`] poses
/// or more, each fitted as a sphere.
pub fn find_seen_lights(
    dataset: &Dataset,
    frames: &[u32],
    bounds: &Aabb,
    scale: f64,
) -> SeenLights {
    let threshold = LIGHT_RATIO * scale;
    let search = search_frames(dataset, frames);
    let search: Vec<&Frame> = search.iter().map(|f| f.as_ref()).collect();
    let mut spots: Vec<Blob> = (0..search.len() as u32)
        .into_par_iter()
        .flat_map_iter(|f| bright_blobs(search[f as usize], f, threshold))
        .collect();
    let found = spots.len();
    spots.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    spots.truncate(MAX_SIGHTINGS);
    let sightings: Vec<Sighting> = spots
        .iter()
        .filter_map(|b| {
            let frame = search[b.frame as usize];
            Some(Sighting {
                frame: b.frame,
                ray: pixel_ray_at(frame, 0, b.centre)?,
                pixel_angle: pixel_angle(frame, b.centre.0, b.centre.1),
            })
        })
        .collect();
    let mut out = SeenLights {
        threshold,
        spots: found,
        ..SeenLights::default()
    };
    for m in meetings(&sightings, MIN_VIEWS) {
        let blobs: Vec<&Blob> = m.sightings.iter().map(|&i| &spots[i]).collect();
        // From a twentieth of a pixel to the widest spot and a pixel more.
        let footprint = |i: usize| {
            let s = &sightings[i];
            s.pixel_angle * (m.point - s.ray.origin).length()
        };
        let smallest = m
            .sightings
            .iter()
            .map(|&i| 0.05 * footprint(i))
            .fold(f64::INFINITY, f64::min);
        let largest = m
            .sightings
            .iter()
            .map(|&i| {
                let (x0, y0, x1, y1) = spots[i].bbox;
                ((x1 - x0).max(y1 - y0) + 2) as f64 * footprint(i)
            })
            .fold(0.0, f64::max);
        let pixel = m
            .sightings
            .iter()
            .map(|&i| footprint(i))
            .fold(f64::INFINITY, f64::min);
        let Some(fit) = fit_sphere(&search, &blobs, m.point, (smallest, largest), pixel) else {
            continue;
        };
        if touches(bounds, fit.centre, fit.radius) {
            out.inside.push(fit.centre);
            continue;
        }
        out.lights.push(SeenLight {
            centre: fit.centre,
            radius: fit.radius,
            radiance: fit.radiance,
            views: m.sightings.len(),
            residual: fit.residual,
        });
        out.saturated.push(fit.saturated);
    }
    out
}

/// Whether pixel `p` of `frame`, through its centre, passes within
/// [`MASK_PIXELS`] pixels' width of `light`'s disc.
pub fn reaches(light: &SeenLight, frame: &Frame, p: u32) -> bool {
    let w = frame.intrinsics.width;
    let Some(ray) = pixel_ray_at(frame, p, (0.5, 0.5)) else {
        return false;
    };
    let v = light.centre - ray.origin;
    let t = v.dot(ray.dir);
    if t <= 0.0 {
        return false;
    }
    let (u, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
    let off = (v - t * ray.dir).length();
    off <= light.radius + MASK_PIXELS * pixel_angle(frame, u, y) * t
}

/// Leaves out of training every pixel of `frames` that `lights` reach
/// ([`reaches`]): their light is the lights', not the field's. Returns how
/// many pixels it left out.
pub fn mask_seen_lights(dataset: &mut Dataset, lights: &[SeenLight], frames: &[u32]) -> usize {
    if lights.is_empty() {
        return 0;
    }
    let mut masked = 0;
    for &f in frames {
        let frame = &mut dataset.frames[f as usize];
        let hits: Vec<u32> = (0..frame.image.state.len() as u32)
            .into_par_iter()
            .filter(|&p| {
                frame.image.state[p as usize] != PixelState::Masked
                    && lights.iter().any(|l| reaches(l, frame, p))
            })
            .collect();
        for p in hits {
            frame.image.state[p as usize] = PixelState::Masked;
            frame.image.radiance[p as usize] = [0.0; 3];
            masked += 1;
        }
    }
    masked
}
