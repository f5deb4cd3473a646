// A plain gradient step: value −= gradient, kept non-negative, the gradient
// cleared (total variation's step after Adam's: its size is its weight, not
// Adam's normalised step). Mirrors passes/src/train/tv.rs tv_step.

struct DescendPush {
    count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

var<immediate> pc: DescendPush;
@group(0) @binding(0) var<storage, read_write> params: array<f32>;
@group(0) @binding(1) var<storage, read_write> grad: array<f32>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + 65535u * 64u * id.y;
    if i >= pc.count {
        return;
    }
    params[i] = max(params[i] - grad[i], 0.0);
    grad[i] = 0.0;
}
