// A triangle covering the whole viewport from vertex indices 0..3, at the far
// plane (depth 1).
fn fullscreen_position(vertex_index: u32) -> vec4<f32> {
    let x = f32((vertex_index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vertex_index & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 1.0, 1.0);
}
