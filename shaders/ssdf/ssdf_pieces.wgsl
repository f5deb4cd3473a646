// The SSDF bake's second kernel (METHOD.md "SSDF field"; with
// ssdf_outer.wgsl and ssdf_arcs.wgsl it mirrors SilhouetteMesh::view_from
// in passes/src/ssdf/silhouette.rs): one invocation per (candidate edge,
// node of the batch). An edge on the silhouette seen from the node is cut
// into its pieces, which are appended, consecutively, to the node's piece
// list. Dispatched indirectly over the candidates (ssdf_candidates.wgsl).
// Needs: u32 defines ARC_PIECES, PIECE_CAPACITY; f32 define PIECE_ANGLE.
#include "ssdf/angles.wgsl"
#include "ssdf/bake_push.wgsl"
#include "ssdf/silhouette_edges.wgsl"

@group(0) @binding(7) var<storage, read> candidates: array<u32>;
@group(0) @binding(8) var<storage, read> candidate_count: array<u32>;
// Per node: its pieces (piece_record) and how many.
@group(0) @binding(10) var<storage, read_write> pieces: array<u32>;
@group(0) @binding(11) var<storage, read_write> piece_counts: array<atomic<u32>>;
// ssdf_outer.wgsl's and ssdf_arcs.wgsl's indirect dispatch: one workgroup
// per 64 pieces of the node with the most (x; the host sets y).
@group(0) @binding(12) var<storage, read_write> piece_args: array<atomic<u32>, 3>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    if gid.x >= candidate_count[0] {
        return;
    }
    let e = candidates[gid.x];
    let x = points[pc.node_offset + node].xyz;
    if !is_silhouette(e, x) {
        return;
    }
    let n = piece_count(edge_view(e, x));
    let first = atomicAdd(&piece_counts[node], n);
    if first + n > PIECE_CAPACITY {
        return;
    }
    for (var k = 0u; k < n; k++) {
        pieces[node * PIECE_CAPACITY + first + k] = piece_record(e, k, n);
    }
    atomicMax(&piece_args[0], (first + n + 63u) / 64u);
}
