//! A light's place, radius and radiance from the pixels around its spots:
//! each pixel reads the background plus the light's radiance times the
//! share of the pixel its disc covers; the radiance follows from a place
//! and a radius in closed form, and the place and radius are those whose
//! coverage fits best. Pixels that
//! saturated in every exposure (lower bounds) take no part in the fit, but
//! the radiance is raised, where needed, to what the mostly covered ones
//! among them say it is at least.

use glam::DVec3;

use crate::dataset::{Frame, PixelState};
use crate::field::seen_lights::sphere_hit;
use crate::geometry::Ray;
use crate::sgfit::model::luminance;

use super::blobs::{radiance_at, Blob};
use crate::train::pixels::{area_offsets, pixel_ray_at};

/// A pixel's coverage is read with this many × this many rays.
pub const COVERAGE_RAYS: u32 = 16;

/// The window read around a spot reaches this many pixels past it; the
/// background is read in the ring of this many pixels and one more
/// beyond the window.
pub const WINDOW_PIXELS: u32 = 2;

/// The radii tried between the smallest and the largest, evenly in log.
const RADII: usize = 48;

/// One pixel near a spot: its rays over its area, and its reading less the
/// background around the spot (for a lower bound, at least that).
struct Reading {
    rays: Vec<Ray>,
    excess: DVec3,
}

/// A lower bound's pixel tells the radiance where the disc covers at least
/// this share of it (less covered, an error in the coverage would ask for
/// far too much light).
pub const BOUND_COVERAGE: f64 = 0.5;

/// The share of `rays` that meet the sphere.
fn coverage(rays: &[Ray], centre: DVec3, radius: f64) -> f64 {
    let hits = rays
        .iter()
        .filter(|r| sphere_hit(r, centre, radius).is_some())
        .count();
    hits as f64 / rays.len().max(1) as f64
}

/// The median of `v` (0 where empty).
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The pixels of `blob`'s window, each read less the median of the ring
/// around the window (per channel): the values, and the lower bounds.
fn readings_of(frame: &Frame, blob: &Blob) -> (Vec<Reading>, Vec<Reading>) {
    let (w, h) = (frame.image.width as i64, frame.image.height as i64);
    let (x0, y0, x1, y1) = blob.bbox;
    let grow = |g: i64| {
        (
            (x0 as i64 - g).max(0),
            (y0 as i64 - g).max(0),
            (x1 as i64 + g).min(w - 1),
            (y1 as i64 + g).min(h - 1),
        )
    };
    let inside =
        |b: (i64, i64, i64, i64), x: i64, y: i64| x >= b.0 && x <= b.2 && y >= b.1 && y <= b.3;
    let window = grow(WINDOW_PIXELS as i64);
    let ring = grow(2 * WINDOW_PIXELS as i64 + 1);
    let mut bg: [Vec<f64>; 3] = Default::default();
    let (mut kept, mut bounds) = (Vec::new(), Vec::new());
    for y in ring.1..=ring.3 {
        for x in ring.0..=ring.2 {
            let p = (y * w + x) as u32;
            let state = frame.image.state[p as usize];
            if state == PixelState::LowerBound && inside(window, x, y) {
                bounds.push(p);
            }
            if state != PixelState::Value {
                continue;
            }
            if inside(window, x, y) {
                kept.push(p);
            } else {
                let c = radiance_at(frame, p);
                for k in 0..3 {
                    bg[k].push(c[k]);
                }
            }
        }
    }
    let [r, g, b] = bg;
    let background = DVec3::new(median(r), median(g), median(b));
    let offsets = area_offsets(COVERAGE_RAYS);
    let read = |pixels: Vec<u32>| -> Vec<Reading> {
        pixels
            .into_iter()
            .filter_map(|p| {
                let rays: Option<Vec<Ray>> =
                    offsets.iter().map(|&o| pixel_ray_at(frame, p, o)).collect();
                Some(Reading {
                    rays: rays?,
                    excess: radiance_at(frame, p) - background,
                })
            })
            .collect()
    };
    (read(kept), read(bounds))
}

