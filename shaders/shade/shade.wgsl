// The object's SG shading pass (eq. 5) without self-shadows (Γ_k = 1).
#include "shade/shade_body.wgsl"

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
    return 1.0;
}

fn shading_prepare(x: vec3<f32>, n: vec3<f32>) {}

fn shading_diffuse_gain() -> vec3<f32> {
    return vec3<f32>(1.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(shade_dispatched_pixel(id));
}

// Zero over the tiles the objects can cover (from pc.tile_origin): the
// pass's first dispatch, before each object's over the tiles it can
// cover.
@compute @workgroup_size(8, 8, 1)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = shade_dispatched_pixel(id);
    if camera_outside(pc.camera, p.xy) {
        return;
    }
    textureStore(out_object, vec2<i32>(p.xy), vec4<f32>(0.0));
}
