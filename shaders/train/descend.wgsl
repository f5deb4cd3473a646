// A plain gradient step: value −= gradient, a colour kept within 0 and
// `limit` (the radiance limit a field file holds; a density is free:
// density_at), the gradient cleared (total variation's
// step after Adam's: its size is its weight, not Adam's normalised step),
// several values an invocation (train/every_value.wgsl).
// Mirrors passes/src/train/tv.rs tv_step.

struct DescendPush {
    count: u32,
    limit: f32,
    pad1: u32,
    pad2: u32,
}

#include "train/every_value.wgsl"

var<immediate> pc: DescendPush;
@group(0) @binding(0) var<storage, read_write> params: array<f32>;
@group(0) @binding(1) var<storage, read_write> grad: array<f32>;

// The plain step of value `i`.
fn step_value(i: u32) {
    if i >= pc.count {
        return;
    }
    let v = params[i] - grad[i];
    // Colours kept within [0, limit]; a density is free (density_at).
    params[i] = select(clamp(v, 0.0, pc.limit), v, (i & 3u) == 3u);
    grad[i] = 0.0;
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    for (var k = 0u; k < VALUES_PER_INVOCATION; k++) {
        step_value(value_index(id, k));
    }
}
