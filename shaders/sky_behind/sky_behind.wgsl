// The sky behind the frame (`sky-behind`): each pixel's colour c
// (premultiplied, its coverage in alpha) over the field's learnt sky read
// along the pixel's ray, c + max(1 − c.a, 0)·sky(d), coverage 1 — the
// trainer's T_N·b behind the field (passes/src/field/sky.rs). A pixel the
// field and objects cover whole reads no sky.
// Mirrors passes/src/sky_behind/mod.rs sky_behind_pixel.
#include "common/camera.wgsl"
#include "field/sky.wgsl"

struct SkyBehindPush {
    camera: CameraRays,
    sky_width: u32,
    sky_height: u32,
    _pad0: u32,
    _pad1: u32,
}

var<immediate> pc: SkyBehindPush;

@group(0) @binding(0) var frame_colour: texture_2d<f32>;
// The sky's texels (r, g, b, 0), row-major.
@group(0) @binding(1) var<storage, read> sky: array<vec4<f32>>;
@group(0) @binding(2) var out_colour: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if camera_outside(pc.camera, id.xy) {
        return;
    }
    let c = textureLoad(frame_colour, vec2<i32>(id.xy), 0);
    let left = max(1.0 - c.a, 0.0);
    var back = vec3<f32>(0.0);
    if left > 0.0 {
        let d = camera_ray_dir(pc.camera, vec2<f32>(id.xy) + vec2<f32>(0.5));
        back = sky_radiance(vec2<u32>(pc.sky_width, pc.sky_height), d);
    }
    textureStore(out_colour, id.xy, vec4<f32>(c.rgb + left * back, 1.0));
}
