// The object's shading lobes (passes/src/lighting/direct_pass.rs): the M
// fitted lobes copied from the fit's buffer; then each lobe of L_env too
// sharp for the fit, its amplitude scaled by the field's mean
// transmittance 1 − Ô along its rays from the object's centre (the rays
// are the lobe's own stratified directions, passes/src/lighting/sharp.rs
// lobe_rays); then each local light (lighting/local_light.wgsl) as the
// centre sees it, its intensity measured towards the centre and written
// with its sphere to `local_lights` for the per-pixel shading. One
// workgroup per output lobe, its rays shared among the group's
// invocations: llvmpipe stops an invocation's loops after 65535
// iterations in all, which one invocation marching a lobe's 256 rays
// could pass (passes/src/lighting/direct_pass.rs checks the rest).
// Mirrors passes/src/lighting/direct_reference.rs.
#include "common/ray_box.wgsl"
#include "common/sg.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"
#include "lighting/local_light.wgsl"
#include "common/group_sum.wgsl"

struct DirectPush {
    origin: vec3<f32>,
    step: f32,
    termination: f32,
    fitted: u32,
    sharp: u32,
    rays: u32,
    // Local lights after the sharp lobes, and the side of their rays.
    local: u32,
    local_side: u32,
    // 1: shade the sharp lobes and the lights of known emission; 0: the
    // environment is off, write them black.
    environment: u32,
    // 1: copy the fitted lobes alone (a fit continued with the object
    // still; the rest stands).
    fitted_only: u32,
}

var<immediate> pc: DirectPush;

// The fit's lobe buffer: slot 0 holds the current M lobes as (p, λ), (μ, 0).
@group(0) @binding(3) var<storage, read> fitted_lobes: array<vec4<f32>>;
// The sharp lobes of L_env, two vec4 each.
@group(0) @binding(4) var<storage, read> sharp_lobes: array<vec4<f32>>;
// `rays` unit directions per sharp lobe (xyz; w unused).
@group(0) @binding(5) var<storage, read> sharp_rays: array<vec4<f32>>;
// Output: M + K + L lobes, two vec4 each.
@group(0) @binding(6) var<storage, read_write> lights: array<vec4<f32>>;
// The local lights, two vec4 each: (centre, radius), and the emission
// when known (intensity, radius it shines from; w = 0: measure it here).
@group(0) @binding(7) var<storage, read> local_spheres: array<vec4<f32>>;
// Output: each local light as (centre, radius), (intensity, radius of the
// disk it shines from; 0 while inactive).
@group(0) @binding(8) var<storage, read_write> local_lights: array<vec4<f32>>;

const DIRECT_NO_OBJECT: f32 = 3.0e38;
const DIRECT_GROUP: u32 = 64u;

var<workgroup> direct_emission: vec4<f32>;

fn local_light(i: u32, k: u32, lid: u32) {
    let sphere = local_spheres[2u * k];
    var emission = local_spheres[2u * k + 1u];
    // A light of known emission lies outside the field: it is environment
    // light, off with the environment.
    let known = emission.w > 0.0;
    if !local_active(sphere, pc.origin) || (known && pc.environment == 0u) {
        if lid == 0u {
            local_lights[2u * k] = sphere;
            local_lights[2u * k + 1u] = vec4<f32>(0.0);
            lights[2u * i] = vec4<f32>(0.0, 1.0, 0.0, 1.0);
            lights[2u * i + 1u] = vec4<f32>(0.0);
        }
        return;
    }
    if !known {
        let part = local_intensity_part(sphere, pc.origin, pc.step, pc.termination, lid, DIRECT_GROUP);
        let sum = group_sum(lid, part.sum);
        let moment = group_sum(lid, vec4<f32>(part.moment, 0.0, 0.0, 0.0)).x;
        if lid == 0u {
            direct_emission = local_intensity_of(sphere, LocalIntensitySum(sum, moment));
        }
        workgroupBarrier();
        emission = direct_emission;
    }
    let n = pc.local_side * pc.local_side;
    var clear = 0.0;
    for (var r = lid; r < n; r += DIRECT_GROUP) {
        clear += local_transmittance_to(sphere, pc.origin, r, pc.local_side, emission.w, pc.step, pc.termination);
    }
    clear = group_sum(lid, vec4<f32>(clear, 0.0, 0.0, 0.0)).x;
    if lid == 0u {
        local_lights[2u * k] = sphere;
        local_lights[2u * k + 1u] = emission;
        let to = sphere.xyz - pc.origin;
        let g = local_sphere_lobe(normalize(to), length(to), emission.w, emission.xyz);
        let t = clamp(clear / f32(max(n, 1u)), 0.0, 1.0);
        lights[2u * i] = vec4<f32>(g.direction, g.sharpness);
        lights[2u * i + 1u] = vec4<f32>(g.amplitude * t, 0.0);
    }
}

// Workgroup i writes output lobe i (every branch below is taken by the
// whole group alike).
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = group.x;
    if i < pc.fitted {
        if lid == 0u {
            lights[2u * i] = fitted_lobes[2u * i];
            lights[2u * i + 1u] = fitted_lobes[2u * i + 1u];
        }
        return;
    }
    if i >= pc.fitted + pc.sharp + pc.local || pc.fitted_only != 0u {
        return;
    }
    if i >= pc.fitted + pc.sharp {
        local_light(i, i - pc.fitted - pc.sharp, lid);
        return;
    }
    let k = i - pc.fitted;
    if pc.environment == 0u {
        if lid == 0u {
            lights[2u * i] = sharp_lobes[2u * k];
            lights[2u * i + 1u] = vec4<f32>(0.0);
        }
        return;
    }
    var clear = 0.0;
    for (var r = lid; r < pc.rays; r += DIRECT_GROUP) {
        let dir = sharp_rays[k * pc.rays + r].xyz;
        let m = march_ray(pc.origin, dir, DIRECT_NO_OBJECT, pc.step, pc.termination);
        clear += 1.0 - m.opacity;
    }
    clear = group_sum(lid, vec4<f32>(clear, 0.0, 0.0, 0.0)).x;
    if lid == 0u {
        let t = clamp(clear / f32(max(pc.rays, 1u)), 0.0, 1.0);
        let amplitude = sharp_lobes[2u * k + 1u];
        lights[2u * i] = sharp_lobes[2u * k];
        lights[2u * i + 1u] = vec4<f32>(amplitude.xyz * t, 0.0);
    }
}
