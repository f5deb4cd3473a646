// The SSDF bake (METHOD.md "SSDF field"): S(d; x) at every direction texel
// of an octahedral map for a batch of grid nodes, mirroring
// passes/src/ssdf/silhouette.rs. One workgroup per (node, 64 directions):
// the workgroup walks the edges 64 at a time, keeps the silhouette ones
// seen from the node (cut into ARC_PIECES pieces, each marked outer when a
// ray just outside its middle misses) in shared memory, and every thread
// takes the smallest angle from its direction to them — all arcs where its
// ray misses, outer arcs where it hits.
// Needs: u32 define ARC_PIECES, f32 define OUTSIDE_OFFSET, bool OCTAHEDRAL.
#include "common/direction_map.wgsl"
#include "ssdf/angles.wgsl"

struct BakePush {
    node_offset: u32,
    map_size: u32,
    edge_count: u32,
    node_count: u32,
}

var<immediate> pc: BakePush;
// Per node: the point S is computed from (xyz).
@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
// Per edge, six vec4s: (a, always), (b, 0), plane 0 (n, n·a), plane 1,
// (third corner of face 0, 0), (third corner of face 1, 0).
@group(0) @binding(1) var<storage, read> edges: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> bvh_triangles: array<vec4<f32>>;
// S per (node of the batch, direction texel), row-major by node.
@group(0) @binding(4) var<storage, read_write> out_ssdf: array<f32>;

#include "geometry/mesh_bvh.wgsl"

const GROUP: u32 = 64u;

var<workgroup> arc_a: array<vec3<f32>, 256>;
var<workgroup> arc_b: array<vec3<f32>, 256>;
var<workgroup> arc_outer: array<u32, 256>;
var<workgroup> arc_count: atomic<u32>;
fn faces_point(plane: vec4<f32>, x: vec3<f32>) -> bool {
    return dot(plane.xyz, x) - plane.w > 0.0;
}

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
    var best = SSDF_PI;
    if lid.x == 0u {
        atomicStore(&arc_count, 0u);
    }
    workgroupBarrier();
    for (var base = 0u; base < pc.edge_count; base += GROUP) {
        let e = base + lid.x;
        if e < pc.edge_count {
            let ea = edges[6u * e];
            let eb = edges[6u * e + 1u].xyz;
            let p0 = edges[6u * e + 2u];
            let p1 = edges[6u * e + 3u];
            let front0 = faces_point(p0, x);
            if ea.w != 0.0 || front0 != faces_point(p1, x) {
                let third = select(edges[6u * e + 5u].xyz, edges[6u * e + 4u].xyz, front0);
                let ra = ea.xyz - x;
                let rb = eb - x;
                let normal_raw = cross(ra, rb);
                let nl = length(normal_raw);
                let normal = select(vec3<f32>(0.0), normal_raw / nl, nl > 0.0);
                let side = sign(dot(normal, third - x));
                for (var k = 0u; k < ARC_PIECES; k++) {
                    let t0 = f32(k) / f32(ARC_PIECES);
                    let t1 = (f32(k) + 1.0) / f32(ARC_PIECES);
                    let m = normalize(ra + (rb - ra) * (0.5 * (t0 + t1)));
                    let probe = normalize(m - normal * (side * OUTSIDE_OFFSET));
                    let slot = atomicAdd(&arc_count, 1u);
                    arc_a[slot] = normalize(ra + (rb - ra) * t0);
                    arc_b[slot] = normalize(ra + (rb - ra) * t1);
                    arc_outer[slot] = select(1u, 0u, bvh_occluded(x, probe));
                }
            }
        }
        workgroupBarrier();
        let count = atomicLoad(&arc_count);
        if valid {
            for (var i = 0u; i < count; i++) {
                if arc_outer[i] != 0u || !hit {
                    best = min(best, ssdf_angle_to_arc(d, arc_a[i], arc_b[i]));
                }
            }
        }
        workgroupBarrier();
        if lid.x == 0u {
            atomicStore(&arc_count, 0u);
        }
        workgroupBarrier();
    }
    if valid {
        out_ssdf[node * texels + texel] = select(best, -best, hit);
    }
}
