//! The CPU reference of the fit (f64): the same model, start, step and
//! accept/reject rule as the GPU pass.

use rayon::prelude::*;

use super::knobs::FitKnobs;
use super::model::{
    apply_step, cold_start, cost, jacobian_rows, max_sharpness, ProbeSamples, PARAMS_PER_LOBE,
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

/// The normal matrix JᵀJ (row-major) and gradient Jᵀr at `lobes`.
fn normal_equations(probe: &ProbeSamples, lobes: &[Sg64]) -> (Vec<f64>, Vec<f64>) {
    let p = PARAMS_PER_LOBE * lobes.len();
    let zero = || (vec![0.0; p * p], vec![0.0; p]);
    (0..probe.directions.len())
        .into_par_iter()
        .fold(zero, |(mut a, mut b), t| {
            let mut rows = [Vec::new(), Vec::new(), Vec::new()];
            jacobian_rows(probe, lobes, t, &mut rows);
            for row in &rows {
                let nz: Vec<usize> = (0..p).filter(|&i| row[i] != 0.0).collect();
                for &i in &nz {
                    b[i] += row[i] * row[p];
                    for &j in &nz {
                        a[i * p + j] += row[i] * row[j];
                    }
                }
            }
            (a, b)
        })
        .reduce(zero, |(mut a, mut b), (a2, b2)| {
            a.iter_mut().zip(a2).for_each(|(x, y)| *x += y);
            b.iter_mut().zip(b2).for_each(|(x, y)| *x += y);
            (a, b)
        })
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
    let p = knobs.parameters();
    let mut eta = knobs.damping;
    let mut costs = vec![current];
    let mut accepted = 0;
    let mut normal: Option<(Vec<f64>, Vec<f64>)> = None;
    for _ in 0..iterations {
        let (a, b) = normal.get_or_insert_with(|| normal_equations(probe, &lobes));
        let candidate = damped_step(a, b, p, eta)
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
