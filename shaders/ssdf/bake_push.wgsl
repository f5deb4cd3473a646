// What every kernel of the SSDF bake reads (ssdf_candidates.wgsl,
// ssdf_pieces.wgsl, ssdf_outer.wgsl, ssdf_arcs.wgsl, ssdf_bake.wgsl): the
// push block and the points; and how the per-node lists the kernels pass
// on are laid out.
//
// The per-node lists: node i of the batch keeps its silhouette pieces
// (ssdf_pieces.wgsl writes them; ssdf_outer.wgsl and ssdf_arcs.wgsl read
// them) from i · PIECE_CAPACITY, and its outline's arcs (ssdf_arcs.wgsl
// writes them, ssdf_bake.wgsl reads them) from i · ARC_CAPACITY, four
// vec4s an arc (ssdf_prepare_arc in angles.wgsl: its ends a and b, unit
// directions from the node, and what its distance needs). A count may
// pass its capacity: what does not fit is not written, and the host,
// which reads the counts back, refuses the bake (SsdfBaker::run).
// ARC_CAPACITY bounds ssdf_bake.wgsl's loop over the arcs, which lavapipe
// would otherwise cut short silently: llvmpipe ends all of an
// invocation's loops after 65535 iterations in all.

struct BakePush {
    node_offset: u32,
    map_size: u32,
    edge_count: u32,
    node_count: u32,
    // The batch's points' bounding box (xyz; w unused).
    box_lo: vec4<f32>,
    box_hi: vec4<f32>,
}

var<immediate> pc: BakePush;
// Per node: the point S is computed from (xyz).
@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
