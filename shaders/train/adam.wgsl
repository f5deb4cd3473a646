// One Adam step over every trained value (4 per node: r, g, b, σ, then the
// view-dependent colour's coefficients), a node's four at once (one
// vec4 read and written a buffer: read value by value, this pass took a
// quarter more time on DOG's field at 128 nodes), VALUES_PER_INVOCATION / 4 nodes an
// invocation (train/every_value.wgsl), the gradient read and cleared.
// Each buffer holds 4 values a node (a coefficient's page: r, g, b, 0; the
// sky's texels, the gains), and is all base values (`base_values` =
// `count`: a node's w its density) or all coefficients (0). A node's
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
@group(0) @binding(0) var<storage, read_write> params: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> grad: array<vec4<f32>>;
// The first and second moments, one binding each (each the size of
// `params`: a sparse grid's values may fill a binding).
@group(0) @binding(2) var<storage, read_write> first: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> second: array<vec4<f32>>;

const ADAM_EPSILON: f32 = 1e-8;

// Adam's step of node `j`'s four values.
fn step_node(j: u32) {
    if 4u * j >= pc.count {
        return;
    }
    let g = grad[j] * pc.grad_scale;
    grad[j] = vec4<f32>(0.0);
    let m1 = pc.beta1 * first[j] + (1.0 - pc.beta1) * g;
    let m2 = pc.beta2 * second[j] + (1.0 - pc.beta2) * g * g;
    first[j] = m1;
    second[j] = m2;
    let p = params[j];
    let base = 4u * j < pc.base_values;
    let density = vec4<bool>(false, false, false, base);
    let lamp_like = select(vec4<f32>(0.0), vec4<f32>(1.0), p > vec4<f32>(pc.relative_floor));
    let colour_rate = select(vec4<f32>(pc.rate), max(vec4<f32>(pc.rate), pc.relative_rate * p * lamp_like), base);
    let rate = select(colour_rate, vec4<f32>(pc.density_rate), density);
    let step = rate * (m1 / pc.correction1) / (sqrt(m2 / pc.correction2) + ADAM_EPSILON);
    // A node's density is free (the clamp at zero is after interpolation:
    // density_at); its colour is kept non-negative; every other value
    // stays within the limit, either sign.
    let moved = p - step;
    let bounded = clamp(moved, vec4<f32>(select(-pc.limit, 0.0, base)), vec4<f32>(pc.limit));
    params[j] = select(bounded, moved, density);
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    for (var k = 0u; k < VALUES_PER_INVOCATION / 4u; k++) {
        step_node(value_index(id, 4u * k) / 4u);
    }
}
