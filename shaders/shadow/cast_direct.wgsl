// The cast shadow (eq. 7-8) of one object whose light ends in direct
// lobes (too sharp for the fit): those are occluded by the share of their
// rays the object's mesh blocks (shadow/direct_rays.wgsl), the others by
// the SSDF (shadow/cast_body.wgsl).
#include "shadow/cast_body.wgsl"

@group(0) @binding(12) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read> sharp_rays: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
#include "shadow/direct_rays.wgsl"

fn cast_direct_visibility(x: vec3<f32>, lobe: u32, rays: u32) -> f32 {
    return direct_clear_fraction(x, lobe, rays, vec3<f32>(0.0), false);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    cast_main(id);
}

@compute @workgroup_size(8, 8, 1)
fn main_chained(@builtin(global_invocation_id) id: vec3<u32>) {
    cast_main_chained(id);
}
