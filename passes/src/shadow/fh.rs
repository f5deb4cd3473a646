//! f_h(θ, λ) (METHOD.md "f_h"): the integral of a unit-amplitude SG of
//! sharpness λ over the side of a great circle whose signed angular
//! distance from the lobe centre is θ — the half-space model of visibility
//! behind the self-shadow factor Γ_k (eq. 9) and the cast shadow ρ (eq. 8).
//!
//! [`fh_exact`] evaluates it by f64 quadrature of its one-dimensional form;
//! [`FhTable`] tabulates the visible fraction q = f_h(θ, λ) / f_h(π/2, λ)
//! once, on a grid that follows the function's shape, for the GPU
//! (`shaders/shadow/fh.wgsl` mirrors [`FhTable::fraction`]). f_h(π/2, λ),
//! the hemisphere around the lobe, has the closed form 2π(1 − e^{−λ})/λ.
//!
//! **Beyond |θ| = π/2** (SSDF values span [−π, π]; a great circle lies at
//! most π/2 from the lobe centre) the model saturates: θ is clamped to
//! [−π/2, π/2], so q = 1 for θ ≥ π/2 (nothing is blocked that the model can
//! express) and q = q(−π/2, λ) = e^{−λ} for θ ≤ −π/2 (the hemisphere around
//! the lobe is blocked; for broad lobes the other half still shows).

use std::f64::consts::{FRAC_PI_2, PI};

use crate::sg::quadrature::integrate_pieces;
use crate::sg::Sg64;

/// Columns (the θ axis) of the table.
pub const FH_COLUMNS: u32 = 64;
/// Rows (the λ axis, logarithmic) of the table.
pub const FH_ROWS: u32 = 128;
/// The sharpness range of the rows; below it the first row is used (q is
/// within λ/2 of its λ → 0 limit there), above it the last (q then depends
/// on θ√λ only, which the column warp already follows).
pub const FH_SHARPNESS_RANGE: (f64, f64) = (1e-3, 1e5);

/// f_h(π/2, λ) = 2π(1 − e^{−λ})/λ: the lobe's integral over the
/// hemisphere around its axis (2π at λ = 0).
pub fn hemisphere_integral(lambda: f64) -> f64 {
    2.0 * PI * Sg64::one_minus_exp_neg_over_x(lambda.max(0.0))
}

