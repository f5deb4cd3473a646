//! The CPU reference of the probe trace (f64): eq. 1 over the same direction
//! map, sub-samples and march quadrature as `shaders/probe/trace.wgsl`.

use glam::DVec3;
use rayon::prelude::*;

use super::direction_map::DirectionMap;
use super::knobs::ProbeKnobs;
use super::texel_filter::texel_environment;
use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::lighting::local::{inside_colour, LocalLight};
use crate::march::{march_ray, MarchKnobs};
use crate::sg::Sg64;

/// For every texel of the knobs' map, row by row, seen from `origin`: the
/// solid-angle mean over the texel's `supersampling`² stratified rays of
/// L_i = (1 − Ô)·L_env + Ĉ (rgb) and of Ô (alpha), L_env blurred as the
/// GPU pass blurs it ([`texel_environment`]). With no lobes the L_env
/// term is skipped.
pub fn trace_probe(
    field: &dyn RadianceField,
    origin: DVec3,
    knobs: &ProbeKnobs,
    march: &MarchKnobs,
    environment: &[Sg64],
) -> Vec<[f64; 4]> {
    trace_probe_without(field, origin, knobs, march, environment, &[])
}

/// As [`trace_probe`], with the light of the `local` lights active from
/// `origin` left out ([`crate::lighting::local::inside_colour`]).
pub fn trace_probe_without(
    field: &dyn RadianceField,
    origin: DVec3,
    knobs: &ProbeKnobs,
    march: &MarchKnobs,
    environment: &[Sg64],
    local: &[LocalLight],
) -> Vec<[f64; 4]> {
    let local: Vec<LocalLight> = local.iter().copied().filter(|l| l.active(origin)).collect();
    let map = knobs.direction_map();
    let side = knobs.supersampling;
    let env = texel_environment(environment, &map, side);
    (0..map.texels())
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i as u32 % map.width, i as u32 / map.width);
            trace_texel(field, origin, &map, (x, y), side, march, &env, &local)
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn trace_texel(
    field: &dyn RadianceField,
    origin: DVec3,
    map: &DirectionMap,
    (x, y): (u32, u32),
    side: u32,
    march: &MarchKnobs,
    env: &[Sg64],
    local: &[LocalLight],
) -> [f64; 4] {
    let (mut l, mut opacity, mut weight) = (DVec3::ZERO, 0.0, 0.0);
    for j in 0..side {
        for i in 0..side {
            let (u, v) = map.subsample_uv(x, y, i, j, side);
            let (dir, density) = map.direction_and_density(u, v);
            let r = march_ray(field, &Ray { origin, dir }, f64::INFINITY, march);
            let inside: DVec3 = local
                .iter()
                .map(|l| inside_colour(field, l, origin, dir, march))
                .sum();
            let mut s = (r.colour - inside).max(DVec3::ZERO);
            if !env.is_empty() {
                let e: DVec3 = env.iter().map(|g| g.eval(dir)).sum();
                s += (1.0 - r.opacity) * e;
            }
            l += density * s;
            opacity += density * r.opacity;
            weight += density;
        }
    }
    let l = l / weight;
    [l.x, l.y, l.z, opacity / weight]
}
