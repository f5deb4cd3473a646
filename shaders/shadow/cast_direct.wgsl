// The cast shadow (eq. 7-8) of one object whose light ends in direct
// lobes (too sharp for the fit, and the local lights last): those are
// occluded by the share of their rays the object's mesh blocks
// (shadow/direct_rays.wgsl; a local light is weighed by its own light at
// the shaded point, through the field, and its rays go from there to
// points of its sphere, shadow/local_rays.wgsl), the others by the SSDF
// (shadow/cast_body.wgsl).
#include "shadow/cast_body.wgsl"

@group(0) @binding(12) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read> sharp_rays: array<vec4<f32>>;
// Each local light as (centre, radius), (intensity, disk radius).
@group(0) @binding(16) var<storage, read> local_lights: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
#include "shadow/direct_rays.wgsl"
#include "lighting/local_light.wgsl"
#include "shadow/local_rays.wgsl"

fn cast_direct_visibility(x: vec3<f32>, lobe: u32, rays: u32) -> f32 {
    return direct_clear_fraction(x, lobe, rays, vec3<f32>(0.0), false);
}

// Local light l as its sphere shows x (direct.rs local_lobe): black while
// inactive (its disk's radius 0).
fn cast_local_lobe(x: vec3<f32>, l: u32) -> Sg {
    let sphere = local_lights[2u * l];
    let emission = local_lights[2u * l + 1u];
    let to = sphere.xyz - x;
    if emission.w <= 0.0 || length(to) <= 0.0 {
        return Sg(vec3<f32>(0.0, 1.0, 0.0), 1.0, vec3<f32>(0.0));
    }
    return local_sphere_lobe(normalize(to), length(to), emission.w, emission.xyz);
}

// Local light l's (transmittance, share of its rays from above the plane)
// at x (shadow/local_rays.wgsl), the transmittance from two normal steps
// off the surface.
fn cast_local_arrival(x: vec3<f32>, n: vec3<f32>, l: u32) -> vec2<f32> {
    return local_cast_arrival(x, n, local_lights[2u * l], local_lights[2u * l + 1u], pc.local_side, 2.0 * pc.normal_step, pc.march_step, pc.march_termination);
}

// The share of local light l's rays from x above the plane that pass the
// mesh.
fn cast_local_clear(x: vec3<f32>, n: vec3<f32>, l: u32) -> f32 {
    return local_cast_clear(x, n, local_lights[2u * l], local_lights[2u * l + 1u], pc.local_side);
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
