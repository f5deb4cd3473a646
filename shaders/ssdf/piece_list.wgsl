// A node's silhouette pieces as ssdf_pieces.wgsl left them, read by the
// kernels that go over them one invocation a piece (ssdf_outer.wgsl,
// ssdf_arcs.wgsl; the layout in bake_push.wgsl).
// Needs: u32 define PIECE_CAPACITY.

@group(0) @binding(10) var<storage, read> pieces: array<u32>;
@group(0) @binding(11) var<storage, read> piece_counts: array<u32>;

// Where piece i of the node's list is kept (in `pieces`, and in the
// kernels' per-piece arrays), or none (0xffffffff) past the list's end.
fn piece_slot(node: u32, i: u32) -> u32 {
    if i >= min(piece_counts[node], PIECE_CAPACITY) {
        return 0xffffffffu;
    }
    return node * PIECE_CAPACITY + i;
}
