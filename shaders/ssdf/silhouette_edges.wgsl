// The mesh's edges as the SSDF bake's kernels read them, and what each
// kernel asks of one edge seen from a node: is it on the silhouette
// (SilhouetteEdge::is_silhouette), its view (ends, plane, which side the
// mesh is on), how many pieces it is cut into (SilhouetteEdge::pieces),
// and directions along it (passes/src/ssdf/silhouette.rs).
// Needs: u32 define ARC_PIECES, f32 define PIECE_ANGLE;
// ssdf/angles.wgsl included before.

// Per edge, six vec4s: (a, always), (b, 0), plane 0 (n, n·a), plane 1,
// (third corner of face 0, 0), (third corner of face 1, 0).
@group(0) @binding(1) var<storage, read> edges: array<vec4<f32>>;

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

// Pieces the edge's arc is cut into: none spans more than PIECE_ANGLE,
// at most ARC_PIECES (SilhouetteEdge::pieces).
fn piece_count(v: EdgeView) -> u32 {
    let c = ceil(ssdf_angle_between(normalize(v.ra), normalize(v.rb)) / PIECE_ANGLE);
    // A degenerate view (NaN) takes one piece, as on the CPU.
    return select(1u, u32(min(c, f32(ARC_PIECES))), c >= 1.0);
}

// Direction from the node at fraction t along the edge.
fn along(v: EdgeView, t: f32) -> vec3<f32> {
    return normalize(v.ra + (v.rb - v.ra) * t);
}

// A piece record of the node's piece list: edge · 256 + k · 16 + (n − 1),
// piece k of the edge's n (n ≤ ARC_PIECES ≤ 16; edges below 2²⁴, more than
// a storage binding of edges holds).
fn piece_record(e: u32, k: u32, n: u32) -> u32 {
    return e * 256u + k * 16u + (n - 1u);
}
fn record_edge(r: u32) -> u32 {
    return r / 256u;
}
fn record_piece(r: u32) -> u32 {
    return (r / 16u) % 16u;
}
fn record_pieces(r: u32) -> u32 {
    return r % 16u + 1u;
}
