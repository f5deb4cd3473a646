// The near-field light at surface points (METHOD.md "Environment light
// estimation"), computed once before the fit. Each point holds its
// position, how far above the surface its rays start marching, and its
// unit normal; nf_ray_start mirrors ray_start in near_field.rs.
// `irradiance`: workgroup (c, p) marches rays [c·NF_RAYS_PER_GROUP,
// (c + 1)·NF_RAYS_PER_GROUP) of point p's `rays` cosine-distributed rays
// (hemisphere.wgsl) through the field and writes their sums Σ Ĉ in rgb and
// Σ Ô in alpha; the caller adds the chunks of a point and scales by π/N
// (E_nerf) and 1/N (mean Ô). An invocation marches at most
// NF_RAYS_PER_INVOCATION rays: llvmpipe ends every loop of an invocation
// once 65535 iterations of all its loops together have run, so one
// invocation marching thousands of rays returns garbage on lavapipe.
// `opacity_map`: one invocation per point and texel of an octahedral
// map, writing Ô along the texel's centre direction (the cache the
// environment term reads). Mirrors passes/src/envest/near_field_reference.rs.
// NF_RAYS_PER_INVOCATION (u32) is defined by the pass: passes/src/envest/near_field.rs.
#include "common/ray_box.wgsl"
#include "common/direction_map.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"
#include "common/tangent_basis.wgsl"
#include "envest/hemisphere.wgsl"
#include "common/group_sum.wgsl"

struct NearFieldPush {
    step: f32,
    termination: f32,
    rays: u32,
    first_point: u32,
    count: u32,
    map_side: u32,
    seed: u32,
    pad: u32,
}

var<immediate> pc: NearFieldPush;

// Two vec4 per point: (position, rise), (normal, 0).
@group(0) @binding(3) var<storage, read> points: array<vec4<f32>>;
// One vec4 per point of the batch and chunk of rays, chunk-minor:
// (Σ Ĉ, Σ Ô) over the chunk's rays.
@group(0) @binding(4) var<storage, read_write> irradiance_out: array<vec4<f32>>;
// map_side² opacities per point of the batch.
@group(0) @binding(5) var<storage, read_write> opacity_out: array<f32>;

const NF_GROUP: u32 = 64u;
const NF_RAYS_PER_GROUP: u32 = NF_GROUP * NF_RAYS_PER_INVOCATION;
const NF_NO_OBJECT: f32 = 3.0e38;
// near_field.rs MIN_RISE_COSINE.
const NF_MIN_RISE_COSINE: f32 = 0.25;

// Where the ray from the point along d starts marching: `rise` above the
// surface along the ray itself.
fn nf_ray_start(position: vec3<f32>, normal: vec3<f32>, rise: f32, d: vec3<f32>) -> vec3<f32> {
    return position + d * (rise / max(dot(d, normal), NF_MIN_RISE_COSINE));
}

@compute @workgroup_size(64, 1, 1)
fn irradiance(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let chunk = group.x;
    let local_point = group.y;
    let point = pc.first_point + local_point;
    let position = points[2u * point];
    let normal = points[2u * point + 1u].xyz;
    let end = min(pc.rays, (chunk + 1u) * NF_RAYS_PER_GROUP);
    var sum = vec4<f32>(0.0);
    for (var i = chunk * NF_RAYS_PER_GROUP + lid; i < end; i += NF_GROUP) {
        let d = hs_ray_direction(normal, point, pc.seed, i, pc.rays);
        let origin = nf_ray_start(position.xyz, normal, position.w, d);
        let m = march_ray(origin, d, NF_NO_OBJECT, pc.step, pc.termination);
        sum += vec4<f32>(m.colour, m.opacity);
    }
    let total = group_sum(lid, sum);
    if lid == 0u {
        let chunks = (pc.rays + NF_RAYS_PER_GROUP - 1u) / NF_RAYS_PER_GROUP;
        irradiance_out[local_point * chunks + chunk] = total;
    }
}

@compute @workgroup_size(64, 1, 1)
fn opacity_map(@builtin(global_invocation_id) id: vec3<u32>) {
    let texels = pc.map_side * pc.map_side;
    if id.x >= texels || id.y >= pc.count {
        return;
    }
    let point = pc.first_point + id.y;
    let position = points[2u * point];
    let normal = points[2u * point + 1u].xyz;
    let t = vec2<u32>(id.x % pc.map_side, id.x / pc.map_side);
    let d = dm_direction(t, vec2<u32>(pc.map_side, pc.map_side));
    let origin = nf_ray_start(position.xyz, normal, position.w, d);
    let m = march_ray(origin, d, NF_NO_OBJECT, pc.step, pc.termination);
    opacity_out[id.y * texels + id.x] = m.opacity;
}
