// The SSDF bake's first kernel (METHOD.md "SSDF field"), mirroring
// SilhouetteMesh::view_from in passes/src/ssdf/silhouette.rs: one workgroup
// per node of the batch finds the edges on the silhouette seen from the
// node, cuts each into ARC_PIECES pieces marked outer when a ray just
// outside the piece's middle misses, and writes consecutive pieces of one
// class as one arc (see `main` for how the work is shared out). Found once
// per node, the arcs serve every direction of ssdf_bake.wgsl.
// Needs: u32 define ARC_PIECES, f32 define OUTSIDE_OFFSET.
#include "ssdf/bake_common.wgsl"

// Per edge, six vec4s: (a, always), (b, 0), plane 0 (n, n·a), plane 1,
// (third corner of face 0, 0), (third corner of face 1, 0).
@group(0) @binding(1) var<storage, read> edges: array<vec4<f32>>;
// The arcs (see bake_common.wgsl) and how many each node has.
@group(0) @binding(4) var<storage, read_write> arcs: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> arc_counts: array<u32>;

var<workgroup> found: atomic<u32>;
// The silhouette edges of the chunk of edges being scanned, and per edge a
// bit per piece: set where the piece's outside ray misses (outer).
const CHUNK: u32 = 256u;
var<workgroup> sil_count: atomic<u32>;
var<workgroup> sil_total: u32;
var<workgroup> sil_edges: array<u32, 256>;
var<workgroup> sil_outer: array<atomic<u32>, 256>;

fn faces_point(plane: vec4<f32>, x: vec3<f32>) -> bool {
    return dot(plane.xyz, x) - plane.w > 0.0;
}

fn is_silhouette(e: u32, x: vec3<f32>) -> bool {
    return edges[6u * e].w != 0.0 || faces_point(edges[6u * e + 2u], x) != faces_point(edges[6u * e + 3u], x);
}

// Edge e seen from x: its ends' directions (unnormalised), the unit normal
// of the plane through x and the edge, and on which side of it the mesh
// lies (the third corner of the face facing x).
struct EdgeView {
    ra: vec3<f32>,
    rb: vec3<f32>,
    normal: vec3<f32>,
    side: f32,
}

fn edge_view(e: u32, x: vec3<f32>) -> EdgeView {
    let front0 = faces_point(edges[6u * e + 2u], x);
    let third = select(edges[6u * e + 5u].xyz, edges[6u * e + 4u].xyz, front0);
    let ra = edges[6u * e].xyz - x;
    let rb = edges[6u * e + 1u].xyz - x;
    let normal_raw = cross(ra, rb);
    let nl = length(normal_raw);
    let normal = select(vec3<f32>(0.0), normal_raw / nl, nl > 0.0);
    return EdgeView(ra, rb, normal, sign(dot(normal, third - x)));
}

fn emit(node: u32, a: vec3<f32>, b: vec3<f32>, outer: u32) {
    let at = 2u * (node * bake_arc_capacity() + atomicAdd(&found, 1u));
    arcs[at] = vec4<f32>(a, f32(outer));
    arcs[at + 1u] = vec4<f32>(b, 0.0);
}

// The edges are scanned CHUNK at a time: first the chunk's silhouette edges
// are gathered, then their pieces' outside rays are cast by all the
// workgroup's invocations together (a silhouette edge is a few per cent of
// the edges: one invocation per edge left most lanes idle while a few cast
// rays), then each silhouette edge's pieces are joined into arcs.
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let node = wg.x;
    let x = points[pc.node_offset + node].xyz;
    if lid.x == 0u {
        atomicStore(&found, 0u);
    }
    for (var base = 0u; base < pc.edge_count; base += CHUNK) {
        if lid.x == 0u {
            atomicStore(&sil_count, 0u);
        }
        workgroupBarrier();
        let end = min(base + CHUNK, pc.edge_count);
        for (var e = base + lid.x; e < end; e += 64u) {
            if is_silhouette(e, x) {
                let slot = atomicAdd(&sil_count, 1u);
                sil_edges[slot] = e;
                atomicStore(&sil_outer[slot], 0u);
            }
        }
        workgroupBarrier();
        if lid.x == 0u {
            sil_total = atomicLoad(&sil_count);
        }
        let count = workgroupUniformLoad(&sil_total);
        for (var t = lid.x; t < count * ARC_PIECES; t += 64u) {
            let slot = t / ARC_PIECES;
            let k = t % ARC_PIECES;
            let v = edge_view(sil_edges[slot], x);
            let t0 = f32(k) / f32(ARC_PIECES);
            let t1 = (f32(k) + 1.0) / f32(ARC_PIECES);
            let m = normalize(v.ra + (v.rb - v.ra) * (0.5 * (t0 + t1)));
            let probe = normalize(m - v.normal * (v.side * OUTSIDE_OFFSET));
            if !bvh_occluded(x, probe) {
                atomicOr(&sil_outer[slot], 1u << k);
            }
        }
        workgroupBarrier();
        for (var slot = lid.x; slot < count; slot += 64u) {
            let v = edge_view(sil_edges[slot], x);
            let bits = atomicLoad(&sil_outer[slot]);
            var run_start = normalize(v.ra);
            var run_outer = 2u;
            for (var k = 0u; k < ARC_PIECES; k++) {
                let outer = (bits >> k) & 1u;
                if outer != run_outer {
                    let split = normalize(v.ra + (v.rb - v.ra) * (f32(k) / f32(ARC_PIECES)));
                    if run_outer != 2u {
                        emit(node, run_start, split, run_outer);
                    }
                    run_start = split;
                    run_outer = outer;
                }
            }
            emit(node, run_start, normalize(v.rb), run_outer);
        }
        workgroupBarrier();
    }
    if lid.x == 0u {
        arc_counts[node] = atomicLoad(&found);
    }
}
