// What the SSDF bake's two kernels share (ssdf_silhouette.wgsl finds each
// node's silhouette arcs, ssdf_bake.wgsl measures every direction against
// them): the push block, the points, the BVH, and how arcs are stored.
// Needs: u32 define ARC_PIECES.

struct BakePush {
    node_offset: u32,
    map_size: u32,
    edge_count: u32,
    node_count: u32,
}

var<immediate> pc: BakePush;
// Per node: the point S is computed from (xyz).
@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> bvh_triangles: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"

// Arcs a node may have: every edge on its silhouette, in at most
// ARC_PIECES runs. Node i of the batch keeps its arcs from
// i · bake_arc_capacity(), two vec4s each: (a, outer ? 1 : 0), (b, 0),
// a and b unit directions from the node.
fn bake_arc_capacity() -> u32 {
    return pc.edge_count * ARC_PIECES;
}
