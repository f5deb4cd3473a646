//! The prior that keeps out of the estimated environment the light which
//! only the model's misfit asks for (not in the paper): a charge on the
//! environment's share of each surface point's irradiance.

use super::fit_data::{mean_given_luminance, mean_luminance, FitData};

/// The prior that keeps out of the environment light which only the
/// model's misfit asks for: the loss gains `weight`·s̄, the mean over
/// points of the environment's share of each point's irradiance,
/// s = Y(E_env)/(Y(E_nerf) + Y(E_env) + ε) in luminance Y (E_nerf with
/// the known lights' light, [`FitData::given`]).
///
/// The share, unlike the light's energy, is blind to where the light comes
/// from and how much of it there is once it dominates: a point that the
/// environment lights almost alone (s near 1) barely feels it, so the
/// scenes whose light is hidden keep their light's strength and
/// direction, while light added to points that the field itself lights
/// costs in proportion to the share it takes. ε (a hundredth of the mean
/// Y(E_nerf)) bounds the slope at points the field leaves dark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharePrior {
    /// The weight: κ·L̄², κ the knob and L̄ the points' mean radiance
    /// luminance (so κ is a fraction of the loss's scale).
    pub weight: f64,
    /// ε, in irradiance.
    pub floor: f64,
}

impl SharePrior {
    /// The prior for knob `kappa` on `data`.
    pub fn new(kappa: f64, data: &FitData) -> Self {
        let mean_near = mean_given_luminance(data);
        let mean = mean_luminance(data.points);
        Self {
            weight: kappa * mean * mean,
            floor: 0.01 * mean_near,
        }
    }

    /// The prior's value at one point, with near-field luminance `near` and
    /// environment luminance `env`.
    pub fn value(&self, near: f64, env: f64) -> f64 {
        let env = env.max(0.0);
        let total = near + env + self.floor;
        if total > 0.0 {
            self.weight * env / total
        } else {
            0.0
        }
    }

    /// d[`Self::value`]/d`env`.
    pub fn slope(&self, near: f64, env: f64) -> f64 {
        let total = near + env.max(0.0) + self.floor;
        if total > 0.0 {
            self.weight * (near + self.floor) / (total * total)
        } else {
            0.0
        }
    }
}
