// The SSDF bake's first kernel (METHOD.md "SSDF field"): the edges that
// can be on the silhouette seen from some point of the batch's box
// (BakePush's box_lo, box_hi: the batch's points, nearby nodes), so that
// ssdf_pieces.wgsl scans those for each node instead of every edge.
// An edge is left out only when the whole box lies, by a margin above f32
// rounding, on the front side of both its faces or on the back side of
// both: then no node of the batch sees it on the silhouette
// (SilhouetteEdge::is_silhouette). Edges with one face or more than two
// are always kept. One invocation per edge; the list's order varies from
// run to run, which changes nothing downstream (each edge's arcs are found
// on their own, and S is a minimum over them).
// CPU mirror: `ssdf::bake::edge_candidates` (passes/src/ssdf/bake.rs).
#include "ssdf/bake_push.wgsl"

// Per edge, six vec4s (silhouette_edges.wgsl): (a, always), (b, 0),
// plane 0 (n, n·a), plane 1, …
@group(0) @binding(1) var<storage, read> edges: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> candidates: array<u32>;
@group(0) @binding(8) var<storage, read_write> candidate_count: array<atomic<u32>>;
// ssdf_pieces.wgsl's indirect dispatch: one workgroup per 64 candidates
// (x; the host sets y to the batch's nodes).
@group(0) @binding(9) var<storage, read_write> candidate_args: array<atomic<u32>, 3>;

// Which side of `plane` the box is on for all its points: 1 front (the
// face faces every point), -1 back, 0 both or too close to tell.
fn box_side(plane: vec4<f32>, centre: vec3<f32>, half: vec3<f32>) -> i32 {
    let s = dot(plane.xyz, centre) - plane.w;
    let reach = dot(abs(plane.xyz), half);
    let margin = 1e-5 * (abs(plane.w) + dot(abs(plane.xyz), abs(centre) + half));
    if s - reach > margin {
        return 1;
    }
    if s + reach < -margin {
        return -1;
    }
    return 0;
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if e >= pc.edge_count {
        return;
    }
    let centre = 0.5 * (pc.box_lo.xyz + pc.box_hi.xyz);
    let half = 0.5 * (pc.box_hi.xyz - pc.box_lo.xyz);
    let s0 = box_side(edges[6u * e + 2u], centre, half);
    let s1 = box_side(edges[6u * e + 3u], centre, half);
    if edges[6u * e].w != 0.0 || s0 == 0 || s0 != s1 {
        let slot = atomicAdd(&candidate_count[0], 1u);
        candidates[slot] = e;
        atomicMax(&candidate_args[0], slot / 64u + 1u);
    }
}
