// Presents an HDR image on the swapchain: exposure, ACES, and sRGB encoding
// unless the swapchain format encodes itself.
#include "common/fullscreen_vertex.wgsl"
#include "common/tonemap.wgsl"

struct Params {
    exposure: f32,
    encode_srgb: u32,
}
var<immediate> params: Params;
@group(0) @binding(0) var hdr: texture_2d<f32>;

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(hdr));
    let p = clamp(vec2<i32>(in.position.xy), vec2<i32>(0), size - 1);
    var c = aces_filmic3(textureLoad(hdr, p, 0).rgb * params.exposure);
    if (params.encode_srgb != 0u) {
        c = srgb_encode3(c);
    }
    return vec4<f32>(c, 1.0);
}
