//! Where the rays through several views' bright spots meet: each meeting
//! point that enough views agree on is a light.

use glam::{DMat3, DVec3};

use crate::geometry::Ray;

/// A ray through a bright spot's centre, and how wide one pixel is there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// Its frame (one sighting of a light per frame counts).
    pub frame: u32,
    /// The ray through the spot's centre (unit direction).
    pub ray: Ray,
    /// The angle one pixel spans there (radians).
    pub pixel_angle: f64,
}

/// A ray may pass this many pixels' width from a point and still see it:
/// a spot's centre is read to a fraction of a pixel, and a capture's poses
/// are good to about a pixel.
pub const TOLERANCE_PIXELS: f64 = 1.5;

/// Two rays closer in direction than this (radians) do not fix a point.
pub const MIN_PARALLAX: f64 = 0.02;

/// At most this many sightings are matched (the brightest): a set with
/// more is specular glints and noise, not lights.
pub const MAX_SIGHTINGS: usize = 400;

/// A point that several sightings agree on.
#[derive(Debug, Clone, PartialEq)]
pub struct Meeting {
    /// The point.
    pub point: DVec3,
    /// The sightings that see it (indices, one per frame).
    pub sightings: Vec<usize>,
}

/// Distance along `s`'s ray to the foot of `p`, and `p`'s distance from
/// the ray.
fn along_and_off(s: &Sighting, p: DVec3) -> (f64, f64) {
    let v = p - s.ray.origin;
    let t = v.dot(s.ray.dir);
    (t, (v - t * s.ray.dir).length())
}

/// How far from `s`'s ray a point at distance `t` along it may lie.
fn tolerance(s: &Sighting, t: f64) -> f64 {
    TOLERANCE_PIXELS * s.pixel_angle * t
}

/// The sightings among `free` that see `p` (in front of their camera and
/// within [`tolerance`]), the nearest to the point in each frame.
fn seeing(sightings: &[Sighting], free: &[bool], p: DVec3) -> Vec<usize> {
    let mut best: Vec<(u32, usize, f64)> = Vec::new();
    for (i, s) in sightings.iter().enumerate() {
        if !free[i] {
            continue;
        }
        let (t, off) = along_and_off(s, p);
        if t <= 0.0 || off > tolerance(s, t) {
            continue;
        }
        let miss = off / tolerance(s, t);
        match best.iter_mut().find(|b| b.0 == s.frame) {
            Some(b) if miss < b.2 => *b = (s.frame, i, miss),
            Some(_) => {}
            None => best.push((s.frame, i, miss)),
        }
    }
    best.into_iter().map(|b| b.1).collect()
}

/// The point nearest the sightings' rays in the least-squares sense, each
/// weighed by its tolerance at `guess`; None where they are all parallel.
pub fn nearest_point(sightings: &[Sighting], which: &[usize], guess: DVec3) -> Option<DVec3> {
    let mut a = DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for &i in which {
        let s = &sightings[i];
        let (t, _) = along_and_off(s, guess);
        let w = 1.0 / tolerance(s, t.max(1e-9)).powi(2);
        let d = s.ray.dir;
        let m = DMat3::IDENTITY - DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        a += m * w;
        b += m * s.ray.origin * w;
    }
    if a.determinant().abs() <= 1e-12 * a.col(0).length().powi(3).max(1e-300) {
        return None;
    }
    Some(a.inverse() * b)
}

/// The midpoint of the shortest segment between two rays, where both
/// points lie in front of their cameras and the rays are not parallel.
fn meeting_of(a: &Sighting, b: &Sighting) -> Option<DVec3> {
    let (d1, d2) = (a.ray.dir, b.ray.dir);
    let cos = d1.dot(d2);
    if cos.abs() > MIN_PARALLAX.cos() {
        return None;
    }
    let w = a.ray.origin - b.ray.origin;
    let (d, e) = (d1.dot(w), d2.dot(w));
    let den = 1.0 - cos * cos;
    let s = (cos * e - d) / den;
    let t = (e - cos * d) / den;
    (s > 0.0 && t > 0.0).then(|| 0.5 * (a.ray.at(s) + b.ray.at(t)))
}

/// The points that at least `min_views` frames' sightings meet at, the best
/// supported first; each sighting used once. Every pair of sightings from
/// two frames proposes where its rays meet; the proposal most frames see
/// wins, is refined by least squares over those that see it, and its
/// sightings leave the pool; until no proposal has `min_views`.
pub fn meetings(sightings: &[Sighting], min_views: usize) -> Vec<Meeting> {
    let n = sightings.len();
    let mut free = vec![true; n];
    let mut out = Vec::new();
    loop {
        let mut best: Option<(DVec3, Vec<usize>)> = None;
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (&sightings[i], &sightings[j]);
                if !free[i] || !free[j] || a.frame == b.frame {
                    continue;
                }
                let Some(p) = meeting_of(a, b) else {
                    continue;
                };
                let (ta, oa) = along_and_off(a, p);
                let (tb, ob) = along_and_off(b, p);
                if oa > tolerance(a, ta) || ob > tolerance(b, tb) {
                    continue;
                }
                let seen = seeing(sightings, &free, p);
                if best.as_ref().is_none_or(|(_, s)| seen.len() > s.len()) {
                    best = Some((p, seen));
                }
            }
        }
        let Some((mut p, mut seen)) = best else {
            break;
        };
        if seen.len() < min_views.max(2) {
            break;
        }
        for _ in 0..3 {
            let Some(q) = nearest_point(sightings, &seen, p) else {
                break;
            };
            let again = seeing(sightings, &free, q);
            if again.len() < seen.len() {
                break;
            }
            (p, seen) = (q, again);
        }
        for &i in &seen {
            free[i] = false;
        }
        out.push(Meeting {
            point: p,
            sightings: seen,
        });
    }
    out
}
