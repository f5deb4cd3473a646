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

/// Marches `ray` (unit direction) through `field`, clipped at distance
/// `t_object` (`f64::INFINITY` when no object is in the way).
pub fn march_ray(
    field: &dyn RadianceField,
    ray: &Ray,
    t_object: f64,
    knobs: &MarchKnobs,
) -> MarchResult {
    let mut r = MarchResult::default();
    let bounds = field.bounds();
    let Some((t_near, t_far)) = ray_box(ray, &bounds) else {
        return r;
    };
    let (t0, t1) = (t_object.min(t_near), t_object.min(t_far));
    if t1 <= t0 {
        return r;
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
        let (sigma, c) = field.sample(x, ray.dir);
        r.samples += 1;
        let attenuation = (-sigma * (b - a)).exp();
        let w = transmittance * (1.0 - attenuation);
        if r.half_depth < 0.0 && r.opacity + w >= 0.5 {
            // T(s) = transmittance·e^{−σs} = 1/2 within [a, b].
            let s = (2.0 * transmittance).ln() / sigma.max(1e-30);
            r.half_depth = a + s.clamp(0.0, b - a);
        }
        r.colour += w * c;
        r.opacity += w;
        r.depth += w * t;
        transmittance *= attenuation;
        if transmittance < knobs.termination {
            break;
        }
        k += 1;
    }
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
