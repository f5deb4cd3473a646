// The SSDF bake's second kernel (METHOD.md "SSDF field"): S(d; x) at every
// direction texel of an octahedral map for a batch of grid nodes,
// mirroring SilhouetteView::signed_angle in passes/src/ssdf/silhouette.rs.
// One workgroup per (node, 64 directions): the node's silhouette arcs
// (found once per node by ssdf_silhouette.wgsl) are read 64 at a time into
// shared memory, and every thread keeps the nearest of them to its
// direction (by squared chord): all arcs where its ray misses, outer arcs
// where it hits. S is that angle, negative where the ray hits.
// Needs: u32 define ARC_PIECES, bool OCTAHEDRAL.
#include "common/direction_map.wgsl"
#include "ssdf/angles.wgsl"
#include "ssdf/bake_common.wgsl"

// The arcs of ssdf_silhouette.wgsl and how many each node has.
@group(0) @binding(4) var<storage, read> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> arc_counts: array<u32>;
// S per (node of the batch, direction texel), row-major by node.
@group(0) @binding(6) var<storage, read_write> out_ssdf: array<f32>;

const GROUP: u32 = 64u;

var<workgroup> arc_a: array<vec3<f32>, 64>;
var<workgroup> arc_b: array<vec3<f32>, 64>;
var<workgroup> arc_n: array<vec3<f32>, 64>;
var<workgroup> arc_outer: array<bool, 64>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    let texels = pc.map_size * pc.map_size;
    let texel = wg.x * GROUP + lid.x;
    let x = points[pc.node_offset + node].xyz;
    let valid = texel < texels;
    var d = vec3<f32>(0.0, 1.0, 0.0);
    if valid {
        d = dm_direction(vec2<u32>(texel % pc.map_size, texel / pc.map_size), vec2<u32>(pc.map_size));
    }
    let hit = valid && bvh_occluded(x, d);
    var nearest = 4.0;
    let count = arc_counts[node];
    let first = node * bake_arc_capacity();
    for (var base = 0u; base < count; base += GROUP) {
        let i = base + lid.x;
        if i < count {
            let a = arcs[2u * (first + i)];
            let b = arcs[2u * (first + i) + 1u].xyz;
            arc_a[lid.x] = a.xyz;
            arc_b[lid.x] = b;
            arc_n[lid.x] = ssdf_arc_normal(a.xyz, b);
            arc_outer[lid.x] = a.w != 0.0;
        }
        workgroupBarrier();
        if valid {
            let n = min(GROUP, count - base);
            for (var j = 0u; j < n; j++) {
                if arc_outer[j] || !hit {
                    nearest = min(nearest, ssdf_chord2_to_arc(d, arc_a[j], arc_b[j], arc_n[j]));
                }
            }
        }
        workgroupBarrier();
    }
    if valid {
        let best = ssdf_angle_of_chord2(nearest);
        out_ssdf[node * texels + texel] = select(best, -best, hit);
    }
}
