//! Importance sampling of one f64 lobe (the path tracer's environment).

use glam::DVec3;

use super::Sg64;

impl Sg64 {
    /// A direction distributed ∝ exp(λ(v·p − 1)) from two uniform numbers.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let l = self.sharpness;
        // Inverse CDF of cos θ: 1 + ln(1 − u(1 − e^{−2λ}))/λ, stable near λ → 0.
        let cos = (1.0 + (-u[0] * Self::one_minus_exp_neg(2.0 * l)).ln_1p() / l).clamp(-1.0, 1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u[1];
        let (t, b) = self.direction.any_orthonormal_pair();
        sin * phi.cos() * t + sin * phi.sin() * b + cos * self.direction
    }

    /// The density (per steradian) with which [`Self::sample`] picks `v`.
    pub fn pdf(&self, v: DVec3) -> f64 {
        self.weight(v) / Self::sphere_factor(self.sharpness)
    }
}
