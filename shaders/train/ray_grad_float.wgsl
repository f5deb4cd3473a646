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

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    train_ray(id.x);
}
