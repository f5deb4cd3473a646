// Compute pass 2 of the demo: two quads' vertices (position, colour) into a
// storage buffer, near quad first so the far one is drawn over it and must
// lose the depth test.
#include "demo/pattern.wgsl"

struct Vertex {
    position: vec4<f32>,
    color: vec4<f32>,
}
struct Params {
    time: f32,
    aspect: f32,
}
var<immediate> params: Params;
@group(0) @binding(0) var<storage, read_write> vertices: array<Vertex>;

@compute @workgroup_size(12, 1, 1)
fn main(@builtin(local_invocation_index) v: u32) {
    let q = demo_quad(v / 6u, params.time);
    // Two counter-clockwise triangles per quad.
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let c = corners[v % 6u];
    let p = q.center + c * vec2<f32>(q.half_size / params.aspect, q.half_size);
    vertices[v] = Vertex(vec4<f32>(p, q.depth, 1.0), vec4<f32>(q.color, 1.0));
}
