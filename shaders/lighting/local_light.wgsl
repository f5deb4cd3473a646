// Local lights: spheres around the field's own light sources, shaded with
// per-pixel visibility (passes/src/lighting/local.rs, which it mirrors
// function for function). A light is two vec4s in `local_lights`:
// (centre, radius), (intensity towards the object's centre, active ? 1 : 0)
// as the direct-light pass writes them; the probe and that pass read the
// spheres alone, (centre, radius).
// This part marches the field; the geometry is local_light_disk.wgsl.
// Needs: common/sg.wgsl, common/ray_box.wgsl, field/grid.wgsl,
// march/volume_march.wgsl.

#include "lighting/local_light_disk.wgsl"

// local.rs INTENSITY_SIDE.
const LOCAL_INTENSITY_SIDE: u32 = 24u;

// The colour a ray gathers inside the sphere (what the probe leaves out).
fn local_inside_colour(sphere: vec4<f32>, origin: vec3<f32>, dir: vec3<f32>, step: f32, termination: f32) -> vec3<f32> {
    let t = local_chord(sphere, origin, dir);
    if t.y <= 0.0 {
        return vec3<f32>(0.0);
    }
    return march_ray(origin, dir, t.y, step, termination).colour
        - march_ray(origin, dir, t.x, step, termination).colour;
}

// The light's emission towards `towards`: (intensity, radius of the disk
// it shines from, √(2 E[ρ²]) weighted by its light), from parallel rays
// through the cell centres of a square grid over its disk (those inside
// it), each through the sphere alone.
fn local_intensity(sphere: vec4<f32>, towards: vec3<f32>, step: f32, termination: f32) -> vec4<f32> {
    let w = normalize(towards - sphere.xyz);
    let f = local_basis(w);
    let n = f32(LOCAL_INTENSITY_SIDE);
    let r = sphere.w;
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    var moment = 0.0;
    for (var k = 0u; k < LOCAL_INTENSITY_SIDE * LOCAL_INTENSITY_SIDE; k++) {
        let a = 2.0 * (f32(k % LOCAL_INTENSITY_SIDE) + 0.5) / n - 1.0;
        let b = 2.0 * (f32(k / LOCAL_INTENSITY_SIDE) + 0.5) / n - 1.0;
        let d2 = a * a + b * b;
        if d2 >= 1.0 {
            continue;
        }
        let half = r * sqrt(1.0 - d2);
        let origin = sphere.xyz + r * (a * f.u + b * f.v) + half * w;
        let c = march_ray(origin, -w, 2.0 * half, step, termination).colour;
        sum += c;
        let y = c.x + c.y + c.z;
        weight += y;
        moment += y * d2;
    }
    let cell = 2.0 * r / n;
    var radius = r;
    if weight > 0.0 {
        radius = r * clamp(sqrt(2.0 * moment / weight), 1e-3, 1.0);
    }
    return vec4<f32>(sum * (cell * cell), radius);
}

// The field's transmittance from x to point k of side² on the disk of
// `radius`, up to the sphere.
fn local_transmittance_to(sphere: vec4<f32>, x: vec3<f32>, k: u32, side: u32, radius: f32, step: f32, termination: f32) -> f32 {
    let p = local_disk_point_towards(sphere, x, k, side, radius);
    let dir = normalize(p - x);
    var end = length(p - x);
    let t = local_chord(sphere, x, dir);
    if t.y > 0.0 {
        end = t.x;
    }
    return 1.0 - march_ray(x, dir, end, step, termination).opacity;
}
