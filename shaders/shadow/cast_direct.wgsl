// The cast shadow (eq. 7-8) of one object whose light ends in direct
// lobes (too sharp for the fit, and the local lights last): those are
// occluded by the share of their rays the object's mesh blocks
// (shadow/direct_rays.wgsl; a local light's rays go from the shaded point
// to points of its sphere, lighting/local_light.wgsl), the others by the
// SSDF (shadow/cast_body.wgsl).
#include "shadow/cast_body.wgsl"

@group(0) @binding(12) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read> sharp_rays: array<vec4<f32>>;
// Each local light as (centre, radius), (intensity, disk radius).
@group(0) @binding(16) var<storage, read> local_lights: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
#include "shadow/direct_rays.wgsl"
#include "lighting/local_light_disk.wgsl"
#include "shadow/local_rays.wgsl"

fn cast_direct_visibility(x: vec3<f32>, lobe: u32, rays: u32) -> f32 {
    let first_local = pc.direct_lobes - min(pc.local_count, pc.direct_lobes);
    if lobe < first_local {
        return direct_clear_fraction(x, lobe, rays, vec3<f32>(0.0), false);
    }
    let l = lobe - first_local;
    return local_clear_fraction(x, local_lights[2u * l], local_lights[2u * l + 1u], pc.local_side);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    cast_main(id);
}

@compute @workgroup_size(8, 8, 1)
fn main_chained(@builtin(global_invocation_id) id: vec3<u32>) {
    cast_main_chained(id);
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main_refine(@builtin(global_invocation_id) id: vec3<u32>) {
    refine_listed(id.x, false);
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main_refine_chained(@builtin(global_invocation_id) id: vec3<u32>) {
    refine_listed(id.x, true);
}
