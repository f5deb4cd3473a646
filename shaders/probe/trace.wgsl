// The incident-light probe (METHOD.md eq. 1): from the object's centre,
// `side` × `side` stratified rays per texel of the direction map through
// the field, writing the solid-angle mean of L_i = (1 − Ô)·L_env + Ĉ in rgb
// and of Ô in alpha (`main_with_environment`). The lobes come blurred to
// the sub-sample spacing (passes/src/probe/texel_filter.rs), so the rays
// integrate even a needle lobe.
// When the scene has no environment light, `main_field_only` writes Ĉ: the
// L_env term is not evaluated at all and `env_lobes` is not bound.
// Local lights (lighting/local_light.wgsl) active from the origin are left
// out: the colour a ray gathers inside their spheres is taken off, since
// they are shaded per pixel.
// A strided trace (`stride` > 1) writes one texel of each stride × stride
// block and leaves the others as they were (passes/src/probe/knobs.rs
// ProbeKnobs::stride).
// A dispatch traces sub-samples [first_sample, first_sample +
// sample_count) of each texel and adds their share of the mean to what
// the dispatches before it wrote (the first writes it): llvmpipe stops an
// invocation's loops after 65535 iterations in all, so the pass splits a
// texel's rays over as many dispatches as that needs
// (passes/src/probe/pass.rs).
// Mirrors passes/src/probe/reference.rs.
#include "common/ray_box.wgsl"
#include "common/sg.wgsl"
#include "common/direction_map.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"
#include "lighting/local_light.wgsl"

struct ProbePush {
    origin: vec3<f32>,
    step: f32,
    width: u32,
    height: u32,
    termination: f32,
    env_lobe_count: u32,
    side: u32,
    // Local lights in `local_spheres`.
    local_count: u32,
    // One texel of each stride × stride block is traced, the one at
    // (phase mod stride, phase / stride) in it (1, 0: every texel).
    stride: u32,
    phase: u32,
    // The sub-samples this dispatch traces (row-major in the texel's
    // side × side cells).
    first_sample: u32,
    sample_count: u32,
    _pad0: u32,
    _pad1: u32,
}

var<immediate> pc: ProbePush;

@group(0) @binding(3) var probe: texture_storage_2d<rgba32float, read_write>;
// Environment lobes, two vec4 each: (p, λ), (μ, 0).
@group(0) @binding(4) var<storage, read> env_lobes: array<vec4<f32>>;
// The local lights, two vec4 each: (centre, radius), known emission.
@group(0) @binding(5) var<storage, read> local_spheres: array<vec4<f32>>;

// "No object along the ray": the probe sees the whole field.
const PROBE_NO_OBJECT: f32 = 3.0e38;

fn environment(d: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < pc.env_lobe_count; k++) {
        sum += sg_eval(sg_unpack(env_lobes[2u * k], env_lobes[2u * k + 1u]), d);
    }
    return sum;
}

// Sub-sample `k` (row-major in the texel's `side` × `side` cells) of
// texel `t`: its direction, its weight dω/(du dv) and the march along it.
struct ProbeSample {
    dir: vec3<f32>,
    weight: f32,
    march: MarchResult,
}

fn probe_sample(t: vec2<u32>, k: u32) -> ProbeSample {
    let ij = vec2<u32>(k % pc.side, k / pc.side);
    let size = vec2<u32>(pc.width, pc.height);
    let dd = dm_direction_density(dm_subsample_uv(t, ij, pc.side, size));
    var m = march_ray(pc.origin, dd.xyz, PROBE_NO_OBJECT, pc.step, pc.termination);
    for (var l = 0u; l < pc.local_count; l++) {
        let sphere = local_spheres[2u * l];
        if local_active(sphere, pc.origin) {
            m.colour -= local_inside_colour(sphere, pc.origin, dd.xyz, pc.step, pc.termination);
        }
    }
    m.colour = max(m.colour, vec3<f32>(0.0));
    return ProbeSample(dd.xyz, dd.w, m);
}

// The texel invocation `id` traces (beyond the map: none).
fn probe_texel(id: vec2<u32>) -> vec2<u32> {
    return id * pc.stride + vec2<u32>(pc.phase % pc.stride, pc.phase / pc.stride);
}

// The sum of texel t's sub-sample weights (every dispatch divides by it).
fn texel_weight(t: vec2<u32>) -> f32 {
    let size = vec2<u32>(pc.width, pc.height);
    var weight = 0.0;
    for (var k = 0u; k < pc.side * pc.side; k++) {
        let ij = vec2<u32>(k % pc.side, k / pc.side);
        weight += dm_direction_density(dm_subsample_uv(t, ij, pc.side, size)).w;
    }
    return weight;
}

// Adds this dispatch's share `sum` of texel t's weighted sum to what the
// dispatches before wrote (the first one writes it).
fn store_share(t: vec2<u32>, sum: vec4<f32>) {
    var before = vec4<f32>(0.0);
    if pc.first_sample > 0u {
        before = textureLoad(probe, t);
    }
    textureStore(probe, t, before + sum / texel_weight(t));
}

// Each entry point writes (or adds) its sub-samples' share of the
// solid-angle mean over the texel's sub-samples.
@compute @workgroup_size(8, 8, 1)
fn main_with_environment(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = probe_texel(gid.xy);
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    var sum = vec4<f32>(0.0);
    for (var k = pc.first_sample; k < pc.first_sample + pc.sample_count; k++) {
        let s = probe_sample(id, k);
        let l = s.march.colour + (1.0 - s.march.opacity) * environment(s.dir);
        sum += s.weight * vec4<f32>(l, s.march.opacity);
    }
    store_share(id, sum);
}

@compute @workgroup_size(8, 8, 1)
fn main_field_only(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = probe_texel(gid.xy);
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    var sum = vec4<f32>(0.0);
    for (var k = pc.first_sample; k < pc.first_sample + pc.sample_count; k++) {
        let s = probe_sample(id, k);
        sum += s.weight * vec4<f32>(s.march.colour, s.march.opacity);
    }
    store_share(id, sum);
}
