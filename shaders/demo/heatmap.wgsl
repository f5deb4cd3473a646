// A debug view of the demo (per-pixel sky luminance as a heat map). Nothing
// consumes it unless asked, so the frame graph culls it.
#include "common/tonemap.wgsl"

var<immediate> size: vec2<u32>;
@group(0) @binding(0) var sky: texture_2d<f32>;
@group(0) @binding(1) var heat: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let c = textureLoad(sky, vec2<i32>(id.xy), 0).rgb;
    let l = aces_filmic(dot(c, vec3<f32>(0.2126, 0.7152, 0.0722)));
    textureStore(heat, vec2<i32>(id.xy), vec4<f32>(l, 1.0 - abs(2.0 * l - 1.0), 1.0 - l, 1.0));
}
