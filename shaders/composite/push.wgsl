// The compositing passes' push block (composite/composite.wgsl and
// composite/refined.wgsl; mirrored by CompositePush in
// passes/src/composite/mod.rs).
struct CompositePush {
    width: u32,
    height: u32,
    object_front: u32,
    // The scale of the cast shadow's blocks `main_upsampled` blends (the
    // last level of its upsampling; unused by the other entry points).
    scale: u32,
    // Largest spread of the blocks' ρ a pixel blends before it is refined
    // (≥ 1: refine none).
    refine_spread: f32,
    // The pixels the object layer covers at most (x0, y0, x1, y1, the ends
    // exclusive): object-shade clears and shades them alone, and the
    // layer is transparent beyond them (composite/object_layer.wgsl).
    object_x0: u32,
    object_y0: u32,
    object_x1: u32,
    object_y1: u32,
}
