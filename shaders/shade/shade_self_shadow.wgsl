// The object's SG shading pass (eq. 5) with self-shadows (eq. 9) from the
// SSDF for every lobe (shade/self_shadow_ssdf.wgsl).
#include "shade/shade_body.wgsl"
#include "shade/self_shadow_ssdf.wgsl"

fn shading_fitted_count() -> u32 {
    return shading_light_count();
}

fn shading_direct_lobe(k: u32, g: Sg) -> Sg {
    return g;
}

fn shading_direct_attenuation(k: u32) -> f32 {
    return 1.0;
}

fn shading_fitted_attenuation(k: u32) -> f32 {
    return ssdf_attenuation(k);
}

fn shading_diffuse_gain() -> vec3<f32> {
    return vec3<f32>(1.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(shade_dispatched_pixel(id));
}
