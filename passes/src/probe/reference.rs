//! The CPU reference of the probe trace (f64): eq. 1 over the same direction
//! map and march quadrature as `shaders/probe/trace.wgsl`.

use glam::DVec3;
use rayon::prelude::*;

use super::direction_map::DirectionMap;
use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};
use crate::sg::Sg64;

/// L_i = (1 − Ô)·L_env + Ĉ (rgb) and Ô (alpha) for every texel of `map`,
/// row by row, seen from `origin`. With no lobes the L_env term is skipped.
pub fn trace_probe(
    field: &dyn RadianceField,
    origin: DVec3,
    map: &DirectionMap,
    march: &MarchKnobs,
    environment: &[Sg64],
) -> Vec<[f64; 4]> {
    (0..map.texels())
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i as u32 % map.width, i as u32 / map.width);
            let dir = map.direction(x, y);
            let r = march_ray(field, &Ray { origin, dir }, f64::INFINITY, march);
            let mut l = r.colour;
            if !environment.is_empty() {
                let env: DVec3 = environment.iter().map(|g| g.eval(dir)).sum();
                l += (1.0 - r.opacity) * env;
            }
            [l.x, l.y, l.z, r.opacity]
        })
        .collect()
}
