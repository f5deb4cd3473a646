//! Lights a trained field's photographs showed past its bounds (a ceiling
//! bulb above the box: `crate::train::seen_lights` finds them), kept beside
//! the field as `FIELD.lights.toml` ([`mod@file`]) and drawn wherever the field
//! is: before the bounds a light hides what lies behind it, past them it
//! shows through what the field and objects leave uncovered, as the sky
//! does ([`with_seen_lights`] for a ray, [`light_over_pixel`] for a pixel).

pub mod file;

use glam::DVec3;

use crate::geometry::{ray_box, Aabb, Ray};
use crate::scene::Shape;

pub use file::{load_seen_lights, seen_lights_path, seen_lights_text, SeenLightsError};

/// A light seen past the field's bounds: a sphere of uniform radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenLight {
    /// Its centre.
    pub centre: DVec3,
    /// Its radius.
    pub radius: f64,
    /// Its radiance (linear RGB).
    pub radiance: DVec3,
    /// The training frames whose spots met at it.
    pub views: usize,
    /// The share of its spots' excess light (squared) the sphere left
    /// unexplained.
    pub residual: f64,
}

/// The nearest point at which `ray` meets the sphere (`centre`, `radius`)
/// in front of its origin.
pub fn sphere_hit(ray: &Ray, centre: DVec3, radius: f64) -> Option<f64> {
    let (t0, t1) = Shape::Sphere { centre, radius }.interval(ray)?;
    if t0 > 0.0 {
        Some(t0)
    } else {
        (t1 > 0.0).then_some(t1)
    }
}

impl SeenLight {
    /// Where `ray` first meets it in front of the ray's origin.
    pub fn hit(&self, ray: &Ray) -> Option<f64> {
        sphere_hit(ray, self.centre, self.radius)
    }

    /// Its radiant intensity, π r² L: what lights a point far from it, and
    /// what a view of it measures best (its radius and radiance alone
    /// trade against each other where it spans a pixel or two).
    pub fn intensity(&self) -> DVec3 {
        std::f64::consts::PI * self.radius * self.radius * self.radiance
    }
}

/// Whether something at distance `t` along `ray` lies before `bounds`
/// (the ray meets it first, or never enters them).
fn before_bounds(ray: &Ray, bounds: &Aabb, t: f64) -> bool {
    ray_box(ray, bounds).is_none_or(|(t0, _)| t <= t0)
}

/// The radiance along `ray` with `lights` beside a field in `bounds`: the
/// nearest light it meets where that lies before the bounds (or the ray
/// misses them), `colour` plus what is left of `opacity` times the light
/// where the light lies past them, and `colour` over `behind` where it
/// meets none. (`colour`, `opacity`) is the field's march along the ray.
pub fn with_seen_lights(
    lights: &[SeenLight],
    ray: &Ray,
    bounds: &Aabb,
    colour: DVec3,
    opacity: f64,
    behind: DVec3,
) -> DVec3 {
    let nearest = lights
        .iter()
        .filter_map(|l| l.hit(ray).map(|t| (t, l.radiance)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match nearest {
        None => colour + (1.0 - opacity) * behind,
        Some((t, radiance)) if before_bounds(ray, bounds, t) => radiance,
        Some((_, radiance)) => colour + (1.0 - opacity) * radiance,
    }
}

/// The share of a pixel that `light`'s disc covers, seen along unit
/// direction `d` from `origin` with one pixel `pixel_angle` wide: the
/// disc's edge ramped over one pixel's width, and at most the disc's area
/// over the pixel's (a disc smaller than a pixel lights part of it).
/// Returns the coverage and the distance to the light's centre along `d`.
pub fn disc_coverage(light: &SeenLight, origin: DVec3, d: DVec3, pixel_angle: f64) -> (f64, f64) {
    let v = light.centre - origin;
    let t = v.dot(d);
    if t <= 0.0 || pixel_angle <= 0.0 {
        return (0.0, t);
    }
    let off = (v - t * d).length() / t;
    let rho = light.radius / t;
    let ramp = (0.5 + (rho - off) / pixel_angle).clamp(0.0, 1.0);
    let area = std::f64::consts::PI * (rho / pixel_angle).powi(2);
    (ramp.min(area), t)
}

/// One frame pixel with `lights` drawn: `colour` (premultiplied, coverage
/// in alpha, the field and objects) over `back` (the sky, or black), seen
/// along unit `d` from `origin`, one pixel `pixel_angle` wide. The nearest
/// light covering the pixel at all is drawn: before `bounds` over
/// everything, past them where the frame leaves the pixel uncovered.
/// Returns the colour, coverage 1. Mirrored in
/// `shaders/sky_behind/sky_behind.wgsl`.
pub fn light_over_pixel(
    colour: [f64; 4],
    back: DVec3,
    lights: &[SeenLight],
    bounds: &Aabb,
    origin: DVec3,
    d: DVec3,
    pixel_angle: f64,
) -> [f64; 4] {
    let left = (1.0 - colour[3]).max(0.0);
    let c = DVec3::new(colour[0], colour[1], colour[2]);
    let mut nearest: Option<(f64, f64, DVec3)> = None;
    for l in lights {
        let (cov, t) = disc_coverage(l, origin, d, pixel_angle);
        if cov > 0.0 && nearest.is_none_or(|n| t < n.1) {
            nearest = Some((cov, t, l.radiance));
        }
    }
    let ray = Ray { origin, dir: d };
    let out = match nearest {
        None => c + left * back,
        Some((cov, t, l)) if before_bounds(&ray, bounds, t) => {
            (1.0 - cov) * (c + left * back) + cov * l
        }
        Some((cov, _, l)) => c + left * ((1.0 - cov) * back + cov * l),
    };
    [out.x, out.y, out.z, 1.0]
}

#[cfg(test)]
mod tests;
