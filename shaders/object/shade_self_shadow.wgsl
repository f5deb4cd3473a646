// The object's SG shading pass (eq. 5) with self-shadows (eq. 9):
// Γ_k = q(S(p_k; x), λ_k), the visible fraction of light lobe k behind the
// half-space at the SSDF's angle, x the pixel's surface point. Mirrors
// passes/src/shadow/runtime.rs self_shadow_factors.
// Needs: the shadow defines (passes/src/shadow/gpu.rs).
#include "object/shade_body.wgsl"

@group(0) @binding(6) var<storage, read> fh_table: array<f32>;
@group(0) @binding(7) var<storage, read> ssdf: SsdfObject;
@group(0) @binding(8) var<storage, read> ssdf_rows: array<f32>;
@group(0) @binding(9) var<storage, read> ssdf_coefs: array<f32>;

#include "shadow/fh.wgsl"
#include "shadow/ssdf.wgsl"

fn shading_attenuation(k: u32) -> f32 {
    let g = shading_light(k);
    return fh_fraction(ssdf_value(ssdf_to_object_dir(g.direction)), g.sharpness);
}

fn shading_prepare(x: vec3<f32>) {
    ssdf_prepare(ssdf_to_object_point(x));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id);
}
