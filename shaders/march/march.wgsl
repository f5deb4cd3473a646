// The NeRF ray-march pass: one camera ray per pixel through the grid field,
// writing (Ĉ, Ô) and D̂. `main_clipped` cuts each ray at the object's depth
// (distance along the ray, Fig. 2); `main_unclipped` is the same pass with
// no object in the frame (no depth image is read). Either may march a
// rectangle of the image alone: invocation (x, y) marches pixel
// `origin` + (x, y).
#include "common/camera.wgsl"
#include "common/ray_box.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"

struct MarchPush {
    camera: CameraRays,
    step: f32,
    termination: f32,
    origin: vec2<u32>,
}

var<immediate> pc: MarchPush;

@group(0) @binding(3) var out_colour: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_depth: texture_storage_2d<r32float, write>;
@group(0) @binding(5) var object_depth: texture_2d<f32>;

// "No object in this pixel".
const NO_OBJECT: f32 = 3.0e38;

fn march_pixel(pixel: vec2<u32>, t_object: f32) {
    let dir = camera_ray_dir(pc.camera, vec2<f32>(pixel) + vec2<f32>(0.5));
    let r = march_ray(pc.camera.origin, dir, t_object, pc.step, pc.termination);
    textureStore(out_colour, pixel, vec4<f32>(r.colour, r.opacity));
    textureStore(out_depth, pixel, vec4<f32>(r.depth, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8, 1)
fn main_unclipped(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = id.xy + pc.origin;
    if camera_outside(pc.camera, pixel) {
        return;
    }
    march_pixel(pixel, NO_OBJECT);
}

@compute @workgroup_size(8, 8, 1)
fn main_clipped(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = id.xy + pc.origin;
    if camera_outside(pc.camera, pixel) {
        return;
    }
    march_pixel(pixel, textureLoad(object_depth, pixel, 0).r);
}
