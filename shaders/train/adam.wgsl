// One Adam step over every trained value (4 per node: r, g, b, σ, then the
// view-dependent colour's coefficients), several an invocation
// (train/every_value.wgsl), the gradient read and cleared. A node's
// colour is kept within 0 and `limit` (the radiance limit a field file
// holds), the coefficients within ±`limit`, its density free (clamped
// after interpolation: density_at). A node's colour steps by the larger
// of `rate` and `relative_rate` × its value once above `relative_floor`
// (an HDR field's lamp is 10^4 × its walls).
// Mirrors passes/src/train/adam.rs adam_step.

struct AdamPush {
    count: u32,
    rate: f32,
    density_rate: f32,
    grad_scale: f32,
    beta1: f32,
    beta2: f32,
    correction1: f32,
    correction2: f32,
    base_values: u32,
    relative_rate: f32,
    relative_floor: f32,
    limit: f32,
}

#include "train/every_value.wgsl"

var<immediate> pc: AdamPush;
@group(0) @binding(0) var<storage, read_write> params: array<f32>;
@group(0) @binding(1) var<storage, read_write> grad: array<f32>;
// The first and second moments, one binding each (each the size of
// `params`: a sparse grid's values may fill a binding).
@group(0) @binding(2) var<storage, read_write> first: array<f32>;
@group(0) @binding(3) var<storage, read_write> second: array<f32>;

const ADAM_EPSILON: f32 = 1e-8;

// Adam's step of value `i`.
fn step_value(i: u32) {
    if i >= pc.count {
        return;
    }
    let g = grad[i] * pc.grad_scale;
    grad[i] = 0.0;
    var m = vec2<f32>(first[i], second[i]);
    m.x = pc.beta1 * m.x + (1.0 - pc.beta1) * g;
    m.y = pc.beta2 * m.y + (1.0 - pc.beta2) * g * g;
    first[i] = m.x;
    second[i] = m.y;
    let base = i < pc.base_values;
    let lamp_like = f32(params[i] > pc.relative_floor);
    let colour_rate = select(pc.rate, max(pc.rate, pc.relative_rate * params[i] * lamp_like), base);
    let rate = select(colour_rate, pc.density_rate, base && (i & 3u) == 3u);
    let step = rate * (m.x / pc.correction1) / (sqrt(m.y / pc.correction2) + ADAM_EPSILON);
    // A node's density is free (the clamp at zero is after interpolation:
    // density_at); its colour is kept non-negative; every other value
    // stays within the limit, either sign.
    let density = base && (i & 3u) == 3u;
    let moved = params[i] - step;
    let bounded = clamp(moved, select(-pc.limit, 0.0, base), pc.limit);
    params[i] = select(bounded, moved, density);
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    for (var k = 0u; k < VALUES_PER_INVOCATION; k++) {
        step_value(value_index(id, k));
    }
}