/// f_h(θ, λ) by adaptive quadrature in f64, θ clamped to [−π/2, π/2]:
/// with t = 1 − cos α (α the angle from the lobe axis),
/// f_h = ∫₀² e^{−λt} Φ(1 − t) dt, where Φ(u) is the azimuthal measure of
/// the visible side on the circle at cos α = u, 2·acos(−u sin θ /
/// (cos θ √(1 − u²))) clamped; kinks at u = ±cos θ are break points.
pub fn fh_exact(theta: f64, lambda: f64) -> f64 {
    let theta = theta.clamp(-FRAC_PI_2, FRAC_PI_2);
    let lambda = lambda.max(0.0);
    let (st, ct) = theta.sin_cos();
    let mut f = |t: f64| {
        let u = 1.0 - t;
        let a = ct * (t * (2.0 - t)).max(0.0).sqrt();
        let b = u * st;
        let phi = if a <= 1e-300 {
            if b >= 0.0 {
                2.0 * PI
            } else {
                0.0
            }
        } else {
            2.0 * (-b / a).clamp(-1.0, 1.0).acos()
        };
        (-lambda * t).exp() * phi
    };
    let mut breaks = vec![0.0, 2.0, 1.0 - ct, 1.0 + ct];
    for k in [1.0, 4.0, 16.0, 64.0] {
        if lambda > 0.0 && k / lambda < 2.0 {
            breaks.push(k / lambda);
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    let tol = 1e-12 * hemisphere_integral(lambda);
    integrate_pieces(&mut f, &breaks, tol)
}

/// The table's column coordinate in [−1, 1] for (θ, λ):
/// tanh(sθ)/tanh(sπ/2) with s = √λ/2, which spreads the columns over the
/// transition of width ~1/√λ around θ = 0 (θ/(π/2) as λ → 0).
pub fn fh_column_coordinate(theta: f64, lambda: f64) -> f64 {
    let theta = theta.clamp(-FRAC_PI_2, FRAC_PI_2);
    let s = 0.5 * lambda.max(0.0).sqrt();
    if s < 1e-3 {
        theta / FRAC_PI_2
    } else {
        (s * theta).tanh() / (s * FRAC_PI_2).tanh()
    }
}

/// The θ whose column coordinate is `c` at sharpness λ (inverse of
/// [`fh_column_coordinate`]).
fn theta_of_column(c: f64, lambda: f64) -> f64 {
    let s = 0.5 * lambda.max(0.0).sqrt();
    if s < 1e-3 {
        c * FRAC_PI_2
    } else {
        (c * (s * FRAC_PI_2).tanh()).clamp(-1.0, 1.0).atanh() / s
    }
}

/// The sharpness of row `r` (log-spaced over [`FH_SHARPNESS_RANGE`]).
fn row_sharpness(r: u32) -> f64 {
    let (lo, hi) = FH_SHARPNESS_RANGE;
    let t = r as f64 / (FH_ROWS - 1) as f64;
    (lo.ln() + t * (hi.ln() - lo.ln())).exp()
}

/// The visible fraction q(θ, λ) = f_h(θ, λ) / f_h(π/2, λ) tabulated over
/// [`FH_COLUMNS`] × [`FH_ROWS`] (row-major, θ across), read bilinearly.
#[derive(Debug, Clone)]
pub struct FhTable {
    values: Vec<f32>,
}

impl Default for FhTable {
    fn default() -> Self {
        Self::new()
    }
}

impl FhTable {
    /// Tabulates q by [`fh_exact`] (about 4096 quadratures, tens of ms).
    pub fn new() -> Self {
        use rayon::prelude::*;
        let values = (0..FH_ROWS * FH_COLUMNS)
            .into_par_iter()
            .map(|i| {
                let (c, r) = (i % FH_COLUMNS, i / FH_COLUMNS);
                let lambda = row_sharpness(r);
                let col = -1.0 + 2.0 * c as f64 / (FH_COLUMNS - 1) as f64;
                let theta = theta_of_column(col, lambda);
                (fh_exact(theta, lambda) / hemisphere_integral(lambda)).clamp(0.0, 1.0) as f32
            })
            .collect();
        Self { values }
    }

    /// The table, row-major, for the GPU.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// q(θ, λ) from the table, bilinearly, in f32 exactly as
    /// `fh_fraction` in `shaders/shadow/fh.wgsl` computes it.
    pub fn fraction(&self, theta: f32, lambda: f32) -> f32 {
        let (lo, hi) = (FH_SHARPNESS_RANGE.0 as f32, FH_SHARPNESS_RANGE.1 as f32);
        let l = lambda.clamp(lo, hi);
        let row = (l.ln() - lo.ln()) / (hi.ln() - lo.ln()) * (FH_ROWS - 1) as f32;
        let th = theta.clamp(-std::f32::consts::FRAC_PI_2, std::f32::consts::FRAC_PI_2);
        let s = 0.5 * lambda.max(0.0).sqrt();
        let c = if s < 1e-3 {
            th / std::f32::consts::FRAC_PI_2
        } else {
            (s * th).tanh() / (s * std::f32::consts::FRAC_PI_2).tanh()
        };
        let col = (c + 1.0) * 0.5 * (FH_COLUMNS - 1) as f32;
        let (c0, r0) = (
            (col.floor() as u32).min(FH_COLUMNS - 2),
            (row.floor() as u32).min(FH_ROWS - 2),
        );
        let (fc, fr) = (col - c0 as f32, row - r0 as f32);
        let at = |c: u32, r: u32| self.values[(r * FH_COLUMNS + c) as usize];
        let top = at(c0, r0) * (1.0 - fc) + at(c0 + 1, r0) * fc;
        let bottom = at(c0, r0 + 1) * (1.0 - fc) + at(c0 + 1, r0 + 1) * fc;
        top * (1.0 - fr) + bottom * fr
    }

    /// f_h(θ, λ) from the table: q times the closed-form hemisphere integral.
    pub fn fh(&self, theta: f64, lambda: f64) -> f64 {
        self.fraction(theta as f32, lambda as f32) as f64 * hemisphere_integral(lambda)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// f_h by Monte Carlo over the sphere, sampling the lobe itself:
    /// (sphere integral) × (fraction of samples on the visible side), with
    /// its standard error. Independent of the one-dimensional form.
    fn fh_monte_carlo(theta: f64, lambda: f64, n: u32) -> (f64, f64) {
        let t = theta.clamp(-FRAC_PI_2, FRAC_PI_2);
        let g = Sg64 {
            direction: DVec3::Z,
            sharpness: lambda,
            amplitude: DVec3::ONE,
        };
        let normal = DVec3::new(t.cos(), 0.0, t.sin());
        let mut rng = crate::rng::Pcg32::new(lambda.to_bits() ^ theta.to_bits(), 7);
        let hits = (0..n)
            .filter(|_| g.sample(rng.next_2d()).dot(normal) >= 0.0)
            .count() as f64;
        let p = hits / n as f64;
        let full = Sg64::sphere_factor(lambda);
        (
            full * p,
            full * (p * (1.0 - p) / n as f64).sqrt().max(1.0 / n as f64),
        )
    }

    #[test]
    fn exact_form_matches_sphere_quadrature_and_closed_forms() {
        for lambda in [0.0, 1e-4, 0.3, 2.3, 40.0, 1e4, 3e4] {
            // Closed forms: the hemisphere around the lobe and the one opposite.
            let hemi = hemisphere_integral(lambda);
            assert!((fh_exact(FRAC_PI_2, lambda) / hemi - 1.0).abs() < 1e-9);
            let opposite =
                2.0 * PI * ((-lambda).exp() - (-2.0 * lambda).exp()) / lambda.max(1e-300);
            let opposite = if lambda == 0.0 { 2.0 * PI } else { opposite };
            assert!((fh_exact(-FRAC_PI_2, lambda) - opposite).abs() < 1e-9 * hemi);
            // Half the sphere integral at θ = 0 by symmetry.
            let full = hemi + opposite;
            assert!((fh_exact(0.0, lambda) / (0.5 * full) - 1.0).abs() < 1e-9);
            if lambda > 0.0 {
                for theta in [-1.2, -0.3, -0.01, 0.004, 0.2, 0.9] {
                    let a = fh_exact(theta, lambda);
                    let (b, sigma) = fh_monte_carlo(theta, lambda, 40_000);
                    assert!(
                        (a - b).abs() < 5.0 * sigma,
                        "θ {theta} λ {lambda}: {a} vs {b} ± {sigma}"
                    );
                }
            }
        }
    }

    /// The table's worst error on the visible fraction, over a dense sweep
    /// off the table's nodes, including λ far below and above its range.
    #[test]
    fn table_matches_quadrature_including_extreme_sharpness() {
        let table = FhTable::new();
        let mut worst = (0.0, 0.0, 0.0);
        for lambda in [
            1e-6f64, 1e-3, 0.05, 0.7, 2.293, 9.0, 130.0, 1e3, 1e4, 2.5e4, 1e5, 1e6,
        ] {
            let width = 1.0 / lambda.sqrt().max(1.0);
            for i in 0..=97 {
                let x = -1.0 + 2.0 * i as f64 / 97.0;
                // Dense near the transition, then out to the saturated ends.
                for theta in [x * 4.0 * width, x * FRAC_PI_2, x * 2.0] {
                    let exact = fh_exact(theta, lambda) / hemisphere_integral(lambda);
                    let got = table.fraction(theta as f32, lambda as f32) as f64;
                    if (got - exact).abs() > worst.0 {
                        worst = ((got - exact).abs(), theta, lambda);
                    }
                }
            }
        }
        // Measured: 1.1e-3 (λ = 2.3, θ near −π/2, between rows) and 1e-3
        // below the range (λ = 10⁻⁶ reads the λ = 10⁻³ row).
        assert!(
            worst.0 < 2e-3,
            "worst |Δq| {} at θ {} λ {}",
            worst.0,
            worst.1,
            worst.2
        );
    }

    #[test]
    fn saturates_beyond_a_quarter_turn() {
        let table = FhTable::new();
        for lambda in [0.01f32, 3.0, 500.0] {
            assert_eq!(
                table.fraction(3.0, lambda),
                table.fraction(FRAC_PI_2 as f32, lambda)
            );
            assert_eq!(
                table.fraction(-3.0, lambda),
                table.fraction(-FRAC_PI_2 as f32, lambda)
            );
            assert!((table.fraction(FRAC_PI_2 as f32, lambda) - 1.0).abs() < 1e-6);
            let lo = table.fraction(-FRAC_PI_2 as f32, lambda) as f64;
            assert!((lo - (-lambda as f64).exp()).abs() < 2e-3, "{lambda}: {lo}");
        }
    }
}