/// A light's fitted place, size and radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereFit {
    /// Its centre.
    pub centre: DVec3,
    /// Its radius.
    pub radius: f64,
    /// Its radiance (linear RGB, each channel at least 0).
    pub radiance: DVec3,
    /// The share of the window pixels' excess luminance (squared) the fit
    /// leaves unexplained (0 a perfect fit).
    pub residual: f64,
    /// The window pixels that saturated in every exposure: where any, the
    /// radiance is at least what the values and these say, and may be more.
    pub saturated: usize,
}

/// How far the centre may move from where the spots' rays meet, in pixels'
/// widths at the light: the meeting's own tolerance
/// ([`super::triangulate`] takes rays within 1.5 pixels) and a little more.
pub const CENTRE_REACH_PIXELS: f64 = 2.0;

/// The centre's search stops at steps this many times smaller than a
/// pixel's width at the light.
pub const CENTRE_STEP_DIVISOR: f64 = 64.0;

/// The windows around a light's spots: their value pixels' readings, their
/// lower bounds', and what every fit of them shares.
struct Windows {
    readings: Vec<Reading>,
    bounds: Vec<Reading>,
    excess: Vec<f64>,
    /// Σ e²: what a sphere of no light leaves unexplained.
    total: f64,
    /// Σ e: the light the windows hold.
    sum_e: f64,
}

impl Windows {
    fn new(frames: &[&Frame], blobs: &[&Blob]) -> Self {
        let (mut readings, mut bounds) = (Vec::new(), Vec::new());
        for b in blobs {
            let (values, lower) = readings_of(frames[b.frame as usize], b);
            readings.extend(values);
            bounds.extend(lower);
        }
        let excess: Vec<f64> = readings.iter().map(|r| luminance(r.excess)).collect();
        Self {
            total: excess.iter().map(|e| e * e).sum(),
            sum_e: excess.iter().sum(),
            readings,
            bounds,
            excess,
        }
    }

    /// Σ (e − L·cov)² of a sphere at (`centre`, `r`), with L = Σ e / Σ cov:
    /// the light the windows hold is the sphere's whatever its place and
    /// radius (a least-squares L weighs the brightest pixels, and a centre
    /// a tenth of a pixel off then takes 2 % of the light). Returns the
    /// error and the coverages; None where the sphere covers no pixel.
    fn error(&self, centre: DVec3, r: f64) -> Option<(f64, Vec<f64>)> {
        let cov: Vec<f64> = self
            .readings
            .iter()
            .map(|x| coverage(&x.rays, centre, r))
            .collect();
        let sum_c: f64 = cov.iter().sum();
        if sum_c <= 0.0 {
            return None;
        }
        let l = (self.sum_e / sum_c).max(0.0);
        let err = cov
            .iter()
            .zip(&self.excess)
            .map(|(c, e)| (e - l * c).powi(2))
            .sum();
        Some((err, cov))
    }

    /// The radius in `[smallest, largest]` whose sphere at `centre` fits
    /// best: the best of [`RADII`] radii evenly in log, then a
    /// golden-section search between its neighbours.
    fn best_radius(&self, centre: DVec3, smallest: f64, largest: f64) -> Option<f64> {
        let ratio = (largest / smallest).max(1.0);
        let radius_at = |k: f64| smallest * ratio.powf(k / (RADII - 1) as f64);
        let at = |k: f64| {
            self.error(centre, radius_at(k))
                .map_or(f64::INFINITY, |e| e.0)
        };
        let mut best: Option<(f64, f64)> = None;
        for k in 0..RADII {
            let e = at(k as f64);
            if e.is_finite() && best.is_none_or(|b| e < b.1) {
                best = Some((k as f64, e));
            }
        }
        let (k, _) = best?;
        let (mut lo, mut hi) = ((k - 1.0).max(0.0), (k + 1.0).min((RADII - 1) as f64));
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..24 {
            let (a, b) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
            if at(a) <= at(b) {
                hi = b;
            } else {
                lo = a;
            }
        }
        Some(radius_at(0.5 * (lo + hi)))
    }

