// The demo's raster pass: the sky as background, then the quads with depth
// testing, into an HDR colour target.
#include "common/fullscreen.wgsl"

struct Vertex {
    position: vec4<f32>,
    color: vec4<f32>,
}
@group(0) @binding(0) var sky: texture_2d<f32>;
@group(0) @binding(1) var sky_sampler: sampler;
@group(0) @binding(2) var<storage, read> vertices: array<Vertex>;

struct BackgroundOut {
    @builtin(position) position: vec4<f32>,
}

@vertex
fn vs_background(@builtin(vertex_index) i: u32) -> BackgroundOut {
    return BackgroundOut(fullscreen_position(i));
}

@fragment
fn fs_background(in: BackgroundOut) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(sky));
    return textureSampleLevel(sky, sky_sampler, in.position.xy / size, 0.0);
}

struct QuadOut {
    @builtin(position) position: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn vs_quad(@builtin(vertex_index) i: u32) -> QuadOut {
    let v = vertices[i];
    return QuadOut(v.position, v.color);
}

@fragment
fn fs_quad(in: QuadOut) -> @location(0) vec4<f32> {
    return in.color;
}
