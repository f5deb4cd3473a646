// The kernels that step every trained value (train/adam.wgsl,
// train/descend.wgsl) take VALUES_PER_INVOCATION consecutive values an
// invocation (a u32 define, passes/src/train/gpu.rs VALUES_PER_INVOCATION:
// llvmpipe charges every invocation).

// The index of the `k`th value invocation `id` steps (dispatches past
// 65535 workgroups go on along y).
fn value_index(id: vec3<u32>, k: u32) -> u32 {
    return (id.x + 65535u * 64u * id.y) * VALUES_PER_INVOCATION + k;
}
