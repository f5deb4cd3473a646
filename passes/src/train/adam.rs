//! Adam over the trained values with a separate step size for density, each
//! node's colour kept non-negative, its density (clamped after
//! interpolation: [`crate::field::density_at`]) and the view-dependent
//! colour's coefficients free of sign (`shaders/train/adam.wgsl` mirrors
//! it). Every value but a density stays within the radiance limit a field
//! file holds ([`crate::scene::RADIANCE_LIMIT`], either sign for the
//! coefficients, the sky's and the gains' too): a step size too large
//! for the photographs can drive a colour up step after step (at
//! `--rate 1` a 32-node PLANTS field reached 4.8·10⁶), and a trainer that
//! ends on such a value would write a field no command loads.
//!
//! A colour's step is the larger of an absolute size and, above a level no
//! surface reaches, a fraction of the colour itself: an HDR field
//! spans radiance 10⁴ apart (a lamp of 140 in a room of 0.03), and at a
//! step sized by the mean radiance alone a lamp's nodes would need ten
//! thousand steps to reach its light. Below that level the steps stay
//! absolute: larger steps on ordinary surfaces cost them accuracy and
//! brighten them (measured in `docs/benchmarks.md`).

/// Adam's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamKnobs {
    /// Step size of the colours (absolute).
    pub rate: f64,
    /// Step size of the colours above `relative_floor` as a fraction of
    /// each: such a colour c steps by the larger of `rate` and this × c
    /// (0: by `rate` alone).
    pub relative_rate: f64,
    /// The colour above which steps grow with the colour.
    pub relative_floor: f64,
    /// Step size of the densities.
    pub density_rate: f64,
    /// First-moment decay.
    pub beta1: f64,
    /// Second-moment decay.
    pub beta2: f64,
}

/// Adam's ε (`ADAM_EPSILON` in the shader).
pub const ADAM_EPSILON: f64 = 1e-8;

/// One step (number `t`, from 1) over `params` (the first `base_values`
/// 4 per node: r, g, b, σ; the rest view-dependent colour coefficients)
/// with gradient `grad` × `grad_scale` (cleared), moments `moments` (first,
/// second per value).
pub fn adam_step(
    params: &mut [f32],
    grad: &mut [f32],
    moments: &mut [[f32; 2]],
    knobs: &AdamKnobs,
    (grad_scale, base_values): (f32, usize),
    t: u32,
) {
    let c1 = (1.0 - knobs.beta1.powi(t as i32)) as f32;
    let c2 = (1.0 - knobs.beta2.powi(t as i32)) as f32;
    let (b1, b2) = (knobs.beta1 as f32, knobs.beta2 as f32);
    let limit = crate::scene::RADIANCE_LIMIT as f32;
    for i in 0..params.len() {
        let g = grad[i] * grad_scale;
        grad[i] = 0.0;
        let m = &mut moments[i];
        m[0] = b1 * m[0] + (1.0 - b1) * g;
        m[1] = b2 * m[1] + (1.0 - b2) * g * g;
        let base = i < base_values;
        let rate = if base && i % 4 == 3 {
            knobs.density_rate as f32
        } else if base {
            let relative = if params[i] > knobs.relative_floor as f32 {
                knobs.relative_rate as f32 * params[i]
            } else {
                0.0
            };
            (knobs.rate as f32).max(relative)
        } else {
            knobs.rate as f32
        };
        let step = rate * (m[0] / c1) / ((m[1] / c2).sqrt() + ADAM_EPSILON as f32);
        params[i] = if base && i % 4 == 3 {
            params[i] - step
        } else {
            let floor = if base { 0.0 } else { -limit };
            (params[i] - step).clamp(floor, limit)
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RADIANCE_LIMIT;

    /// A colour and the coefficients driven past the radiance limit stop at
    /// it (either sign for a coefficient); a density steps on.
    #[test]
    fn no_value_but_a_density_steps_past_the_radiance_limit() {
        let near = 0.99 * RADIANCE_LIMIT as f32;
        // One node (r, g, b, σ), then three coefficients.
        let mut params = vec![near, 5.0, 0.0, near, near, -near, 1.0];
        // Each pushed outward: up, up, down (held at zero), up; up, down,
        // up (well inside).
        let mut grad = vec![-1.0, -1.0, 1.0, -1.0, -1.0, 1.0, -1.0];
        let mut moments = vec![[0.0f32; 2]; params.len()];
        let knobs = AdamKnobs {
            rate: 5e4,
            relative_rate: 0.5,
            relative_floor: 1.0,
            density_rate: 5e4,
            beta1: 0.9,
            beta2: 0.99,
        };
        adam_step(&mut params, &mut grad, &mut moments, &knobs, (1.0, 4), 1);
        let limit = RADIANCE_LIMIT as f32;
        assert_eq!(params[0], limit, "a colour stops at the limit");
        assert!((params[1] - 5e4 - 5.0).abs() < 1.0, "{}", params[1]);
        assert_eq!(params[2], 0.0, "a colour stays non-negative");
        assert!(params[3] > limit, "a density steps on: {}", params[3]);
        assert_eq!(params[4], limit);
        assert_eq!(params[5], -limit, "a coefficient stops at −limit");
        assert!((params[6] - 5e4 - 1.0).abs() < 1.0, "{}", params[6]);
    }
}
