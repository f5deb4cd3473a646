//! The SG identities, written once and instantiated for f64 ([`Sg64`], the
//! CPU references) and f32 ([`Sg32`], the exact mirror of
//! `shaders/common/sg.wgsl`). Every formula is arranged so that sharpness
//! from 0 to 10⁴ and amplitudes up to 10⁶ neither overflow nor cancel:
//! - v·p − 1 is evaluated as −|v − p|²/2 (no cancellation near the axis);
//! - 1 − e^{−x} and (1 − e^{−x})/x use a series for small x (no expm1 in WGSL);
//! - the product's exponent λm − λ1 − λ2 is evaluated as
//!   −λ1 λ2 |p1 − p2|² / (λm + λ1 + λ2), which is ≤ 0 and exact in sign.

use glam::{DVec3, Vec3};
use serde::Deserialize;

/// Below this x, 1 − e^{−x} and (1 − e^{−x})/x are evaluated by their series
/// (through x¹¹/12!: the truncation error is under 10⁻¹⁵ relative at x = 0.25).
pub const SERIES_BELOW: f64 = 0.25;

/// Sharpness of the one-lobe SG standing for the clamped cosine max(v·n, 0):
/// the L2-closest lobe among those with the cosine's exact integral π
/// (relative L2 error 0.187 against 0.177 for the unconstrained optimum
/// λ = 2.144, μ = 1.177; `tests.rs` checks both by quadrature).
pub const COSINE_SHARPNESS: f64 = 2.293;

macro_rules! sg_math {
    ($name:ident, $t:ident, $v:ident) => {
        /// One RGB spherical Gaussian lobe G(v) = μ·exp(λ(v·p − 1)).
        #[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            /// Lobe axis p, a unit vector (normalise before use).
            #[serde(deserialize_with = "crate::scene::vec3::exact")]
            pub direction: $v,
            /// Sharpness λ ≥ 0 (0 is the constant lobe).
            pub sharpness: $t,
            /// RGB amplitude μ ≥ 0 (the value on the axis).
            #[serde(deserialize_with = "crate::scene::vec3::exact")]
            pub amplitude: $v,
        }

        impl $name {
            /// (1 − e^{−x})/x for x ≥ 0 (1 at x = 0), without cancellation
            /// for small x.
            pub fn one_minus_exp_neg_over_x(x: $t) -> $t {
                if x < SERIES_BELOW as $t {
                    // Σ_{k≥0} (−x)^k/(k+1)!, Horner form, through x¹¹/12!.
                    let mut s: $t = 1.0;
                    let mut k: $t = 12.0;
                    while k >= 2.0 {
                        s = 1.0 - x / k * s;
                        k -= 1.0;
                    }
                    s
                } else {
                    (1.0 - (-x).exp()) / x
                }
            }

            /// 1 − e^{−x} for x ≥ 0, without cancellation for small x.
            pub fn one_minus_exp_neg(x: $t) -> $t {
                x * Self::one_minus_exp_neg_over_x(x)
            }

            /// 2π(1 − e^{−2λ})/λ, the sphere integral of a unit-amplitude
            /// lobe; 4π at λ = 0.
            pub fn sphere_factor(sharpness: $t) -> $t {
                4.0 * std::$t::consts::PI * Self::one_minus_exp_neg_over_x(2.0 * sharpness)
            }

            /// The lobe's value in unit direction `v`.
            pub fn eval(&self, v: $v) -> $v {
                self.amplitude * self.weight(v)
            }

            /// exp(λ(v·p − 1)) for unit `v`: the lobe's shape without its amplitude.
            pub fn weight(&self, v: $v) -> $t {
                (-0.5 * self.sharpness * (v - self.direction).length_squared()).exp()
            }

            /// ∫ G(v) dv over the sphere.
            pub fn integral(&self) -> $v {
                self.amplitude * Self::sphere_factor(self.sharpness)
            }

            /// The SG equal to the product of two SGs.
            pub fn product(&self, other: &Self) -> Self {
                let (l1, l2) = (self.sharpness, other.sharpness);
                let u = self.direction * l1 + other.direction * l2;
                let lm = u.length();
                let sum = lm + l1 + l2;
                let exponent = if sum > 0.0 {
                    -l1 * l2 * (self.direction - other.direction).length_squared() / sum
                } else {
                    0.0
                };
                Self {
                    // At λm = 0 the product is constant: any axis will do.
                    direction: if lm > 0.0 { u / lm } else { self.direction },
                    sharpness: lm,
                    amplitude: self.amplitude * other.amplitude * exponent.exp(),
                }
            }

            /// ∫ G1(v) G2(v) dv over the sphere (per channel).
            pub fn inner_product(&self, other: &Self) -> $v {
                self.product(other).integral()
            }

            /// The irradiance ∫ G(v) max(v·n, 0) dv the lobe delivers to a
            /// surface of unit normal `n`, by Stephen Hill's fitted curve
            /// (M. Pettineo, "SG Series Part 3", 2016): exact in the
            /// limits, and unlike the inner product with
            /// [`Self::clamped_cosine`] it falls to zero below the horizon
            /// for sharp lobes (that lobe is 0.12 at the horizon and 0.07
            /// at 100°, where a small light's irradiance is gone).
            pub fn irradiance(&self, n: $v) -> $v {
                let mu_n = self.direction.dot(n);
                let lambda = self.sharpness.max(1e-4 as $t);
                let c0 = 0.36 as $t;
                let c1 = 1.0 / (4.0 * c0);
                let eml = (-lambda).exp();
                let em2l = eml * eml;
                let rl = 1.0 / lambda;
                let scale = 1.0 + 2.0 * em2l - rl;
                let bias = (eml - em2l) * rl - em2l;
                let x = (1.0 - scale).max(0.0).sqrt();
                let x0 = c0 * mu_n;
                let x1 = c1 * x;
                let sum = x0 + x1;
                let y = if x0.abs() <= x1 {
                    sum * sum / x
                } else {
                    mu_n.clamp(0.0, 1.0)
                };
                let result = (scale * y + bias).max(0.0);
                self.amplitude * (result * 2.0 * std::$t::consts::PI / lambda)
            }

            /// The irradiance the lobe delivers to a surface of unit normal
            /// `n`, as the shading takes it: [`Self::irradiance`] (Hill's
            /// fit) for lobes of sharpness 2 and more, the inner product with
            /// [`Self::clamped_cosine`] below 1 (where the fit fails: 100 %
            /// off at λ 0.3), blended linearly between. Against quadrature
            /// the worst error over the angle to the normal, relative to the
            /// irradiance facing the lobe, is 1.6 % from λ 5 up (the cosine
            /// lobe alone: 6–16 %) and under 5 % at λ 1–2.
            pub fn diffuse_irradiance(&self, n: $v) -> $v {
                let w = (self.sharpness - 1.0).clamp(0.0, 1.0);
                let lobe = if w < 1.0 {
                    self.inner_product(&Self::clamped_cosine(n))
                } else {
                    $v::ZERO
                };
                let fit = if w > 0.0 {
                    self.irradiance(n)
                } else {
                    $v::ZERO
                };
                lobe * (1.0 - w) + fit * w
            }

            /// One lobe standing for the clamped cosine max(v·n, 0) around
            /// unit normal `n`, with the cosine's integral π.
            pub fn clamped_cosine(n: $v) -> Self {
                let l = COSINE_SHARPNESS as $t;
                Self {
                    direction: n,
                    sharpness: l,
                    amplitude: $v::splat(std::$t::consts::PI / Self::sphere_factor(l)),
                }
            }
        }
    };
}

