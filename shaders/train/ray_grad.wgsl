// The training kernel on every device: the gradient scattered with atomic
// float adds made of a compare-and-swap loop on the bits (core WGSL).
// The kernel itself: train/ray_grad_body.wgsl.

#include "train/ray_grad_body.wgsl"

@group(0) @binding(2) var<storage, read_write> grad: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> gain_grad: array<atomic<u32>>;

fn add_float(i: u32, value: f32) {
    if value == 0.0 {
        return;
    }
    var old = atomicLoad(&grad[i]);
    loop {
        let r = atomicCompareExchangeWeak(&grad[i], old, bitcast<u32>(bitcast<f32>(old) + value));
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
}

// add_float into gain_grad (a second array: WGSL takes no pointer to a
// storage array as an argument).
fn add_gain_float(i: u32, value: f32) {
    if value == 0.0 {
        return;
    }
    var old = atomicLoad(&gain_grad[i]);
    loop {
        let r = atomicCompareExchangeWeak(&gain_grad[i], old, bitcast<u32>(bitcast<f32>(old) + value));
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    train_ray(id.x);
}
