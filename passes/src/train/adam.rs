//! Adam over the trained values with a separate step size for density, each
//! node's values kept non-negative, the view-dependent colour's
//! coefficients free (`shaders/train/adam.wgsl` mirrors it).

/// Adam's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamKnobs {
    /// Step size of the colours.
    pub rate: f64,
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
    for i in 0..params.len() {
        let g = grad[i] * grad_scale;
        grad[i] = 0.0;
        let m = &mut moments[i];
        m[0] = b1 * m[0] + (1.0 - b1) * g;
        m[1] = b2 * m[1] + (1.0 - b2) * g * g;
        let base = i < base_values;
        let rate = if base && i % 4 == 3 {
            knobs.density_rate
        } else {
            knobs.rate
        } as f32;
        let step = rate * (m[0] / c1) / ((m[1] / c2).sqrt() + ADAM_EPSILON as f32);
        params[i] = if base {
            (params[i] - step).max(0.0)
        } else {
            params[i] - step
        };
    }
}
