// The SG fit's model, mirroring passes/src/sgfit/model.rs: Fibonacci axes, cold-start sharpness, texel validity, the step.
// Needs: common/sg.wgsl and common/tangent_basis.wgsl.
#include "common/fibonacci.wgsl"

const FIT_PI: f32 = 3.14159265358979;
const FIT_LN_2: f32 = 0.693147180559945;
const FIT_MIN_SHARPNESS: f32 = 1e-4;
// FIT_MAX_SHARPNESS (f32) is defined by the pass: passes/src/sgfit/model.rs `max_sharpness`.
const FIT_MAX_AXIS_STEP: f32 = 1.0;
const FIT_SEED_CONTRAST: f32 = 4.0;

// Axis k of m Fibonacci-lattice points (+Y up).
fn fit_fibonacci_axis(k: u32, m: u32) -> vec3<f32> {
    return fibonacci_axis(k, m);
}

fn fit_initial_sharpness(m: u32) -> f32 {
    return 8.0 * FIT_LN_2 * f32(m) / (4.0 * FIT_PI);
}

fn fit_luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Finite (by the exponent bits, which no fast-math can assume away) and ≥ 0.
fn fit_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn fit_texel_valid(c: vec3<f32>) -> bool {
    return fit_finite(c.x) && fit_finite(c.y) && fit_finite(c.z) && all(c >= vec3<f32>(0.0));
}

// Lobe g moved by its six parameter steps d0 = (Δa_r, Δa_g, Δa_b, Δs),
// d1 = (Δu, Δv).
fn fit_apply_step(g: Sg, d0: vec4<f32>, d1: vec2<f32>) -> Sg {
    let a = sqrt(g.amplitude) + d0.xyz;
    let s = clamp(log(max(g.sharpness, FIT_MIN_SHARPNESS)) + d0.w, log(FIT_MIN_SHARPNESS), log(FIT_MAX_SHARPNESS));
    var uv = d1;
    let len = length(uv);
    if len > FIT_MAX_AXIS_STEP {
        uv *= FIT_MAX_AXIS_STEP / len;
    }
    let b = tangent_basis(g.direction);
    return Sg(normalize(g.direction + uv.x * b.t1 + uv.y * b.t2), exp(s), a * a);
}
