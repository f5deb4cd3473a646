// The object's SG shading pass (eq. 5) with self-shadows (eq. 9) where the
// light ends in direct lobes (too sharp for the fit): those take Γ as the
// share of their rays above the tangent plane that leave the surface clear,
// cast against the object's mesh from DIRECT_RAY_OFFSET radii off it
// (shadow/direct_rays.wgsl); the others Γ from the SSDF. Mirrors
// passes/src/shadow/runtime.rs self_shadow_factors.
#include "shade/shade_body.wgsl"
#include "shade/self_shadow_ssdf.wgsl"

@group(0) @binding(10) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> sharp_rays: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
#include "shadow/direct_rays.wgsl"

fn shading_attenuation(k: u32) -> f32 {
    let first = pc.light_count - min(pc.direct_lobes, pc.light_count);
    if k < first {
        return ssdf_attenuation(k);
    }
    let lifted = shade_point + shade_normal * (DIRECT_RAY_OFFSET * ssdf_world_sphere().w);
    return direct_clear_fraction(lifted, k - first, pc.direct_rays, shade_normal, true);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id);
}
