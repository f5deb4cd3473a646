// The field's light at the object's surface (`[shading] field_light`): the
// fitted lobes are the light at the object's centre, and a point of the
// object that the field hides from part of it (a toy among foliage, the
// underside near a floor) would be lit as if it stood there. Each
// workgroup of the gain pass covers one tile of 8 · pc.field_scale pixels
// a side (each of its 8 × 8 invocations a square of pc.field_scale² of
// them: the tiles grow with the image, field_light.rs TileScale); the
// tile picks one of its object pixels with diffuse light (the one nearest
// the tile's centre), casts pc.field_side² rays from that point (lifted
// off the surface) along fixed directions spread evenly over the sphere,
// and keeps per ray the field's light, Ĉ + (1 − Ô)·L_env(d) (the broad
// lobes of L_env beyond the field, as the probe adds them; the colour
// gathered inside a local light's sphere taken off, as the probe does,
// since that light is shaded on its own), and the fitted lobes' L_fit(d).
// Each pixel of the tile then scales its fitted lobes' diffuse light by
//   g = Σ_r max(0, n·d_r) (field light)_r / Σ_r max(0, n·d_r) L_fit(d_r),
// per colour channel, with its own normal n: the same rays in numerator
// and denominator, so where the field sends what the lobes say the gain is
// exactly 1 whatever the rays' count. Mirrors passes/src/shade/field_light.rs.
// Needs: shade/shade_body.wgsl, shade/self_shadow_ssdf.wgsl, the hook
// shading_fitted_count() of brdf/sg_shading.wgsl, field/grid.wgsl,
// march/volume_march.wgsl, lighting/local_light.wgsl, shadow/direct_rays.wgsl
// (DIRECT_RAY_OFFSET), the binding `local_lights`.
#include "common/fibonacci.wgsl"

// field_light.rs MAX_SIDE²: the tile's rays.
const FIELD_LIGHT_MAX_RAYS: u32 = 256u;
// field_light.rs GAIN_MAX: a bound, not a model (a field that sends more
// than this many times the lobes' light onto a plane is not their error).
const FIELD_LIGHT_GAIN_MAX: f32 = 16.0;
const FIELD_LIGHT_NO_PICK: u32 = 0xffffffffu;
// "No object along the ray": the rays see the whole field.
const FIELD_LIGHT_NO_OBJECT: f32 = 3.0e38;

// The pick: its squared doubled offset from the tile's centre above its
// index in the tile (row-major, 12 bits: tiles of up to 64 pixels a side,
// field_light.rs MAX_TILE_SCALE 4 takes 32), so that the least is
// field_light.rs tile_pick's.
var<workgroup> field_light_pick: atomic<u32>;
var<workgroup> field_light_rays: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;
var<workgroup> field_light_lobes: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;
var<workgroup> field_light_dirs: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;

// Rays per tile.
fn field_light_ray_count() -> u32 {
    return min(pc.field_side * pc.field_side, FIELD_LIGHT_MAX_RAYS);
}

// Pixels a side of a tile.
fn field_light_side() -> u32 {
    return 8u * pc.field_scale;
}

// The i-th of the pc.field_scale² pixels invocation `local` of tile
// `group` takes (a square of them, row by row).
fn field_light_pixel(group: vec2<u32>, local: vec2<u32>, i: u32) -> vec2<u32> {
    let s = pc.field_scale;
    return group * field_light_side() + local * s + vec2<u32>(i % s, i / s);
}

// The fitted lobes' radiance along d (the direct lobes at the end left out).
fn field_light_fitted(d: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < shading_fitted_count(); k++) {
        sum += sg_eval(shading_light(k), d);
    }
    return sum;
}

// Lobes of L_env, two vec4 each: (p, λ), (μ, 0); pc.env_count of them.
@group(0) @binding(23) var<storage, read> env_lobes: array<vec4<f32>>;

// L_env's broad lobes along d.
fn field_light_environment(d: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < pc.env_count; k++) {
        sum += sg_eval(sg_unpack(env_lobes[2u * k], env_lobes[2u * k + 1u]), d);
    }
    return sum;
}

