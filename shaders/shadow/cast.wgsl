// The cast shadow (eq. 7-8) of one object whose light has no direct
// lobes: every lobe's visibility from the SSDF (shadow/cast_body.wgsl).
#include "shadow/cast_body.wgsl"

fn cast_direct_visibility(x: vec3<f32>, lobe: u32, rays: u32) -> f32 {
    return 1.0;
}

// No local lights here (pc.local_count is 0).
fn cast_local_lobe(x: vec3<f32>, l: u32) -> Sg {
    return Sg(vec3<f32>(0.0, 1.0, 0.0), 1.0, vec3<f32>(0.0));
}

fn cast_local_arrival(x: vec3<f32>, n: vec3<f32>, l: u32) -> vec2<f32> {
    return vec2<f32>(0.0);
}

fn cast_local_clear(x: vec3<f32>, n: vec3<f32>, l: u32) -> f32 {
    return 0.0;
}

@compute @workgroup_size(8, 8, 1)
fn main_classify(@builtin(global_invocation_id) id: vec3<u32>) {
    if !cast_outside(id) {
        cast_classify(id, vec3<f32>(1.0));
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_classify_chained(@builtin(global_invocation_id) id: vec3<u32>) {
    if !cast_outside(id) {
        cast_classify(id, cast_previous(id));
    }
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main_listed(@builtin(global_invocation_id) id: vec3<u32>) {
    refine_listed(id.x, false);
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main_listed_chained(@builtin(global_invocation_id) id: vec3<u32>) {
    refine_listed(id.x, true);
}
