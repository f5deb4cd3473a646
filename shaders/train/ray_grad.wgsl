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

@group(0) @binding(24) var<storage, read_write> sky_grad: array<atomic<u32>>;

// add_float into sky_grad.
fn add_sky_float(i: u32, value: f32) {
    if value == 0.0 {
        return;
    }
    var old = atomicLoad(&sky_grad[i]);
    loop {
        let r = atomicCompareExchangeWeak(&sky_grad[i], old, bitcast<u32>(bitcast<f32>(old) + value));
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
}

// The gradient's pages (train/sh_pages.wgsl).
@group(0) @binding(15) var<storage, read_write> sh_grad_0: array<atomic<u32>>;
@group(0) @binding(16) var<storage, read_write> sh_grad_1: array<atomic<u32>>;
@group(0) @binding(17) var<storage, read_write> sh_grad_2: array<atomic<u32>>;
@group(0) @binding(18) var<storage, read_write> sh_grad_3: array<atomic<u32>>;
@group(0) @binding(19) var<storage, read_write> sh_grad_4: array<atomic<u32>>;
@group(0) @binding(20) var<storage, read_write> sh_grad_5: array<atomic<u32>>;
@group(0) @binding(21) var<storage, read_write> sh_grad_6: array<atomic<u32>>;
@group(0) @binding(22) var<storage, read_write> sh_grad_7: array<atomic<u32>>;

// One compare-and-swap of word i of the gradient's page j: (1, _) when it
// took, else (0, the word found there).
fn sh_grad_swap(j: u32, i: u32, old: u32, swapped: u32) -> vec2<u32> {
    switch j {
        case 0u: {
            let r = atomicCompareExchangeWeak(&sh_grad_0[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 1u: {
            let r = atomicCompareExchangeWeak(&sh_grad_1[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 2u: {
            let r = atomicCompareExchangeWeak(&sh_grad_2[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 3u: {
            let r = atomicCompareExchangeWeak(&sh_grad_3[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 4u: {
            let r = atomicCompareExchangeWeak(&sh_grad_4[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 5u: {
            let r = atomicCompareExchangeWeak(&sh_grad_5[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        case 6u: {
            let r = atomicCompareExchangeWeak(&sh_grad_6[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
        default: {
            let r = atomicCompareExchangeWeak(&sh_grad_7[i], old, swapped);
            return vec2<u32>(u32(r.exchanged), r.old_value);
        }
    }
}

// add_float into word i of the gradient's page j (the first swap guesses
// the word is zero, and learns it otherwise).
fn add_sh_float(j: u32, i: u32, value: f32) {
    if value == 0.0 {
        return;
    }
    var old = 0u;
    loop {
        let r = sh_grad_swap(j, i, old, bitcast<u32>(bitcast<f32>(old) + value));
        if r.x == 1u {
            break;
        }
        old = r.y;
    }
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    train_pixel(id.x);
}
