//! The CPU reference of the fit (f64): the same model, start, step and
//! accept/reject rule as the GPU pass.

use rayon::prelude::*;

use super::knobs::FitKnobs;
use super::model::{
    apply_step, cold_start, cost, max_sharpness, normal_from_gram, texel_features, ProbeSamples,
    FEATURES_PER_LOBE,
};
use super::solve::damped_step;
use crate::sg::Sg64;

/// Damping never falls below this or rises above its inverse.
pub const DAMPING_LIMIT: f64 = 1e-9;
/// Damping shrinks by this factor after an accepted step…
pub const DAMPING_DOWN: f64 = 1.0 / 3.0;
/// …and grows by this factor after a rejected one.
pub const DAMPING_UP: f64 = 4.0;

/// Where a fit starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start<'a> {
    /// From [`cold_start`].
    Cold,
    /// From these lobes, unless the cold start fits the probe better.
    Warm(&'a [Sg64]),
}

/// What a fit produced.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// The fitted lobes.
    pub lobes: Vec<Sg64>,
    /// Cost Σ w |fit − L|² after each iteration (index 0: at the start).
    pub costs: Vec<f64>,
    /// Σ w |L|², the cost of fitting nothing.
    pub energy: f64,
    /// Whether the fit started cold (asked for, or the warm start was worse).
    pub started_cold: bool,
    /// Accepted steps.
    pub accepted: u32,
    /// Texels ignored as NaN, infinite or negative.
    pub invalid: usize,
}

impl FitOutcome {
    /// The final relative residual √(cost / energy) (0 for a black probe
    /// fitted exactly).
    pub fn relative_residual(&self) -> f64 {
        relative_residual(*self.costs.last().unwrap_or(&0.0), self.energy)
    }
}

/// √(cost / energy), 0 when both are 0.
pub fn relative_residual(cost: f64, energy: f64) -> f64 {
    if energy > 0.0 {
        (cost / energy).sqrt()
    } else if cost > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// The features' Gram matrix Σ_t f_t f_tᵀ ([`texel_features`], F × F
/// row-major, F = 4M + 3).
pub fn feature_gram(probe: &ProbeSamples, lobes: &[Sg64]) -> Vec<f64> {
    let f = FEATURES_PER_LOBE * lobes.len() + 3;
    (0..probe.directions.len())
        .into_par_iter()
        .fold(
            || (vec![0.0; f * f], Vec::new()),
            |(mut g, mut x), t| {
                texel_features(probe, lobes, t, &mut x);
                if x.iter().any(|v| *v != 0.0) {
                    for i in 0..f {
                        for j in 0..f {
                            g[i * f + j] += x[i] * x[j];
                        }
                    }
                }
                (g, x)
            },
        )
        .map(|(g, _)| g)
        .reduce(
            || vec![0.0; f * f],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                a
            },
        )
}

/// The normal matrix JᵀJ (row-major) and gradient Jᵀr at `lobes`, from
/// the features' Gram matrix as the GPU builds them.
pub fn normal_equations(probe: &ProbeSamples, lobes: &[Sg64]) -> (Vec<f64>, Vec<f64>) {
    normal_from_gram(&feature_gram(probe, lobes), lobes)
}

/// Fits `knobs.lobes` SGs to `probe` by Levenberg–Marquardt for
/// `iterations` iterations, then sets their amplitudes to hold the probe's
/// energy ([`super::conserve_energy`]). The costs are the Levenberg–Marquardt
/// iterations'.
pub fn fit_reference(
    probe: &ProbeSamples,
    knobs: &FitKnobs,
    start: Start,
    iterations: u32,
) -> FitOutcome {
    let cold = cold_start(probe, knobs.lobes);
    let cold_cost = cost(probe, &cold);
    let (mut lobes, mut current, started_cold) = match start {
        Start::Warm(w) if w.len() == cold.len() => {
            let warm_cost = cost(probe, w);
            if warm_cost.is_finite() && warm_cost <= cold_cost {
                (w.to_vec(), warm_cost, false)
            } else {
                (cold, cold_cost, true)
            }
        }
        _ => (cold, cold_cost, true),
    };
    let mut eta = knobs.damping;
    let mut costs = vec![current];
    let mut accepted = 0;
    let mut normal: Option<(Vec<f64>, Vec<f64>)> = None;
    for _ in 0..iterations {
        let (a, b) = normal.get_or_insert_with(|| normal_equations(probe, &lobes));
        let candidate = damped_step(a, b, lobes.len(), eta)
            .map(|d| apply_step(&lobes, &d, max_sharpness(probe.directions.len())));
        let candidate_cost = candidate.as_ref().map(|c| cost(probe, c));
        match (candidate, candidate_cost) {
            (Some(c), Some(cc)) if cc.is_finite() && cc < current => {
                lobes = c;
                current = cc;
                eta = (eta * DAMPING_DOWN).max(DAMPING_LIMIT);
                accepted += 1;
                normal = None;
            }
            _ => eta = (eta * DAMPING_UP).min(1.0 / DAMPING_LIMIT),
        }
        costs.push(current);
    }
    FitOutcome {
        lobes: super::energy::conserve_energy(probe, &lobes),
        costs,
        energy: probe.energy(),
        started_cold,
        accepted,
        invalid: probe.invalid,
    }
}
