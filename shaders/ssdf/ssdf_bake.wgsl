// The SSDF bake's last kernel (METHOD.md "SSDF field"): S(d; x) at every
// direction texel of an octahedral map for a batch of grid nodes,
// mirroring SilhouetteView::signed_angle in passes/src/ssdf/silhouette.rs.
// One workgroup per (node, 64 · DIRECTIONS_PER_INVOCATION directions):
// every invocation reads the node's outline arcs (found once per node by
// ssdf_arcs.wgsl and prepared by ssdf_prepare_arc, so that each costs a
// few dot products; the same arc for every invocation at once) and keeps
// the nearest to each of its directions (by squared chord). S is that
// angle, negative where the ray along the direction hits. (Staging the
// arcs through workgroup memory, 64 at a time between barriers, was 30 %
// slower on lavapipe.)
// Needs: u32 defines ARC_CAPACITY, DIRECTIONS_PER_INVOCATION (8), bool
// OCTAHEDRAL.
#include "common/direction_map.wgsl"
#include "ssdf/angles.wgsl"
#include "ssdf/bake_common.wgsl"

// The outline's arcs of ssdf_arcs.wgsl and how many each node has.
@group(0) @binding(4) var<storage, read> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> arc_counts: array<u32>;
// S per (node of the batch, direction texel), row-major by node.
@group(0) @binding(6) var<storage, read_write> out_ssdf: array<f32>;

// Each invocation measures DIRECTIONS_PER_INVOCATION (8) directions, as
// two groups of four in vec4s (ssdf_arc_chord2_4): each arc read serves
// them all (the loop is bound by the arcs' reads, every lane reading the
// same arc), and no loop runs inside the loop over the arcs (llvmpipe
// counts every iteration of every loop against its limit: bake_push.wgsl).
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    let texels = pc.map_size * pc.map_size;
    let x = points[pc.node_offset + node].xyz;
    let base = (wg.x * 64u + lid.x) * DIRECTIONS_PER_INVOCATION;
    var d: array<vec3<f32>, DIRECTIONS_PER_INVOCATION>;
    for (var j = 0u; j < DIRECTIONS_PER_INVOCATION; j++) {
        let t = min(base + j, texels - 1u);
        d[j] = dm_direction(vec2<u32>(t % pc.map_size, t / pc.map_size), vec2<u32>(pc.map_size));
    }
    let lo_x = vec4<f32>(d[0].x, d[1].x, d[2].x, d[3].x);
    let lo_y = vec4<f32>(d[0].y, d[1].y, d[2].y, d[3].y);
    let lo_z = vec4<f32>(d[0].z, d[1].z, d[2].z, d[3].z);
    let hi_x = vec4<f32>(d[4].x, d[5].x, d[6].x, d[7].x);
    let hi_y = vec4<f32>(d[4].y, d[5].y, d[6].y, d[7].y);
    let hi_z = vec4<f32>(d[4].z, d[5].z, d[6].z, d[7].z);
    var lo = SsdfChords4(vec4<f32>(4.0), vec4<f32>(2.0));
    var hi = lo;
    let count = min(arc_counts[node], ARC_CAPACITY);
    let first = 4u * node * ARC_CAPACITY;
    for (var i = first; i < first + 4u * count; i += 4u) {
        let p0 = arcs[i];
        let p1 = arcs[i + 1u];
        let p2 = arcs[i + 2u];
        let p3 = arcs[i + 3u];
        let l = ssdf_arc_chord2_4(lo_x, lo_y, lo_z, p0, p1, p2, p3);
        let h = ssdf_arc_chord2_4(hi_x, hi_y, hi_z, p0, p1, p2, p3);
        lo = SsdfChords4(min(lo.ends, l.ends), min(lo.sines, l.sines));
        hi = SsdfChords4(min(hi.ends, h.ends), min(hi.sines, h.sines));
    }
    for (var j = 0u; j < DIRECTIONS_PER_INVOCATION; j++) {
        if base + j < texels {
            let k = j % 4u;
            let m = select(vec2<f32>(hi.ends[k], hi.sines[k]), vec2<f32>(lo.ends[k], lo.sines[k]), j < 4u);
            let best = ssdf_angle_of_chord2(ssdf_chord2_of(m));
            let hit = bvh_occluded(x, d[j]);
            out_ssdf[node * texels + base + j] = select(best, -best, hit);
        }
    }
}
