// The incident-light probe (METHOD.md eq. 1): from the object's centre,
// one ray per texel of the direction map through the field, writing
// L_i = (1 − Ô)·L_env + Ĉ in rgb and Ô in alpha (`main_with_environment`).
// When the scene has no environment light, `main_field_only` writes Ĉ: the
// L_env term is not evaluated at all and `env_lobes` is not bound.
// Mirrors passes/src/probe/reference.rs.
#include "common/ray_box.wgsl"
#include "common/sg.wgsl"
#include "common/direction_map.wgsl"
#include "field/grid.wgsl"
#include "nerf/volume_march.wgsl"

struct ProbePush {
    origin: vec3<f32>,
    step: f32,
    width: u32,
    height: u32,
    termination: f32,
    env_lobe_count: u32,
}

var<immediate> pc: ProbePush;

@group(0) @binding(3) var probe: texture_storage_2d<rgba32float, write>;
// Environment lobes, two vec4 each: (p, λ), (μ, 0).
@group(0) @binding(4) var<storage, read> env_lobes: array<vec4<f32>>;

// "No object along the ray": the probe sees the whole field.
const PROBE_NO_OBJECT: f32 = 3.0e38;

fn environment(d: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < pc.env_lobe_count; k++) {
        sum += sg_eval(sg_unpack(env_lobes[2u * k], env_lobes[2u * k + 1u]), d);
    }
    return sum;
}

struct ProbeRay {
    dir: vec3<f32>,
    march: MarchResult,
}

fn probe_ray(t: vec2<u32>) -> ProbeRay {
    let d = dm_direction(t, vec2<u32>(pc.width, pc.height));
    return ProbeRay(d, march_ray(pc.origin, d, PROBE_NO_OBJECT, pc.step, pc.termination));
}

@compute @workgroup_size(8, 8, 1)
fn main_with_environment(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    let p = probe_ray(id.xy);
    let radiance = p.march.colour + (1.0 - p.march.opacity) * environment(p.dir);
    textureStore(probe, id.xy, vec4<f32>(radiance, p.march.opacity));
}

@compute @workgroup_size(8, 8, 1)
fn main_field_only(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    let p = probe_ray(id.xy);
    textureStore(probe, id.xy, vec4<f32>(p.march.colour, p.march.opacity));
}
