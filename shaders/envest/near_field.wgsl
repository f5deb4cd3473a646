// The near-field light at surface points (METHOD.md "Environment light
// estimation"), computed once before the fit. Each point holds its ray
// origin (the surface point lifted along the normal) and its unit normal.
// `irradiance`: one workgroup per point marches `rays` cosine-distributed
// rays (hemisphere.wgsl) through the field and writes
// E_nerf = π/N · Σ Ĉ in rgb and the rays' mean Ô in alpha.
// `opacity_map`: one invocation per point and texel of an octahedral
// map, writing Ô along the texel's centre direction (the cache the
// environment term reads). Mirrors passes/src/envest/near_field_reference.rs.
#include "common/ray_box.wgsl"
#include "common/direction_map.wgsl"
#include "field/grid.wgsl"
#include "nerf/volume_march.wgsl"
#include "common/tangent_basis.wgsl"
#include "envest/hemisphere.wgsl"

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

// Two vec4 per point: (origin, 0), (normal, 0).
@group(0) @binding(3) var<storage, read> points: array<vec4<f32>>;
// One vec4 per point of the batch: (E_nerf, mean Ô).
@group(0) @binding(4) var<storage, read_write> irradiance_out: array<vec4<f32>>;
// map_side² opacities per point of the batch.
@group(0) @binding(5) var<storage, read_write> opacity_out: array<f32>;

const NF_GROUP: u32 = 64u;
const NF_NO_OBJECT: f32 = 3.0e38;

var<workgroup> nf_sums: array<vec4<f32>, NF_GROUP>;

@compute @workgroup_size(64, 1, 1)
fn irradiance(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let local_point = group.x;
    let point = pc.first_point + local_point;
    let origin = points[2u * point].xyz;
    let normal = points[2u * point + 1u].xyz;
    var sum = vec4<f32>(0.0);
    for (var i = lid; i < pc.rays; i += NF_GROUP) {
        let d = hs_ray_direction(normal, point, pc.seed, i, pc.rays);
        let m = march_ray(origin, d, NF_NO_OBJECT, pc.step, pc.termination);
        sum += vec4<f32>(m.colour, m.opacity);
    }
    nf_sums[lid] = sum;
    workgroupBarrier();
    for (var stride = NF_GROUP / 2u; stride > 0u; stride = stride / 2u) {
        if lid < stride {
            nf_sums[lid] += nf_sums[lid + stride];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        let mean = nf_sums[0] / f32(pc.rays);
        irradiance_out[local_point] = vec4<f32>(HS_PI * mean.rgb, mean.a);
    }
}

@compute @workgroup_size(64, 1, 1)
fn opacity_map(@builtin(global_invocation_id) id: vec3<u32>) {
    let texels = pc.map_side * pc.map_side;
    if id.x >= texels || id.y >= pc.count {
        return;
    }
    let point = pc.first_point + id.y;
    let origin = points[2u * point].xyz;
    let t = vec2<u32>(id.x % pc.map_side, id.x / pc.map_side);
    let d = dm_direction(t, vec2<u32>(pc.map_side, pc.map_side));
    let m = march_ray(origin, d, NF_NO_OBJECT, pc.step, pc.termination);
    opacity_out[id.y * texels + id.x] = m.opacity;
}
