// The body of the cast-shadow pass (eq. 7-8) of one object on the field,
// included by shadow/cast.wgsl and shadow/cast_direct.wgsl, which define
// the hooks cast_direct_visibility(x, lobe, rays) -> f32: the visible share
// of direct lobe `lobe` (the last pc.direct_lobes lobes, too sharp for the
// fit) from x, ray-cast against the mesh (shadow/direct_rays.wgsl), and,
// for the local lights (the last pc.local_count of those),
// cast_local_lobe(x, l) -> Sg, the light's lobe from x,
// cast_local_arrival(x, n, l) -> (transmittance, share of its rays from
// above the plane), and cast_local_clear(x, n, l) -> the share of those
// rays past the mesh (shadow/local_rays.wgsl): a local light is weighed
// by its light at x, not at the object's centre. Per
// pixel, the
// point at the field's expected depth D̂/Ô, the normal −∇σ there, and
// ρ = 1 − Σ_k E_k (1 − q(S(p'_k), λ'_k)) / max(Σ_k E_k, π L) over the
// lobes L_k, p'_k their products with the cosine and E_k their irradiance
// on the point's plane (sg_diffuse_irradiance; runtime.rs explains why not
// the products' integrals); L the field's colour at the pixel, π L the
// irradiance floor of an albedo ≤ 1 surface; each
// lobe's occlusion is capped by the share of its energy the bounding
// sphere can block and, for a lobe the SSDF shadows, by its light over the
// sphere's cone where the cone's points resolve it (shadow/cone.wgsl;
// cast_bound), and lobes whose
// direction clears the sphere by a quarter turn, or of which it can block
// under CAST_SKIP_SHARE, skip the SSDF (q = 1); a direct lobe takes q
// from its rays instead of the SSDF; the light the object sends back
// (shadow/bounce.wgsl) offsets the blocked light, never beyond it, and
// the least of it (whatever the point's own ratio) is taken off the first
// test's bound before the SSDF is read. Mirrors
// passes/src/shadow/runtime.rs cast_shadow_factor. `main_classify` writes
// 1 where the first test leaves a pixel unshadowed and lists the others;
// `main_listed` takes ρ in full at the listed pixels, and at the pixels
// shadow-upsample listed; the `_chained` entries multiply the previous
// object's ρ. Output: ρ in rgb.
// Needs: the shadow defines (passes/src/shadow/gpu.rs).
#include "common/ray_box.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"
#include "common/camera.wgsl"
#include "common/sg.wgsl"