    /// The centre near `start` whose sphere of radius `r` fits best: a
    /// pattern search along the axes from half of `pixel` (a pixel's width
    /// at the light) down to `pixel` / [`CENTRE_STEP_DIVISOR`], within
    /// [`CENTRE_REACH_PIXELS`] pixels of `guess`.
    fn best_centre(&self, start: DVec3, guess: DVec3, r: f64, pixel: f64) -> DVec3 {
        let at = |c: DVec3| self.error(c, r).map_or(f64::INFINITY, |e| e.0);
        let (mut c, mut e) = (start, at(start));
        let mut step = 0.5 * pixel;
        while step > pixel / CENTRE_STEP_DIVISOR {
            let mut moved = false;
            for axis in [
                DVec3::X,
                DVec3::Y,
                DVec3::Z,
                -DVec3::X,
                -DVec3::Y,
                -DVec3::Z,
            ] {
                let t = c + step * axis;
                if (t - guess).length() > CENTRE_REACH_PIXELS * pixel {
                    continue;
                }
                let et = at(t);
                if et < e {
                    (c, e, moved) = (t, et, true);
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        c
    }
}

/// The sphere that best explains the windows around `blobs` (which index
/// `frames`), near `guess` (where the spots' rays meet), `pixel` a pixel's
/// width at the light: each pixel reads the background plus the radiance
/// times the share of the pixel the disc covers. At each place and radius
/// the radiance is the one that gives the windows their light; the radius
/// in `[smallest, largest]` and the centre are those whose coverage fits
/// the pixels best (least squares in luminance), each found in turn twice.
/// Then each channel's radiance the same way, raised where a lower bound's
/// pixel the disc mostly covers ([`BOUND_COVERAGE`]) asks for more. The
/// rays meet only within a pixel or so, and a centre a tenth of a pixel
/// off turns the pixels the disc barely grazes (white in a photograph,
/// however little it covers) black. None where no radius covers any
/// value's pixel.
pub fn fit_sphere(
    frames: &[&Frame],
    blobs: &[&Blob],
    guess: DVec3,
    (smallest, largest): (f64, f64),
    pixel: f64,
) -> Option<SphereFit> {
    let windows = Windows::new(frames, blobs);
    let mut centre = guess;
    let mut radius = windows.best_radius(centre, smallest, largest)?;
    for _ in 0..2 {
        centre = windows.best_centre(centre, guess, radius, pixel);
        radius = windows.best_radius(centre, smallest, largest)?;
    }
    let (err, cov) = windows.error(centre, radius)?;
    let sum_c: f64 = cov.iter().sum();
    let readings = &windows.readings;
    let channel = |k: usize| (readings.iter().map(|r| r.excess[k]).sum::<f64>() / sum_c).max(0.0);
    let mut radiance = DVec3::new(channel(0), channel(1), channel(2));
    // What each mostly covered lower bound asks for at least.
    let needed = windows
        .bounds
        .iter()
        .filter_map(|b| {
            let c = coverage(&b.rays, centre, radius);
            (c >= BOUND_COVERAGE).then(|| luminance(b.excess) / c)
        })
        .fold(0.0, f64::max);
    let have = luminance(radiance);
    if needed > have {
        radiance = if have > 0.0 {
            radiance * (needed / have)
        } else {
            DVec3::splat(needed)
        };
    }
    Some(SphereFit {
        centre,
        radius,
        radiance,
        residual: if windows.total > 0.0 {
            err / windows.total
        } else {
            0.0
        },
        saturated: windows.bounds.len(),
    })
}
