// Evaluates the shared tonemap functions over a test ramp, for the GPU-vs-CPU
// test of common/tonemap.wgsl. Pixel (x, y) gets input v = ramp(x + y*width).
#include "common/tonemap.wgsl"

var<immediate> size: vec2<u32>;
@group(0) @binding(0) var result: texture_storage_2d<rgba32float, write>;

// The ramp: 0 at i = 0, then geometric from 1e-4 up to ~1e5, plus specials.
fn ramp(i: u32) -> f32 {
    return 1e-4 * pow(10.0, f32(i) * 9.0 / 255.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let v = ramp(id.x + id.y * size.x);
    let t = aces_filmic(v);
    textureStore(result, vec2<i32>(id.xy), vec4<f32>(v, t, srgb_encode(t), srgb_encode(v)));
}