struct CastPush {
    camera: CameraRays,
    // The step of the central differences that take the field's normal.
    normal_step: f32,
    // Lobes of `light_lobes` that light the object (from its start).
    light_count: u32,
    // How many of them, at the end, are direct lobes, and rays per lobe.
    direct_lobes: u32,
    direct_rays: u32,
    // How many of the direct lobes, at the end, are local lights, and the
    // side of their rays (read by shadow/cast_direct.wgsl).
    local_count: u32,
    local_side: u32,
    // The march's step and termination, for pixels marched again
    // (shadow_point).
    march_step: f32,
    march_termination: f32,
    // ρ is taken at one pixel (its centre) of each scale × scale block
    // (shadow/upsample.wgsl brings it back to full resolution).
    scale: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

var<immediate> pc: CastPush;
@group(0) @binding(3) var field_colour: texture_2d<f32>;
@group(0) @binding(4) var field_depth: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> light_lobes: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> fh_table: array<f32>;
@group(0) @binding(7) var<storage, read> ssdf: SsdfObject;
@group(0) @binding(8) var<storage, read> ssdf_rows: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> ssdf_coefs: array<vec4<f32>>;
@group(0) @binding(10) var previous: texture_2d<f32>;
@group(0) @binding(11) var out_shadow: texture_storage_2d<rgba32float, write>;
@group(0) @binding(17) var refined: texture_storage_2d<rgba32float, read_write>;
@group(0) @binding(18) var<storage, read> refine_count: u32;
@group(0) @binding(19) var<storage, read> refine_list: array<u32>;
// The list `main_classify*` appends the pixels the object may shadow to
// (their count, their indices y · width + x at the cast scale, and the
// workgroups of REFINE_WORKGROUP of the listed pass's indirect dispatch).
@group(0) @binding(20) var<storage, read_write> cast_count: atomic<u32>;
@group(0) @binding(21) var<storage, read_write> cast_list: array<u32>;
@group(0) @binding(22) var<storage, read_write> cast_args: array<atomic<u32>, 3>;
@group(0) @binding(15) var<storage, read> objects: array<ObjectRecord>;

#include "shadow/fh.wgsl"
#include "shadow/cone.wgsl"
#include "ssdf/ssdf.wgsl"
#include "shadow/bounce.wgsl"
#include "shadow/refine_list.wgsl"

const CAST_HALF_PI: f32 = 1.57079632679490;

fn density(x: vec3<f32>) -> f32 {
    return grid_sample(x).w;
}

// Below this share of a lobe's energy the object can block, the lobe is
// left unshadowed (runtime.rs CAST_SKIP_SHARE).
const CAST_SKIP_SHARE: f32 = 1e-3;
// Where the object can block less than this share of a point's light, the
// point is left unshadowed (runtime.rs CAST_TOLERANCE).
const CAST_TOLERANCE: f32 = 1e-3;

// The bounding sphere seen from one point (runtime.rs SphereView): the
// direction to its centre, cos β and sin β of its angular radius, the
// cone's solid angle 2π(1 − cos β) times the share the mesh covers (its
// fill far away, all of it at the sphere), and whether the point is inside.
struct CastSphere {
    u: vec3<f32>,
    cos_beta: f32,
    sin_beta: f32,
    covered_solid: f32,
    inside: bool,
}

fn cast_sphere(x: vec3<f32>) -> CastSphere {
    let to = ssdf_world_sphere().xyz - x;
    let dist = length(to);
    let r = ssdf_world_sphere().w;
    if dist <= r {
        return CastSphere(vec3<f32>(0.0, 1.0, 0.0), 0.0, 1.0, 0.0, true);
    }
    let sin_beta = r / dist;
    let cos_beta = sqrt(max(1.0 - sin_beta * sin_beta, 0.0));
    let fill = ssdf.reflectance.w;
    let covered = fill + (1.0 - fill) * sin_beta * sin_beta;
    return CastSphere(to / dist, cos_beta, sin_beta, 2.0 * SG_PI * (1.0 - cos_beta) * covered, false);
}

// cos(max(γ − β, 0)), γ the angle from unit `dir` to the centre.
fn cast_cos_gap(v: CastSphere, dir: vec3<f32>) -> f32 {
    let cos_gamma = clamp(dot(dir, v.u), -1.0, 1.0);
    if cos_gamma >= v.cos_beta {
        return 1.0;
    }
    return cos_gamma * v.cos_beta + sqrt(max(1.0 - cos_gamma * cos_gamma, 0.0)) * v.sin_beta;
}

// The largest share of lobe p's hemisphere energy the bounding sphere can
// block (runtime.rs sphere_share), and whether the sphere lies a quarter
// turn or more from p's axis (runtime.rs sphere_clear_of).
fn sphere_share(v: CastSphere, p: Sg, cos_gap: f32) -> f32 {
    if v.inside {
        return 1.0;
    }
    let peak = exp(p.sharpness * (cos_gap - 1.0));
    return min(peak * v.covered_solid / (2.0 * SG_PI * sg_one_minus_exp_neg_over_x(p.sharpness)), 1.0);
}

fn clears_sphere(v: CastSphere, cos_gap: f32) -> bool {
    return !v.inside && cos_gap <= 0.0;
}

// The share of product lobe `p`'s energy the sphere seen as `view` can
// block, or −1 where the object cannot block its light (the sphere clears
// its axis by a quarter turn, or the share is under CAST_SKIP_SHARE).
fn cast_share(view: CastSphere, p: Sg) -> f32 {
    let gap = cast_cos_gap(view, p.direction);
    let share = sphere_share(view, p, gap);
    if clears_sphere(view, gap) || share < CAST_SKIP_SHARE {
        return -1.0;
    }
    return share;
}

// The most light lobe `g`, of irradiance `e` (E_k) at the point, can lose
// there: e × the sphere's `share`, and for a lobe shadowed through the
// SSDF (`ssdf_lobe`) no more than its light over the cone where the
// cone's points resolve it (runtime.rs cast_shadow_factor_within's bound).
fn cast_bound(view: CastSphere, cone: ptr<function, CastCone>, g: Sg, e: vec3<f32>, share: f32, ssdf_lobe: bool) -> vec3<f32> {
    let most = e * share;
    if ssdf_lobe && !view.inside && cone_resolves(cone, g) {
        return min(most, cone_blockable(cone, g));
    }
    return most;
}

// Lobe k of the light as stored: as the object's centre sees it (a local
// light's, the last pc.local_count lobes, is taken from each point
// instead: cast_local_lobe).
fn cast_stored_lobe(k: u32) -> Sg {
    return sg_unpack(light_lobes[2u * k], light_lobes[2u * k + 1u]);
}

// Whether the object can block under CAST_TOLERANCE of the light `total`
// when it can block at most `most`.
fn cast_within_tolerance(most: vec3<f32>, total: vec3<f32>) -> bool {
    let reach = most / max(total, vec3<f32>(1e-30));
    return !(max(reach.x, max(reach.y, reach.z)) >= CAST_TOLERANCE);
}

// `radiance`: the field's colour at x; π × it floors the irradiance the
// blocked light is taken from (an albedo ≤ 1 surface showing L receives at
// least πL; runtime.rs cast_shadow_factor).
// The first light's bound at x: its irradiance without the local lights
// (`den`) and the most the object can block of all of it (`most`, each
// lobe's cast_bound; a local light's whole sphere's).
struct CastFirstBound {
    den: vec3<f32>,
    most: vec3<f32>,
}

fn cast_first_local() -> u32 {
    let m = pc.light_count;
    return m - min(min(pc.local_count, pc.direct_lobes), m);
}

fn cast_first_direct() -> u32 {
    return pc.light_count - min(pc.direct_lobes, pc.light_count);
}

// The lobes are taken in three loops, the fitted, the direct and the
// local lights', in the order of one loop over them all: on lavapipe the
// mere presence of the direct lobes' rays and the local lights' march in
// a loop over every lobe costs each lobe's turn (the shading pass lost 27
// ms of 99 to it on DOG at 1280 × 720; docs/benchmarks.md, issue 26's
// eighth pass).
fn cast_first_bound(x: vec3<f32>, n: vec3<f32>, view: CastSphere, cone: ptr<function, CastCone>) -> CastFirstBound {
    let cosine = sg_clamped_cosine(n);
    let first_direct = cast_first_direct();
    let first_local = cast_first_local();
    var b = CastFirstBound(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var k = 0u; k < first_local; k++) {
        let g = cast_stored_lobe(k);
        let e = sg_diffuse_irradiance(g, n);
        b.den += e;
        let share = cast_share(view, sg_product(g, cosine));
        if share >= 0.0 {
            b.most += cast_bound(view, cone, g, e, share, k < first_direct);
        }
    }
    for (var k = first_local; k < pc.light_count; k++) {
        let g = cast_local_lobe(x, k - first_local);
        let share = cast_share(view, sg_product(g, cosine));
        if share >= 0.0 {
            b.most += cast_bound(view, cone, g, sg_diffuse_irradiance(g, n), share, false);
        }
    }
    return b;
}

fn cast_factor(x: vec3<f32>, n: vec3<f32>, radiance: vec3<f32>) -> vec3<f32> {
    let cosine = sg_clamped_cosine(n);
    let m = pc.light_count;
    let first_direct = cast_first_direct();
    let first_local = cast_first_local();
    let view = cast_sphere(x);
    var cone: CastCone;
    if !view.inside {
        cone = cast_cone(view, n);
    }
    // First the irradiance, and the most the object can block of it (each
    // lobe's bound, cast_bound): where that is under CAST_TOLERANCE of the
    // light, ρ = 1 without the SSDF or any ray. A local light's light at x
    // needs a ray through the field: the test is first taken without it (a
    // lower bound, floored at π L) against the local lights' whole
    // spheres' bounds (an upper one), then again with it.
    let first = cast_first_bound(x, n, view, &cone);
    var den = first.den;
    let floor = SG_PI * radiance;
    if cast_within_tolerance(first.most, max(den, floor)) {
        return vec3<f32>(1.0);
    }
    // Less the least light the object sends back (cast_bounce_net).
    let back = cast_bounce_parts(x, n);
    let most = cast_bounce_net(back, first.most, max(den, floor));
    if cast_within_tolerance(most, max(den, floor)) {
        return vec3<f32>(1.0);
    }
    var arrivals: array<vec2<f32>, MAX_LOCAL_LIGHTS>;
    if first_local < m {
        for (var k = first_local; k < m; k++) {
            let a = cast_local_arrival(x, n, k - first_local);
            arrivals[k - first_local] = a;
            den += sg_diffuse_irradiance(cast_local_lobe(x, k - first_local), n) * a.x * a.y;
        }
        if cast_within_tolerance(most, max(den, floor)) {
            return vec3<f32>(1.0);
        }
    }
    var blocked = vec3<f32>(0.0);
    // The fitted lobes the object can block (cast_share ≥ 0), as bits of
    // `low` (lobes 0–31) and `high` (32–63; the fit has at most 64, a
    // const assertion in passes/src/shadow/cast.rs). Only those are read
    // through the SSDF, in the same order as one loop over every lobe
    // would take them. lavapipe runs a branch's body for every invocation
    // of a group of eight, masked: a lobe skipped by a branch costs its
    // SSDF read all the same, a loop over the set bits costs the turns of
    // the group's point with the most (docs/benchmarks.md, issue 26's
    // twentieth pass).
    var low = 0u;
    var high = 0u;
    for (var k = 0u; k < first_direct; k++) {
        if cast_share(view, sg_product(cast_stored_lobe(k), cosine)) >= 0.0 {
            low |= select(0u, 1u << k, k < 32u);
            high |= select(0u, 1u << (k - 32u), k >= 32u);
        }
    }
    if (low | high) != 0u {
        ssdf_prepare(ssdf_to_object_point(x));
    }
    loop {
        var k = 0u;
        if low != 0u {
            k = firstTrailingBit(low);
            low &= low - 1u;
        } else if high != 0u {
            k = 32u + firstTrailingBit(high);
            high &= high - 1u;
        } else {
            break;
        }
        let g = cast_stored_lobe(k);
        let p = sg_product(g, cosine);
        let share = cast_share(view, p);
        let e = sg_diffuse_irradiance(g, n);
        let q = fh_fraction(ssdf_value(ssdf_to_object_dir(p.direction)), p.sharpness);
        blocked += min(e * (1.0 - q), cast_bound(view, &cone, g, e, share, true));
    }
    for (var k = first_direct; k < first_local; k++) {
        let g = cast_stored_lobe(k);
        if cast_share(view, sg_product(g, cosine)) < 0.0 {
            continue;
        }
        blocked += sg_diffuse_irradiance(g, n) * (1.0 - cast_direct_visibility(x, k - first_direct, pc.direct_rays));
    }
    for (var k = first_local; k < m; k++) {
        let g = cast_local_lobe(x, k - first_local);
        if cast_share(view, sg_product(g, cosine)) < 0.0 {
            continue;
        }
        let a = arrivals[k - first_local];
        blocked += sg_diffuse_irradiance(g, n) * a.x * (a.y - cast_local_clear(x, n, k - first_local));
    }
    let total = max(den, floor);
    if max(blocked.x, max(blocked.y, blocked.z)) > 0.0 {
        // The bounce, its light from below x's plane at x's own ratio
        // before it (runtime.rs cast_shadow_factor: the field the object's
        // face sees there is shadowed about as deeply as x).
        let ratio = clamp(vec3<f32>(1.0) - blocked / max(total, vec3<f32>(1e-30)), vec3<f32>(0.0), vec3<f32>(1.0));
        blocked = max(blocked - cast_bounce_at(back, ratio), vec3<f32>(0.0));
    }
    return select(vec3<f32>(1.0), vec3<f32>(1.0) - blocked / max(total, vec3<f32>(1e-30)), total > vec3<f32>(0.0));
}

// The field's normal −∇σ at x by central differences, or zero where the
// density is flat (empty space, inside a homogeneous medium).
fn field_normal_at(x: vec3<f32>) -> vec3<f32> {
    let h = pc.normal_step;
    let g = vec3<f32>(
        density(x + vec3<f32>(h, 0.0, 0.0)) - density(x - vec3<f32>(h, 0.0, 0.0)),
        density(x + vec3<f32>(0.0, h, 0.0)) - density(x - vec3<f32>(0.0, h, 0.0)),
        density(x + vec3<f32>(0.0, 0.0, h)) - density(x - vec3<f32>(0.0, 0.0, h)),
    );
    if length(g) <= 1e-12 {
        return vec3<f32>(0.0);
    }
    return -normalize(g);
}

const CAST_NO_OBJECT: f32 = 3.0e38;

// The field's point at pixel `pixel` (ray direction `dir`): its expected
// depth D̂/Ô.
fn pixel_point(pixel: vec2<i32>, dir: vec3<f32>, opacity: f32) -> vec3<f32> {
    return pc.camera.origin + dir * (textureLoad(field_depth, pixel, 0).r / opacity);
}

// Whether pixel_factor(pixel) is 1 by its first tests alone: no field
// there, or a point on a surface where the object can block under
// CAST_TOLERANCE of the light without the local lights', or does once the
// least light it sends back is taken off (cast_factor's first two tests).
// False where the rest of it must decide, the point off any surface
// (marched again) included.
fn pixel_unshadowed(pixel: vec2<i32>) -> bool {
    let colour = textureLoad(field_colour, pixel, 0);
    let opacity = colour.a;
    if opacity <= 1e-4 {
        return true;
    }
    let dir = camera_ray_dir(pc.camera, vec2<f32>(pixel) + vec2<f32>(0.5));
    let x = pixel_point(pixel, dir, opacity);
    let n = field_normal_at(x);
    if all(n == vec3<f32>(0.0)) {
        return false;
    }
    let view = cast_sphere(x);
    var cone: CastCone;
    if !view.inside {
        cone = cast_cone(view, n);
    }
    let first = cast_first_bound(x, n, view, &cone);
    let total = max(first.den, SG_PI * colour.rgb / opacity);
    if cast_within_tolerance(first.most, total) {
        return true;
    }
    return cast_within_tolerance(cast_bounce_net(cast_bounce_parts(x, n), first.most, total), total);
}

// ρ at pixel `pixel` (1 where the field is empty or flat). The shadow is
// taken at the field's expected depth D̂/Ô; where that point lies off any
// surface (the pixel sees a table through glass, and D̂/Ô falls between
// them), at the depth where the ray's opacity reached 1/2 instead, and
// only the share of the pixel's colour gathered from that surface on is
// shadowed: the glass's own light is not (passes/src/shadow/runtime.rs
// shadow_point).
fn pixel_factor(pixel: vec2<i32>) -> vec3<f32> {
    let colour = textureLoad(field_colour, pixel, 0);
    let opacity = colour.a;
    if opacity <= 1e-4 {
        return vec3<f32>(1.0);
    }
    let dir = camera_ray_dir(pc.camera, vec2<f32>(pixel) + vec2<f32>(0.5));
    let x = pixel_point(pixel, dir, opacity);
    let n = field_normal_at(x);
    if any(n != vec3<f32>(0.0)) {
        return cast_factor(x, n, colour.rgb / opacity);
    }
    let half = march_ray(pc.camera.origin, dir, CAST_NO_OBJECT, pc.march_step, pc.march_termination).half_depth;
    if half < 0.0 {
        return vec3<f32>(1.0);
    }
    let behind_x = pc.camera.origin + dir * half;
    let behind_n = field_normal_at(behind_x);
    if all(behind_n == vec3<f32>(0.0)) {
        return vec3<f32>(1.0);
    }
    let rho = cast_factor(behind_x, behind_n, colour.rgb / opacity);
    // Unshadowed there, ρ is 1 whatever share of the colour is shadowed,
    // and the second march is left out.
    if all(rho == vec3<f32>(1.0)) {
        return rho;
    }
    // What lies in front of the surface: up to two normal steps before it
    // (its density rises over about one).
    let front = march_ray(pc.camera.origin, dir, max(half - 2.0 * pc.normal_step, 0.0), pc.march_step, pc.march_termination).colour;
    let share = clamp((colour.rgb - front) / max(colour.rgb, vec3<f32>(1e-30)), vec3<f32>(0.0), vec3<f32>(1.0));
    return vec3<f32>(1.0) - (vec3<f32>(1.0) - rho) * share;
}

// The full-resolution pixel block `id` is taken at (upsample.rs
// source_pixel).
fn cast_source(id: vec2<u32>) -> vec2<i32> {
    let p = min(id * pc.scale + vec2<u32>(pc.scale / 2u), vec2<u32>(pc.camera.width - 1u, pc.camera.height - 1u));
    return vec2<i32>(p);
}

// The depth along the ray at full-resolution pixel p, or −1 where the
// field is empty: what shadow-upsample weighs each block by (upsample.wgsl
// upsample_depth, the same expression), kept in the alpha of the image at
// the cast scale so that the upsampling reads one texel a corner.
fn cast_source_depth(p: vec2<i32>) -> f32 {
    let o = textureLoad(field_colour, p, 0).a;
    if o <= 1e-4 {
        return -1.0;
    }
    return textureLoad(field_depth, p, 0).r / o;
}

// The width of the image at pc.scale (upsample.rs low_size).
fn cast_low_width() -> u32 {
    return (pc.camera.width + pc.scale - 1u) / pc.scale;
}

// The including shader's `main_listed` and `main_listed_chained` call this
// (one invocation per listed pixel, in workgroups of REFINE_WORKGROUP,
// dispatched indirectly): at the i-th listed pixel of the image at pc.scale
// (the pixels `cast_classify` listed, or at pc.scale 1 those
// shadow-upsample flagged), ρ taken in full, in place in `refined`;
// `chained` multiplies what is there (the previous objects' ρ).
fn refine_listed(i: u32, chained: bool) {
    if i >= refine_count {
        return;
    }
    let p = refine_list[i];
    let width = cast_low_width();
    let at = vec2<u32>(p % width, p / width);
    var rho = pixel_factor(cast_source(at));
    let here = textureLoad(refined, vec2<i32>(at));
    if chained {
        rho *= here.rgb;
    }
    // The alpha stays: the source pixel's depth at the cast scale.
    textureStore(refined, vec2<i32>(at), vec4<f32>(rho, here.a));
}

// Whether invocation `id` of a classification lies off the image.
fn cast_outside(id: vec3<u32>) -> bool {
    return camera_outside(pc.camera, id.xy * pc.scale);
}

// The previous object's ρ at invocation `id` (main_classify_chained; a
// function of its own: `main_classify` binds no previous image).
fn cast_previous(id: vec3<u32>) -> vec3<f32> {
    return textureLoad(previous, vec2<i32>(id.xy), 0).rgb;
}

// The including shader's `main_classify` and `main_classify_chained` call
// this, over the image at pc.scale: where the first test leaves the pixel
// unshadowed (pixel_unshadowed), ρ = 1 times `previous` (the previous
// object's ρ there, or 1) and nothing more; elsewhere that is written too,
// and the pixel is listed for `main_listed*`, which takes ρ in full there. Two stages, so
// that the shadow's own code runs only at the pixels it can darken:
// lavapipe gives every invocation of a shader that large a fixed cost,
// even one that returns at once (docs/benchmarks.md, issue 26's fifth
// pass).
fn cast_classify(id: vec3<u32>, previous_rho: vec3<f32>) {
    let source = cast_source(id.xy);
    textureStore(out_shadow, vec2<i32>(id.xy), vec4<f32>(previous_rho, cast_source_depth(source)));
    if pixel_unshadowed(source) {
        return;
    }
    let width = cast_low_width();
    let i = atomicAdd(&cast_count, 1u);
    cast_list[i] = id.y * width + id.x;
    if i % REFINE_WORKGROUP == 0u {
        atomicAdd(&cast_args[0], 1u);
    }
}
