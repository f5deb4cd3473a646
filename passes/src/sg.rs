//! Spherical Gaussians G(v; p, λ, μ) = μ·exp(λ(v·p − 1)) (METHOD.md eq. 2):
//! the pieces the environment light of a recipe needs (evaluation, integral
//! over the sphere, importance sampling). Issue 4 grows this into the full SG
//! library with its WGSL mirror.

use glam::DVec3;
use serde::Deserialize;

/// One RGB spherical Gaussian lobe.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SgLobe {
    /// Lobe axis p (normalised on use).
    pub direction: DVec3,
    /// Sharpness λ > 0.
    pub sharpness: f64,
    /// RGB amplitude μ ≥ 0 (radiance at the lobe centre).
    pub amplitude: DVec3,
}

/// 1 − e^{−2λ}, accurate for small λ.
fn one_minus_exp_m2l(lambda: f64) -> f64 {
    -(-2.0 * lambda).exp_m1()
}

impl SgLobe {
    /// The lobe's value in unit direction `v`.
    pub fn eval(&self, v: DVec3) -> DVec3 {
        self.amplitude * (self.sharpness * (v.dot(self.direction) - 1.0)).exp()
    }

    /// ∫ over the sphere: 2π μ (1 − e^{−2λ}) / λ.
    pub fn integral(&self) -> DVec3 {
        self.amplitude
            * (2.0 * std::f64::consts::PI * one_minus_exp_m2l(self.sharpness) / self.sharpness)
    }

    /// A direction distributed ∝ exp(λ(v·p − 1)) from two uniform numbers.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let l = self.sharpness;
        // Inverse CDF of cos θ: 1 + ln(1 − u(1 − e^{−2λ}))/λ, stable near λ → 0.
        let cos = (1.0 + (-u[0] * one_minus_exp_m2l(l)).ln_1p() / l).clamp(-1.0, 1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u[1];
        let (t, b) = self.direction.any_orthonormal_pair();
        sin * phi.cos() * t + sin * phi.sin() * b + cos * self.direction
    }

    /// The density (per steradian) with which [`Self::sample`] picks `v`.
    pub fn pdf(&self, v: DVec3) -> f64 {
        let l = self.sharpness;
        l * (l * (v.dot(self.direction) - 1.0)).exp()
            / (2.0 * std::f64::consts::PI * one_minus_exp_m2l(l))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Riemann sum over the sphere in (cos θ, φ) around the lobe axis.
    fn quadrature(f: impl Fn(DVec3) -> f64, axis: DVec3) -> f64 {
        let (t, b) = axis.any_orthonormal_pair();
        let n = 4000;
        let m = 64;
        let mut sum = 0.0;
        for i in 0..n {
            let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..m {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / m as f64;
                sum += f(s * phi.cos() * t + s * phi.sin() * b + c * axis);
            }
        }
        sum * 4.0 * std::f64::consts::PI / (n * m) as f64
    }

    #[test]
    fn integral_and_pdf_match_quadrature() {
        for l in [1e-4, 0.1, 1.0, 10.0, 200.0] {
            let g = SgLobe {
                direction: DVec3::new(0.2, 1.0, -0.3).normalize(),
                sharpness: l,
                amplitude: DVec3::new(1.0, 2.0, 3.0),
            };
            let q = quadrature(|v| g.eval(v).y, g.direction);
            assert!(
                (q / g.integral().y - 1.0).abs() < 2e-3,
                "λ={l}: {q} vs {}",
                g.integral().y
            );
            let p = quadrature(|v| g.pdf(v), g.direction);
            assert!((p - 1.0).abs() < 2e-3, "λ={l}: pdf integrates to {p}");
        }
    }

    #[test]
    fn samples_follow_the_lobe() {
        let g = SgLobe {
            direction: DVec3::Z,
            sharpness: 8.0,
            amplitude: DVec3::ONE,
        };
        let mut rng = crate::rng::Pcg32::new(3, 0);
        let n = 20000;
        let mean_cos: f64 = (0..n).map(|_| g.sample(rng.next_2d()).z).sum::<f64>() / n as f64;
        // E[cos θ] = coth(λ)·... for the SG density: 1/tanh(λ)·(1) − 1/λ on (−1, 1].
        let expected = 1.0 / (8.0f64).tanh() - 1.0 / 8.0;
        assert!(
            (mean_cos - expected).abs() < 5e-3,
            "{mean_cos} vs {expected}"
        );
    }
}
