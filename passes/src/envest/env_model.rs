//! The environment's parameters in the fit (METHOD.md eq. 2): M SG lobes,
//! each an unnormalised axis v (p = v/|v|), log sharpness and log RGB
//! energy (the lobe's integral over the sphere, so that sharpening a lobe
//! at constant energy is one parameter's move: a light that should be
//! more concentrated, such as a sun, is found by following one gradient),
//! packed 7 per lobe for the optimiser; and the environment term
//! E_env(x) = ∫_{Ω+} (1 − Ô(ω; x)) L_env(ω)(ω·n) dω, importance sampled from
//! the SG mixture with its gradient.
//!
//! **Sampling**: a direction is drawn from the mixture of the lobes
//! (weights ∝ each lobe's luminance integral) with probability 1 − α, or
//! from the cosine lobe about n with probability α = [`DEFENSIVE_FRACTION`]
//! (defensive importance sampling: every direction the integrand can reach
//! keeps a density, so a light where no lobe yet points still pulls a lobe
//! towards it). The density of the combination divides each sample. The
//! gradient treats the sampled directions and their density as fixed: its
//! expectation is the gradient of E_env.

use glam::DVec3;

use super::hemisphere::cosine_direction;
use crate::rng::Pcg32;
use crate::sg::Sg64;
use crate::sgfit::model::{fibonacci_axis, luminance};

/// Parameters per lobe: axis (3), log sharpness (1), log energy (3).
pub const PARAMS_PER_LOBE: usize = 7;

/// Probability of a cosine-distributed sample in [`EnvSampler`].
pub const DEFENSIVE_FRACTION: f64 = 0.25;

/// Smallest sharpness the fit uses.
pub const MIN_SHARPNESS: f64 = 0.05;

/// The starting environment: `m` lobes on a Fibonacci sphere, sharpness
/// m/4 (neighbours overlap), amplitudes giving a uniform radiance of about
/// `radiance`; packed.
pub fn initial_params(m: usize, radiance: f64) -> Vec<f64> {
    let sharpness = (m as f64 / 4.0).max(1.0);
    let energy = (4.0 * std::f64::consts::PI * radiance.max(1e-9) / m as f64).ln();
    (0..m as u32)
        .map(|k| fibonacci_axis(k, m as u32))
        .flat_map(|d| [d.x, d.y, d.z, sharpness.ln(), energy, energy, energy])
        .collect()
}

/// The amplitude per unit energy of a lobe of sharpness λ:
/// 1/∫G = 1/(4π·(1 − e^{−2λ})/(2λ)).
pub fn amplitude_per_energy(sharpness: f64) -> f64 {
    1.0 / (4.0 * std::f64::consts::PI * Sg64::one_minus_exp_neg_over_x(2.0 * sharpness))
}

/// d log(amplitude per energy)/d log λ = 1 − x/(eˣ − 1) with x = 2λ.
fn amplitude_per_energy_slope(sharpness: f64) -> f64 {
    let x = 2.0 * sharpness;
    let r = if x < 1e-4 {
        1.0 - x / 2.0 + x * x / 12.0
    } else {
        x / x.exp_m1()
    };
    1.0 - r
}

/// The lobes `params` describe.
pub fn lobes(params: &[f64]) -> Vec<Sg64> {
    params
        .chunks_exact(PARAMS_PER_LOBE)
        .map(|p| Sg64 {
            direction: DVec3::new(p[0], p[1], p[2]).normalize_or(DVec3::Y),
            sharpness: p[3].exp(),
            amplitude: DVec3::new(p[4], p[5], p[6]).exp() * amplitude_per_energy(p[3].exp()),
        })
        .collect()
}

/// Keeps `params` in range after a step: unit axes, sharpness in
/// [[`MIN_SHARPNESS`], `max_sharpness`], log energies in [−40, 40].
pub fn project(params: &mut [f64], max_sharpness: f64) {
    for p in params.chunks_exact_mut(PARAMS_PER_LOBE) {
        let v = DVec3::new(p[0], p[1], p[2]).normalize_or(DVec3::Y);
        p[..3].copy_from_slice(&v.to_array());
        p[3] = p[3].clamp(MIN_SHARPNESS.ln(), max_sharpness.ln());
        for a in &mut p[4..7] {
            *a = a.clamp(-40.0, 40.0);
        }
    }
}

/// Draws directions from the current lobes' mixture (defensively mixed
/// with the cosine lobe) and gives their density.
#[derive(Debug, Clone)]
pub struct EnvSampler {
    lobes: Vec<Sg64>,
    cdf: Vec<f64>,
    weights: Vec<f64>,
}

