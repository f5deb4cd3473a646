// Check kernel for common/sg.wgsl: for each case (lobes a, b and a
// direction v), writes eval(a, v), product(a, b), integral(a),
// inner_product(a, b) and the clamped-cosine lobe around v evaluated at
// a's axis, for comparison with Sg32/Sg64 on the CPU.
#include "common/sg.wgsl"

struct Case {
    a0: vec4<f32>,
    a1: vec4<f32>,
    b0: vec4<f32>,
    b1: vec4<f32>,
    v: vec4<f32>,
}

struct Result {
    eval: vec4<f32>,
    product0: vec4<f32>,
    product1: vec4<f32>,
    integral: vec4<f32>,
    inner: vec4<f32>,
    cosine: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> results: array<Result>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&cases) {
        return;
    }
    let c = cases[i];
    let a = sg_unpack(c.a0, c.a1);
    let b = sg_unpack(c.b0, c.b1);
    let p = sg_product(a, b);
    let cosine = sg_clamped_cosine(c.v.xyz);
    results[i] = Result(
        vec4<f32>(sg_eval(a, c.v.xyz), 0.0),
        vec4<f32>(p.direction, p.sharpness),
        vec4<f32>(p.amplitude, 0.0),
        vec4<f32>(sg_integral(a), 0.0),
        vec4<f32>(sg_inner_product(a, b), 0.0),
        vec4<f32>(sg_eval(cosine, a.direction), cosine.amplitude.x),
    );
}
