// The SSDF bake's first kernel (METHOD.md "SSDF field"), mirroring
// SilhouetteMesh::view_from in passes/src/ssdf/silhouette.rs: one workgroup
// per node of the batch walks the edges, keeps those on the silhouette seen
// from the node, cuts each into ARC_PIECES pieces marked outer when a ray
// just outside the piece's middle misses, and writes consecutive pieces of
// one class as one arc. Found once per node, the arcs serve every direction
// of ssdf_bake.wgsl.
// Needs: u32 define ARC_PIECES, f32 define OUTSIDE_OFFSET.
#include "ssdf/bake_common.wgsl"

// Per edge, six vec4s: (a, always), (b, 0), plane 0 (n, n·a), plane 1,
// (third corner of face 0, 0), (third corner of face 1, 0).
@group(0) @binding(1) var<storage, read> edges: array<vec4<f32>>;
// The arcs (see bake_common.wgsl) and how many each node has.
@group(0) @binding(4) var<storage, read_write> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> arc_counts: array<u32>;

var<workgroup> found: atomic<u32>;

fn faces_point(plane: vec4<f32>, x: vec3<f32>) -> bool {
    return dot(plane.xyz, x) - plane.w > 0.0;
}

fn emit(node: u32, a: vec3<f32>, b: vec3<f32>, outer: u32) {
    let at = 2u * (node * bake_arc_capacity() + atomicAdd(&found, 1u));
    arcs[at] = vec4<f32>(a, f32(outer));
    arcs[at + 1u] = vec4<f32>(b, 0.0);
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.x;
    let x = points[pc.node_offset + node].xyz;
    if lid.x == 0u {
        atomicStore(&found, 0u);
    }
    workgroupBarrier();
    for (var e = lid.x; e < pc.edge_count; e += 64u) {
        let ea = edges[6u * e];
        let front0 = faces_point(edges[6u * e + 2u], x);
        if ea.w == 0.0 && front0 == faces_point(edges[6u * e + 3u], x) {
            continue;
        }
        let third = select(edges[6u * e + 5u].xyz, edges[6u * e + 4u].xyz, front0);
        let ra = ea.xyz - x;
        let rb = edges[6u * e + 1u].xyz - x;
        let normal_raw = cross(ra, rb);
        let nl = length(normal_raw);
        let normal = select(vec3<f32>(0.0), normal_raw / nl, nl > 0.0);
        let side = sign(dot(normal, third - x));
        var run_start = normalize(ra);
        var run_outer = 2u;
        for (var k = 0u; k < ARC_PIECES; k++) {
            let t0 = f32(k) / f32(ARC_PIECES);
            let t1 = (f32(k) + 1.0) / f32(ARC_PIECES);
            let m = normalize(ra + (rb - ra) * (0.5 * (t0 + t1)));
            let probe = normalize(m - normal * (side * OUTSIDE_OFFSET));
            let outer = select(1u, 0u, bvh_occluded(x, probe));
            if outer != run_outer {
                let split = normalize(ra + (rb - ra) * t0);
                if run_outer != 2u {
                    emit(node, run_start, split, run_outer);
                }
                run_start = split;
                run_outer = outer;
            }
        }
        emit(node, run_start, normalize(rb), run_outer);
    }
    workgroupBarrier();
    if lid.x == 0u {
        arc_counts[node] = atomicLoad(&found);
    }
}
