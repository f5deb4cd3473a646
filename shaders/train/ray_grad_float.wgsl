// The training kernel where the device adds 32-bit floats atomically in
// storage buffers (VK_EXT_shader_atomic_float's shaderBufferFloat32AtomicAdd,
// which lavapipe and NVIDIA have): one atomicAdd per value instead of a
// compare-and-swap loop. The kernel itself: train/ray_grad_body.wgsl.

#include "train/ray_grad_body.wgsl"

@group(0) @binding(2) var<storage, read_write> grad: array<atomic<f32>>;
@group(0) @binding(5) var<storage, read_write> gain_grad: array<atomic<f32>>;

fn add_float(i: u32, value: f32) {
    if value != 0.0 {
        atomicAdd(&grad[i], value);
    }
}

fn add_gain_float(i: u32, value: f32) {
    if value != 0.0 {
        atomicAdd(&gain_grad[i], value);
    }
}

@group(0) @binding(24) var<storage, read_write> sky_grad: array<atomic<f32>>;

fn add_sky_float(i: u32, value: f32) {
    if value != 0.0 {
        atomicAdd(&sky_grad[i], value);
    }
}

// The gradient's pages (train/sh_pages.wgsl).
@group(0) @binding(15) var<storage, read_write> sh_grad_0: array<atomic<f32>>;
@group(0) @binding(16) var<storage, read_write> sh_grad_1: array<atomic<f32>>;
@group(0) @binding(17) var<storage, read_write> sh_grad_2: array<atomic<f32>>;
@group(0) @binding(18) var<storage, read_write> sh_grad_3: array<atomic<f32>>;
@group(0) @binding(19) var<storage, read_write> sh_grad_4: array<atomic<f32>>;
@group(0) @binding(20) var<storage, read_write> sh_grad_5: array<atomic<f32>>;
@group(0) @binding(21) var<storage, read_write> sh_grad_6: array<atomic<f32>>;
@group(0) @binding(22) var<storage, read_write> sh_grad_7: array<atomic<f32>>;

// Adds `value` to word i of the gradient's page j.
fn add_sh_float(j: u32, i: u32, value: f32) {
    if value == 0.0 {
        return;
    }
    switch j {
        case 0u: {
            atomicAdd(&sh_grad_0[i], value);
        }
        case 1u: {
            atomicAdd(&sh_grad_1[i], value);
        }
        case 2u: {
            atomicAdd(&sh_grad_2[i], value);
        }
        case 3u: {
            atomicAdd(&sh_grad_3[i], value);
        }
        case 4u: {
            atomicAdd(&sh_grad_4[i], value);
        }
        case 5u: {
            atomicAdd(&sh_grad_5[i], value);
        }
        case 6u: {
            atomicAdd(&sh_grad_6[i], value);
        }
        default: {
            atomicAdd(&sh_grad_7[i], value);
        }
    }
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    train_pixel(id.x);
}
