// What lies outside the field, drawn with the frame (`sky-behind`): each
// pixel's colour c (premultiplied, its coverage in alpha) over the field's
// learnt sky read along the pixel's ray, c + max(1 − c.a, 0)·sky(d),
// coverage 1 — the trainer's T_N·b behind the field
// (passes/src/field/sky.rs); and the lights the photographs saw past the
// bounds: the nearest disc covering the pixel at all, past the bounds in
// place of the sky where it covers, before them over the whole pixel
// where it covers (passes/src/field/seen_lights/mod.rs). A pixel the field
// and objects cover whole reads no sky.
// Mirrors passes/src/field/seen_lights/mod.rs light_over_pixel.
#include "common/camera.wgsl"
#include "common/ray_box.wgsl"
#include "field/sky.wgsl"

struct SkyBehindPush {
    camera: CameraRays,
    // 0: black behind the frame.
    sky_width: u32,
    sky_height: u32,
    light_count: u32,
    _pad0: u32,
}

var<immediate> pc: SkyBehindPush;

const PI: f32 = 3.14159265358979;

@group(0) @binding(0) var frame_colour: texture_2d<f32>;
// The sky's texels (r, g, b, 0), row-major (one unused entry without a sky).
@group(0) @binding(1) var<storage, read> sky: array<vec4<f32>>;
// The field's bounds (min, 0) and (max, 0), then each light's
// (centre, radius) and (radiance, 0).
@group(0) @binding(2) var<storage, read> lights: array<vec4<f32>>;
@group(0) @binding(3) var out_colour: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if camera_outside(pc.camera, id.xy) {
        return;
    }
    let c = textureLoad(frame_colour, vec2<i32>(id.xy), 0);
    let left = max(1.0 - c.a, 0.0);
    let px = vec2<f32>(id.xy) + vec2<f32>(0.5);
    let d = camera_ray_dir(pc.camera, px);
    var back = vec3<f32>(0.0);
    if left > 0.0 && pc.sky_width != 0u {
        back = sky_radiance(vec2<u32>(pc.sky_width, pc.sky_height), d);
    }
    var out = c.rgb + left * back;
    if pc.light_count != 0u {
        // One pixel's angle: the chord to the next pixel's ray.
        let pixel_angle = length(camera_ray_dir(pc.camera, px + vec2<f32>(1.0, 0.0)) - d);
        var best_t = 3.0e38;
        var best_cov = 0.0;
        var best_radiance = vec3<f32>(0.0);
        for (var i = 0u; i < pc.light_count; i++) {
            let a = lights[2u + 2u * i];
            let v = a.xyz - pc.camera.origin;
            let t = dot(v, d);
            if t <= 0.0 {
                continue;
            }
            let off = length(v - t * d) / t;
            let rho = a.w / t;
            let ramp = clamp(0.5 + (rho - off) / pixel_angle, 0.0, 1.0);
            let area = PI * (rho / pixel_angle) * (rho / pixel_angle);
            let cov = min(ramp, area);
            if cov > 0.0 && t < best_t {
                best_t = t;
                best_cov = cov;
                best_radiance = lights[3u + 2u * i].xyz;
            }
        }
        if best_cov > 0.0 {
            let span = ray_box(pc.camera.origin, d, lights[0].xyz, lights[1].xyz);
            if span.x > span.y || best_t <= span.x {
                out = (1.0 - best_cov) * out + best_cov * best_radiance;
            } else {
                out = c.rgb + left * ((1.0 - best_cov) * back + best_cov * best_radiance);
            }
        }
    }
    textureStore(out_colour, id.xy, vec4<f32>(out, 1.0));
}
