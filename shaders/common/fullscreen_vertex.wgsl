// The vertex stage of a full-screen pass: `vs_main` draws the triangle of
// common/fullscreen.wgsl (3 vertices); fragment stages take `FullscreenOut`.
#include "common/fullscreen.wgsl"

struct FullscreenOut {
    @builtin(position) position: vec4<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> FullscreenOut {
    return FullscreenOut(fullscreen_position(i));
}
