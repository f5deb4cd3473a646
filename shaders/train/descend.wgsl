// A plain gradient step: value −= gradient, a colour kept within 0 and
// `limit` (the radiance limit a field file holds; a density is free:
// density_at), the gradient cleared (total variation's
// step after Adam's: its size is its weight, not Adam's normalised step),
// several values an invocation (train/every_value.wgsl). With
// DENSITIES_ONLY (a bool define: total variation took no colour,
// train/tv.wgsl) value j is node j's density (4j + 3), the colours'
// gradient being zero and their values within the bounds already.
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

// The plain step of value `j` (node j's density with DENSITIES_ONLY).
fn step_value(j: u32) {
    if j >= pc.count {
        return;
    }
    let i = select(j, 4u * j + 3u, DENSITIES_ONLY);
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
