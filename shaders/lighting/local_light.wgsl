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

// The light's emission towards `towards` is measured with parallel rays
// through the cell centres of a LOCAL_INTENSITY_SIDE² grid over its disk
// (those inside it), each through the sphere alone; this sums rays
// first, first + every, … of them: (Σ colour, Σ luminance y) and Σ y·ρ²
// (ρ the ray's distance from the centre over the radius), which
// local_intensity_of turns into the emission. Split so that the rays
// can be shared among a workgroup (lighting/direct.wgsl).
struct LocalIntensitySum {
    sum: vec4<f32>,
    moment: f32,
}

fn local_intensity_part(sphere: vec4<f32>, towards: vec3<f32>, step: f32, termination: f32, first: u32, every: u32) -> LocalIntensitySum {
    let w = normalize(towards - sphere.xyz);
    let f = local_basis(w);
    let n = f32(LOCAL_INTENSITY_SIDE);
    let r = sphere.w;
    var out = LocalIntensitySum(vec4<f32>(0.0), 0.0);
    for (var k = first; k < LOCAL_INTENSITY_SIDE * LOCAL_INTENSITY_SIDE; k += every) {
        let a = 2.0 * (f32(k % LOCAL_INTENSITY_SIDE) + 0.5) / n - 1.0;
        let b = 2.0 * (f32(k / LOCAL_INTENSITY_SIDE) + 0.5) / n - 1.0;
        let d2 = a * a + b * b;
        if d2 >= 1.0 {
            continue;
        }
        let half = r * sqrt(1.0 - d2);
        let origin = sphere.xyz + r * (a * f.u + b * f.v) + half * w;
        let c = march_ray(origin, -w, 2.0 * half, step, termination).colour;
        let y = c.x + c.y + c.z;
        out.sum += vec4<f32>(c, y);
        out.moment += y * d2;
    }
    return out;
}

// The emission from the sums of all the rays: (intensity, radius of the
// disk it shines from, √(2 E[ρ²]) weighted by its light).
fn local_intensity_of(sphere: vec4<f32>, total: LocalIntensitySum) -> vec4<f32> {
    let r = sphere.w;
    let cell = 2.0 * r / f32(LOCAL_INTENSITY_SIDE);
    var radius = r;
    if total.sum.w > 0.0 {
        radius = r * clamp(sqrt(2.0 * total.moment / total.sum.w), 1e-3, 1.0);
    }
    return vec4<f32>(total.sum.xyz * (cell * cell), radius);
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