sg_math!(Sg64, f64, DVec3);
sg_math!(Sg32, f32, Vec3);

impl Sg64 {
    /// The lobe convolved with a normalised lobe of sharpness `kernel`
    /// (a blur of angular variance ≈ 1/`kernel`), approximated as one SG:
    /// the variances add, so λ' = λκ/(λ + κ), and the amplitude is set so
    /// that the sphere integral — the lobe's energy — is kept exactly. A
    /// lobe far wider than the kernel is left almost as it is; a needle
    /// (λ ≫ κ) becomes a lobe of sharpness ≈ κ with the needle's energy.
    pub fn blurred(&self, kernel: f64) -> Sg64 {
        let sharpness = if self.sharpness <= 0.0 {
            0.0
        } else {
            self.sharpness * kernel / (self.sharpness + kernel)
        };
        Sg64 {
            direction: self.direction,
            sharpness,
            amplitude: self.amplitude * Self::sphere_factor(self.sharpness)
                / Self::sphere_factor(sharpness),
        }
    }

    /// The f32 lobe the GPU would hold.
    pub fn to_f32(&self) -> Sg32 {
        Sg32 {
            direction: self.direction.as_vec3(),
            sharpness: self.sharpness as f32,
            amplitude: self.amplitude.as_vec3(),
        }
    }
}

impl Sg32 {
    /// The same lobe in f64.
    pub fn to_f64(&self) -> Sg64 {
        Sg64 {
            direction: self.direction.as_dvec3(),
            sharpness: self.sharpness as f64,
            amplitude: self.amplitude.as_dvec3(),
        }
    }

    /// The lobe as the GPU stores it: (p, λ), (μ, 0).
    pub fn packed(&self) -> [f32; 8] {
        let (p, m) = (self.direction, self.amplitude);
        [p.x, p.y, p.z, self.sharpness, m.x, m.y, m.z, 0.0]
    }

    /// Reads a lobe stored by [`Self::packed`].
    pub fn unpack(v: &[f32]) -> Self {
        Self {
            direction: Vec3::new(v[0], v[1], v[2]),
            sharpness: v[3],
            amplitude: Vec3::new(v[4], v[5], v[6]),
        }
    }
}
