// The SSDF bake's second kernel (METHOD.md "SSDF field"): S(d; x) at every
// direction texel of an octahedral map for a batch of grid nodes,
// mirroring SilhouetteView::signed_angle in passes/src/ssdf/silhouette.rs.
// One workgroup per (node, 64 directions): every invocation reads the
// node's silhouette arcs (found once per node by ssdf_silhouette.wgsl; the
// same arc for every invocation at once) and keeps the nearest to its
// direction (by squared chord): all arcs where its ray misses, outer arcs
// where it hits. S is that angle, negative where the ray hits. (Staging
// the arcs through workgroup memory, 64 at a time between barriers, was
// 30 % slower on lavapipe.)
// Needs: u32 define ARC_PIECES, bool OCTAHEDRAL.
#include "common/direction_map.wgsl"
#include "ssdf/angles.wgsl"
#include "ssdf/bake_common.wgsl"

// The arcs of ssdf_silhouette.wgsl and how many each node has.
@group(0) @binding(4) var<storage, read> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> arc_counts: array<u32>;
// S per (node of the batch, direction texel), row-major by node.
@group(0) @binding(6) var<storage, read_write> out_ssdf: array<f32>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    let texels = pc.map_size * pc.map_size;
    let texel = wg.x * 64u + lid.x;
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
    if valid {
        for (var i = 0u; i < count; i++) {
            let a = arcs[2u * (first + i)];
            if a.w != 0.0 || !hit {
                let b = arcs[2u * (first + i) + 1u].xyz;
                nearest = min(nearest, ssdf_chord2_to_arc(d, a.xyz, b, ssdf_arc_normal(a.xyz, b)));
            }
        }
        let best = ssdf_angle_of_chord2(nearest);
        out_ssdf[node * texels + texel] = select(best, -best, hit);
    }
}
