// Compute pass 1 of the demo: the HDR sky into a storage image.
#include "demo/pattern.wgsl"

struct Params {
    size: vec2<u32>,
    time: f32,
    _pad: f32,
}
var<immediate> params: Params;
@group(0) @binding(0) var sky: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(params.size);
    textureStore(sky, vec2<i32>(id.xy), vec4<f32>(demo_sky(uv, params.time), 1.0));
}