// The field's light from `origin` along d, a local light's own taken off,
// L_env beyond the field.
fn field_light_along(origin: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let m = march_ray(origin, d, FIELD_LIGHT_NO_OBJECT, pc.march_step, pc.march_termination);
    var colour = m.colour;
    let first = pc.light_count - min(pc.local_count, pc.light_count);
    for (var l = 0u; l < pc.light_count - first; l++) {
        let sphere = local_lights[2u * l];
        if local_lights[2u * l + 1u].w != 0.0 && local_active(sphere, origin) {
            colour -= local_inside_colour(sphere, origin, d, pc.march_step, pc.march_termination);
        }
    }
    return max(colour, vec3<f32>(0.0)) + (1.0 - m.opacity) * field_light_environment(d);
}

// Whether pixel `p` is the object's and has diffuse light to correct
// (a metal's pixels pick no rays: their gain is never used).
fn field_light_wants(p: vec2<u32>) -> bool {
    if camera_outside(pc.camera, p) || textureLoad(distance_id, vec2<i32>(p), 0).g != pc.object_index {
        return false;
    }
    let am = textureLoad(albedo_metallic, vec2<i32>(p), 0);
    return any(brdf_diffuse(clamp(am.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), clamp(am.a, 0.0, 1.0)) > vec3<f32>(0.0));
}

// The tile's rays, into workgroup memory; every invocation of the
// workgroup (`local`, `local_index`, of tile `group`) calls it (it holds
// barriers), before any returns.
fn field_light_gather(local: vec2<u32>, local_index: u32, group: vec3<u32>) {
    if pc.field_side == 0u {
        return;
    }
    if local_index == 0u {
        atomicStore(&field_light_pick, FIELD_LIGHT_NO_PICK);
    }
    workgroupBarrier();
    let side = field_light_side();
    for (var i = 0u; i < pc.field_scale * pc.field_scale; i++) {
        let p = field_light_pixel(group.xy, local, i);
        if field_light_wants(p) {
            // Twice the offset from the tile's centre, so it is a whole
            // number.
            let q = p - group.xy * side;
            let o = vec2<i32>(q) * 2 - vec2<i32>(i32(side) - 1);
            atomicMin(&field_light_pick, (u32(o.x * o.x + o.y * o.y) << 12u) | (q.y * side + q.x));
        }
    }
    workgroupBarrier();
    let count = field_light_ray_count();
    let pick = atomicLoad(&field_light_pick);
    if pick != FIELD_LIGHT_NO_PICK {
        let source = pick & 0xfffu;
        let pixel = group.xy * side + vec2<u32>(source % side, source / side);
        let hit = textureLoad(distance_id, vec2<i32>(pixel), 0);
        let n = normalize(textureLoad(normal_roughness, vec2<i32>(pixel), 0).xyz);
        let x = pc.camera.origin + camera_ray_dir(pc.camera, vec2<f32>(pixel) + vec2<f32>(0.5)) * hit.r;
        let origin = x + n * (DIRECT_RAY_OFFSET * ssdf_world_sphere().w);
        for (var k = local_index; k < count; k += 64u) {
            let d = fibonacci_axis(k, count);
            field_light_rays[k] = vec4<f32>(field_light_along(origin, d), 0.0);
            field_light_lobes[k] = vec4<f32>(field_light_fitted(d), 0.0);
            field_light_dirs[k] = vec4<f32>(d, 0.0);
        }
    }
    workgroupBarrier();
}

// The gain on the fitted lobes' diffuse light at a pixel of the tile of
// normal n (1 where the feature is off or the tile picked no pixel).
fn field_light_gain(n: vec3<f32>) -> vec3<f32> {
    if pc.field_side == 0u || atomicLoad(&field_light_pick) == FIELD_LIGHT_NO_PICK {
        return vec3<f32>(1.0);
    }
    let count = field_light_ray_count();
    var field = vec3<f32>(0.0);
    var lobes = vec3<f32>(0.0);
    for (var r = 0u; r < count; r++) {
        let w = max(dot(n, field_light_dirs[r].xyz), 0.0);
        field += w * field_light_rays[r].xyz;
        lobes += w * field_light_lobes[r].xyz;
    }
    let ok = lobes > vec3<f32>(0.0);
    let gain = select(vec3<f32>(1.0), field / select(vec3<f32>(1.0), lobes, ok), ok);
    return clamp(gain, vec3<f32>(0.0), vec3<f32>(FIELD_LIGHT_GAIN_MAX));
}
