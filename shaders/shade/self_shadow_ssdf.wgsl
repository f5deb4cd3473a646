// Self-shadows (eq. 9) from the SSDF, for the self-shadowed shading
// passes (shade/shade_self_shadow.wgsl, shade/shade_self_shadow_direct.wgsl):
// Γ_k = clamp(q(S(p'; x), λ') / q(asin(n·p'), λ'), 0, 1) for the lobe's
// cosine-weighted light L_k ⊗ cosine = (p', λ'): the visible fraction behind
// the half-space at the SSDF's angle relative to the tangent plane's own,
// x the pixel's surface point, n its normal. Mirrors
// passes/src/shadow/runtime.rs self_shadow_factors (which says why).
// Needs: shade/shade_body.wgsl before it; the shadow defines
// (passes/src/shadow/gpu.rs).

@group(0) @binding(6) var<storage, read> fh_table: array<f32>;
@group(0) @binding(7) var<storage, read> ssdf: SsdfObject;
@group(0) @binding(8) var<storage, read> ssdf_rows: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> ssdf_coefs: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> objects: array<ObjectRecord>;

#include "shadow/fh.wgsl"
#include "ssdf/ssdf.wgsl"

const SELF_SHADOW_HORIZON_FLOOR: f32 = 1e-6;

var<private> shade_normal: vec3<f32>;
var<private> shade_point: vec3<f32>;

// Γ_k from the SSDF.
fn ssdf_attenuation(k: u32) -> f32 {
    let p = sg_product(shading_light(k), sg_clamped_cosine(shade_normal));
    let elevation = asin(clamp(dot(shade_normal, p.direction), -1.0, 1.0));
    let horizon = fh_fraction(elevation, p.sharpness);
    if horizon < SELF_SHADOW_HORIZON_FLOOR {
        return 1.0;
    }
    let q = fh_fraction(ssdf_value(ssdf_to_object_dir(p.direction)), p.sharpness);
    return clamp(q / horizon, 0.0, 1.0);
}

fn shading_prepare(x: vec3<f32>, n: vec3<f32>) {
    shade_normal = n;
    shade_point = x;
    ssdf_prepare(ssdf_to_object_point(x));
}