impl EnvSampler {
    /// A sampler for `lobes`.
    pub fn new(lobes: &[Sg64]) -> Self {
        let energy: Vec<f64> = lobes
            .iter()
            .map(|l| luminance(l.integral()).max(0.0))
            .collect();
        let total: f64 = energy.iter().sum();
        let weights: Vec<f64> = if total > 0.0 {
            energy.iter().map(|e| e / total).collect()
        } else {
            vec![1.0 / lobes.len().max(1) as f64; lobes.len()]
        };
        let mut cdf = Vec::with_capacity(lobes.len());
        let mut acc = 0.0;
        for w in &weights {
            acc += w;
            cdf.push(acc);
        }
        Self {
            lobes: lobes.to_vec(),
            cdf,
            weights,
        }
    }

    /// A direction for surface normal `n`.
    pub fn sample(&self, n: DVec3, rng: &mut Pcg32) -> DVec3 {
        let pick = rng.next_f64();
        let u = rng.next_2d();
        if pick < DEFENSIVE_FRACTION || self.lobes.is_empty() {
            return cosine_direction(n, u);
        }
        let x = (pick - DEFENSIVE_FRACTION) / (1.0 - DEFENSIVE_FRACTION);
        let k = self
            .cdf
            .partition_point(|c| *c <= x)
            .min(self.lobes.len() - 1);
        self.lobes[k].sample(u)
    }

    /// The density of [`Self::sample`] at `d` for normal `n`.
    pub fn pdf(&self, n: DVec3, d: DVec3) -> f64 {
        let cosine = d.dot(n).max(0.0) / std::f64::consts::PI;
        let mixture: f64 = self
            .lobes
            .iter()
            .zip(&self.weights)
            .map(|(l, w)| w * l.pdf(d))
            .sum();
        DEFENSIVE_FRACTION * cosine + (1.0 - DEFENSIVE_FRACTION) * mixture
    }
}

/// One point's sampled environment term: E_env and what its gradient needs.
#[derive(Debug, Clone)]
pub struct EnvTerm {
    /// The estimate of E_env (RGB).
    pub irradiance: DVec3,
    samples: Vec<(DVec3, f64)>,
}

/// E_env at a point with normal `n` from `samples` directions drawn by
/// `sampler`, `visibility(ω)` = 1 − Ô(ω; x).
pub fn env_term(
    lobes: &[Sg64],
    sampler: &EnvSampler,
    n: DVec3,
    samples: u32,
    visibility: &dyn Fn(DVec3) -> f64,
    rng: &mut Pcg32,
) -> EnvTerm {
    let mut kept = Vec::with_capacity(samples as usize);
    let mut e = DVec3::ZERO;
    for _ in 0..samples {
        let d = sampler.sample(n, rng);
        let cos = d.dot(n);
        if cos <= 0.0 {
            continue;
        }
        let pdf = sampler.pdf(n, d);
        if pdf <= 0.0 {
            continue;
        }
        let f = visibility(d) * cos / (pdf * samples as f64);
        if f <= 0.0 {
            continue;
        }
        e += f * lobes.iter().map(|l| l.eval(d)).sum::<DVec3>();
        kept.push((d, f));
    }
    EnvTerm {
        irradiance: e,
        samples: kept,
    }
}

impl EnvTerm {
    /// The part of the estimate that `lobe` (one of the mixture's) gives.
    pub fn lobe_irradiance(&self, lobe: &Sg64) -> DVec3 {
        self.samples.iter().map(|(d, f)| *f * lobe.eval(*d)).sum()
    }

    /// Adds ∂loss/∂params to `grad` given ∂loss/∂E_env (RGB).
    pub fn backward(&self, params: &[f64], d_irradiance: DVec3, grad: &mut [f64]) {
        for (p, grad) in params
            .chunks_exact(PARAMS_PER_LOBE)
            .zip(grad.chunks_exact_mut(PARAMS_PER_LOBE))
        {
            let axis = DVec3::new(p[0], p[1], p[2]);
            let len = axis.length().max(1e-12);
            let axis = axis / len;
            let sharpness = p[3].exp();
            let amplitude = DVec3::new(p[4], p[5], p[6]).exp() * amplitude_per_energy(sharpness);
            let slope = amplitude_per_energy_slope(sharpness);
            for (d, f) in &self.samples {
                let c = d.dot(axis);
                let w = (sharpness * (c - 1.0)).exp();
                if w < 1e-300 {
                    continue;
                }
                // ∂E_c/∂log energy_c = f·G_c; dot with ∂loss/∂E.
                let g = *f * w * amplitude * d_irradiance;
                let gsum = g.x + g.y + g.z;
                grad[3] += gsum * (sharpness * (c - 1.0) + slope);
                let dv = gsum * sharpness * (*d - c * axis) / len;
                grad[0] += dv.x;
                grad[1] += dv.y;
                grad[2] += dv.z;
                grad[4] += g.x;
                grad[5] += g.y;
                grad[6] += g.z;
            }
        }
    }
}
