//! Dropping, at the end of the fit, the lobes whose light the surface
//! points do not see (not in the paper): how much of each lobe reaches
//! the points, and which lobes go.

use glam::DVec3;
use rayon::prelude::*;

use super::env_model::{env_term, lobes, EnvSampler, PARAMS_PER_LOBE};
use super::fit_data::FitData;
use crate::rng::Pcg32;
use crate::sg::Sg64;
use crate::sgfit::model::luminance;

/// A lobe of which less than this fraction of the energy reaches the
/// points, on average (cosine-weighted, through their cached opacity), is
/// unsupported by them; see [`prune_unseen`].
pub const MIN_LOBE_REACH: f64 = 0.01;

/// An unsupported lobe is dropped only if it also gives less than this
/// fraction of the light that reaches the points from the whole
/// environment (a light that few points see, such as one through a window,
/// is kept by the share it gives them).
pub const MAX_DROPPED_SHARE: f64 = 0.05;

/// Each lobe's mean luminance irradiance over the points (through their
/// cached opacity), `samples` directions per point from the mixture.
pub fn lobe_reach(data: &FitData, env_lobes: &[Sg64], samples: u32, seed: u64) -> Vec<f64> {
    let sampler = EnvSampler::new(env_lobes);
    let n = data.points.len();
    let sums = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Pcg32::new(seed ^ 0x4EAC, i as u64);
            let visibility = |d: DVec3| 1.0 - data.near.opacity_at(i, d);
            let term = env_term(
                env_lobes,
                &sampler,
                data.points[i].normal,
                samples,
                &visibility,
                &mut rng,
            );
            env_lobes
                .iter()
                .map(|l| luminance(term.lobe_irradiance(l)))
                .collect::<Vec<f64>>()
        })
        .collect::<Vec<Vec<f64>>>();
    // Summed in point order, so that the same points give the same reach.
    let mut reach = vec![0.0; env_lobes.len()];
    for per_point in sums {
        reach.iter_mut().zip(per_point).for_each(|(r, v)| *r += v);
    }
    reach.into_iter().map(|s| s / n.max(1) as f64).collect()
}

/// The packed parameters `env` without the lobes the points do not
/// support: less than [`MIN_LOBE_REACH`] of the lobe's energy reaches
/// them and it gives less than [`MAX_DROPPED_SHARE`] of the light that
/// reaches them. Facing below every surface or behind every occluder, such
/// a lobe feels almost no gradient and keeps what it started with; kept,
/// it would stand in the estimate as light the field gives no evidence of.
/// When no lobe reaches the points at all, none is kept.
pub fn prune_unseen(data: &FitData, env: &[f64], samples: u32, seed: u64) -> Vec<f64> {
    let env_lobes = lobes(env);
    let reach = lobe_reach(data, &env_lobes, samples.max(64), seed);
    let total: f64 = reach.iter().sum();
    env.chunks_exact(PARAMS_PER_LOBE)
        .zip(env_lobes.iter().zip(&reach))
        .filter(|(_, (l, r))| {
            let energy = luminance(l.integral());
            let supported = **r >= MIN_LOBE_REACH * energy;
            total > 0.0 && (supported || **r >= MAX_DROPPED_SHARE * total)
        })
        .flat_map(|(p, _)| p.iter().copied())
        .collect()
}
