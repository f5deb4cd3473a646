//! The CPU reference of the march (f64): the same quadrature as
//! `shaders/march/volume_march.wgsl`, over any [`RadianceField`].

use glam::DVec3;
use rayon::prelude::*;

use super::knobs::MarchKnobs;
use crate::camera::CameraFrame;
use crate::field::RadianceField;
use crate::geometry::{ray_box, Ray};

/// Volume-rendering integrals along one ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarchResult {
    /// Ĉ: premultiplied colour.
    pub colour: DVec3,
    /// Ô: opacity.
    pub opacity: f64,
    /// D̂: opacity-weighted depth (distance along the ray).
    pub depth: f64,
    /// Where the opacity first reached 1/2 (within its segment, solved
    /// exactly for the segment's density), or −1 if it never did: the
    /// first surface that hides most of what lies behind it. Behind glass
    /// D̂/Ô lies between the glass and the table; this lies on the table.
    pub half_depth: f64,
    /// Field samples evaluated (skipped ones not counted).
    pub samples: u32,
}

impl Default for MarchResult {
    fn default() -> Self {
        Self {
            colour: DVec3::ZERO,
            opacity: 0.0,
            depth: 0.0,
            half_depth: -1.0,
            samples: 0,
        }
    }
}

/// One sample of the march's quadrature: the segment [a, b] of the ray,
/// sampled at its midpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarchSample {
    /// The sample point.
    pub x: DVec3,
    /// Its distance along the ray (the segment's midpoint).
    pub t: f64,
    /// The segment's start.
    pub a: f64,
    /// The segment's end.
    pub b: f64,
    /// Density at the point.
    pub sigma: f64,
    /// Colour at the point, seen along the ray.
    pub colour: DVec3,
    /// Transmittance from the ray's start to the segment's start.
    pub transmittance: f64,
    /// The sample's weight T·(1 − e^{−σ(b−a)}).
    pub weight: f64,
}

/// Walks the march's quadrature along `ray` (unit direction) through
/// `field`, clipped at distance `t_object`, handing each sample evaluated
/// to `visit` (skipped empty space is not visited); stops where the march
/// stops. The one definition of the samples `march_ray` sums.
pub fn march_samples(
    field: &dyn RadianceField,
    ray: &Ray,
    t_object: f64,
    knobs: &MarchKnobs,
    mut visit: impl FnMut(&MarchSample),
) {
    let bounds = field.bounds();
    let Some((t_near, t_far)) = ray_box(ray, &bounds) else {
        return;
    };
    let (t0, t1) = (t_object.min(t_near), t_object.min(t_far));
    if t1 <= t0 {
        return;
    }
    let step = knobs.step(bounds.diagonal());
    let mut transmittance = 1.0;
    let mut k: u64 = 0;
    loop {
        let a = t0 + k as f64 * step;
        if a >= t1 {
            break;
        }
        let b = (a + step).min(t1);
        let t = 0.5 * (a + b);
        let x = ray.at(t);
        if knobs.skip_empty {
            if let Some(s) = field.empty_until(x, ray.dir) {
                k = (k + 1).max(((t + s - t0) / step - 0.5).ceil() as u64);
                continue;
            }
        }
        let (sigma, colour) = field.sample(x, ray.dir);
        let attenuation = (-sigma * (b - a)).exp();
        visit(&MarchSample {
            x,
            t,
            a,
            b,
            sigma,
            colour,
            transmittance,
            weight: transmittance * (1.0 - attenuation),
        });
        transmittance *= attenuation;
        if transmittance < knobs.termination {
            break;
        }
        k += 1;
    }
}

/// Marches `ray` (unit direction) through `field`, clipped at distance
/// `t_object` (`f64::INFINITY` when no object is in the way).
pub fn march_ray(
    field: &dyn RadianceField,
    ray: &Ray,
    t_object: f64,
    knobs: &MarchKnobs,
) -> MarchResult {
    let mut r = MarchResult::default();
    march_samples(field, ray, t_object, knobs, |s| {
        r.samples += 1;
        let w = s.weight;
        if r.half_depth < 0.0 && r.opacity + w >= 0.5 {
            // T(s) = transmittance·e^{−σs} = 1/2 within [a, b].
            let d = (2.0 * s.transmittance).ln() / s.sigma.max(1e-30);
            r.half_depth = s.a + d.clamp(0.0, s.b - s.a);
        }
        r.colour += w * s.colour;
        r.opacity += w;
        r.depth += w * s.t;
    });
    r
}

/// Marches every pixel centre of `camera`; `object_depth(x, y)` gives the
/// clip distance per pixel. Row-major from the top.
pub fn march_image(
    field: &dyn RadianceField,
    camera: &CameraFrame,
    knobs: &MarchKnobs,
    object_depth: &(dyn Fn(u32, u32) -> f64 + Sync),
) -> Vec<MarchResult> {
    (0..camera.height)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..camera.width)
                .map(move |x| march_ray(field, &camera.pixel_ray(x, y), object_depth(x, y), knobs))
        })
        .collect()
}
