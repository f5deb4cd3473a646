// The SSDF bake's third kernel (METHOD.md "SSDF field"): one invocation
// per silhouette piece of a node (ssdf_pieces.wgsl). The piece is outer,
// on the outline, when a ray just outside its middle (by OUTSIDE_OFFSET,
// on the side away from the face that faces the node) misses
// (SilhouetteEdge::piece). One ray an invocation: every lane casts one,
// and no invocation's loops run long (llvmpipe's limit: bake_push.wgsl).
// Needs: u32 defines ARC_PIECES, PIECE_CAPACITY; f32 defines
// OUTSIDE_OFFSET, PIECE_ANGLE.
#include "ssdf/angles.wgsl"
#include "ssdf/bake_common.wgsl"
#include "ssdf/silhouette_edges.wgsl"
#include "ssdf/piece_list.wgsl"
// Per piece of the node's list: 1 outer, 0 not.
@group(0) @binding(13) var<storage, read_write> outer: array<u32>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    let slot = piece_slot(node, gid.x);
    if slot == 0xffffffffu {
        return;
    }
    let r = pieces[slot];
    let x = points[pc.node_offset + node].xyz;
    let v = edge_view(record_edge(r), x);
    let m = along(v, (f32(record_piece(r)) + 0.5) / f32(record_pieces(r)));
    let probe = normalize(m - v.normal * (v.side * OUTSIDE_OFFSET));
    outer[slot] = select(1u, 0u, bvh_occluded(x, probe));
}
