// The SSDF bake's fourth kernel (METHOD.md "SSDF field"): one invocation
// per silhouette piece of a node; the first piece of each edge joins the
// edge's consecutive outer pieces (ssdf_outer.wgsl) into arcs and appends
// them to the node's outline (SilhouetteMesh::view_from).
// Needs: u32 defines ARC_PIECES, PIECE_CAPACITY, ARC_CAPACITY; f32 define
// PIECE_ANGLE.
#include "ssdf/angles.wgsl"
#include "ssdf/bake_push.wgsl"
#include "ssdf/silhouette_edges.wgsl"
#include "ssdf/piece_list.wgsl"

@group(0) @binding(13) var<storage, read> outer: array<u32>;
// Per node: its outline's arcs and how many (bake_push.wgsl).
@group(0) @binding(4) var<storage, read_write> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> arc_counts: array<atomic<u32>>;

fn emit(node: u32, a: vec3<f32>, b: vec3<f32>) {
    let slot = atomicAdd(&arc_counts[node], 1u);
    if slot < ARC_CAPACITY {
        let at = 4u * (node * ARC_CAPACITY + slot);
        let p = ssdf_prepare_arc(a, b);
        arcs[at] = p[0];
        arcs[at + 1u] = p[1];
        arcs[at + 2u] = p[2];
        arcs[at + 3u] = p[3];
    }
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.y;
    let base = piece_slot(node, gid.x);
    if base == 0xffffffffu {
        return;
    }
    let r = pieces[base];
    if record_piece(r) != 0u {
        return;
    }
    let n = record_pieces(r);
    let v = edge_view(record_edge(r), points[pc.node_offset + node].xyz);
    var run = false;
    var run_start = vec3<f32>(0.0);
    for (var k = 0u; k < n; k++) {
        let is_outer = outer[base + k] != 0u;
        if is_outer && !run {
            run_start = along(v, f32(k) / f32(n));
        } else if !is_outer && run {
            emit(node, run_start, along(v, f32(k) / f32(n)));
        }
        run = is_outer;
    }
    if run {
        emit(node, run_start, along(v, 1.0));
    }
}
