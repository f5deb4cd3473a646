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
// A point of normal n scales its fitted lobes' diffuse light by
//   g = Σ_r max(0, n·d_r) (field light)_r / Σ_r max(0, n·d_r) L_fit(d_r),
// per colour channel: the same rays in numerator and denominator, so where
// the field sends what the lobes say the gain is exactly 1 whatever the
// rays' count. The tile keeps both sums at the 16² normals of an
// octahedral map (`field_light_tiles`, written by the gain pass), and a
// pixel blends the sums of the four tiles whose centres surround it, read
// bilinearly at its own normal, each tile weighed bilinearly in the image
// and down where its pick lies off the pixel's tangent plane
// (field_light_blended_gain): no steps at the tiles' edges. Mirrors
// passes/src/shade/field_light.rs.
// Needs: shade/shade_body.wgsl, shade/self_shadow_ssdf.wgsl, the hook
// shading_fitted_count() of brdf/sg_shading.wgsl, field/grid.wgsl,
// march/volume_march.wgsl, lighting/local_light.wgsl, shadow/direct_rays.wgsl
// (DIRECT_RAY_OFFSET), the binding `local_lights`.
#include "common/fibonacci.wgsl"
#include "common/octahedral_map.wgsl"

// field_light.rs MAX_SIDE²: the tile's rays.
const FIELD_LIGHT_MAX_RAYS: u32 = 256u;
// field_light.rs GAIN_MAX: a bound, not a model (a field that sends more
// than this many times the lobes' light onto a plane is not their error).
const FIELD_LIGHT_GAIN_MAX: f32 = 16.0;
const FIELD_LIGHT_NO_PICK: u32 = 0xffffffffu;
// "No object along the ray": the rays see the whole field.
const FIELD_LIGHT_NO_OBJECT: f32 = 3.0e38;
// field_light.rs TABLE_SIDE (its 256 normals four to each of the gain
// pass's 64 invocations), TABLE_STRIDE and PLANE_WEIGHT_MIN.
const FIELD_LIGHT_TABLE_SIDE: u32 = 16u;
const FIELD_LIGHT_TABLE_STRIDE: u32 = 513u;
const FIELD_LIGHT_PLANE_WEIGHT_MIN: f32 = 1e-4;
// field_light.rs FOOTPRINT_MIN, at f32's least normal number.
const FIELD_LIGHT_FOOTPRINT_MIN: f32 = 1.2e-38;

// Each tile's table, field_light.rs TileTable: the pick's point (w 1, or
// 0 where the tile picked none), then at each normal the field's sum and
// the lobes' sum: the object's own, row by row over its region of
// pc.field_tiles (columns | rows << 16) tiles from tile pc.field_origin
// (x | y << 16).
@group(0) @binding(25) var<storage, read_write> field_light_tiles: array<vec4<f32>>;

// The pick: its squared doubled offset from the tile's centre above its
// index in the tile (row-major, 12 bits: tiles of up to 64 pixels a side,
// field_light.rs MAX_TILE_SCALE 4 takes 32), so that the least is
// field_light.rs tile_pick's.
var<workgroup> field_light_pick: atomic<u32>;
var<workgroup> field_light_rays: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;
var<workgroup> field_light_lobes: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;
var<workgroup> field_light_dirs: array<vec4<f32>, FIELD_LIGHT_MAX_RAYS>;
// The pick's surface point.
var<workgroup> field_light_point: vec3<f32>;

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
        if local_index == 0u {
            field_light_point = x;
        }
        for (var k = local_index; k < count; k += 64u) {
            let d = fibonacci_axis(k, count);
            field_light_rays[k] = vec4<f32>(field_light_along(origin, d), 0.0);
            field_light_lobes[k] = vec4<f32>(field_light_fitted(d), 0.0);
            field_light_dirs[k] = vec4<f32>(d, 0.0);
        }
    }
    workgroupBarrier();
}

// The first vec4 of tile `tile`'s table (tile in the field light's tiles
// of the image, inside the object's region), or none (0xffffffff) beyond
// the region.
fn field_light_table(tile: vec2<i32>) -> u32 {
    let origin = vec2<i32>(i32(pc.field_origin & 0xffffu), i32(pc.field_origin >> 16u));
    let size = vec2<i32>(i32(pc.field_tiles & 0xffffu), i32(pc.field_tiles >> 16u));
    let t = tile - origin;
    if any(t < vec2<i32>(0)) || any(t >= size) {
        return 0xffffffffu;
    }
    return u32(t.y * size.x + t.x) * FIELD_LIGHT_TABLE_STRIDE;
}

// The normal of entry j of a table: the centre of its texel of the
// octahedral map (field_light.rs table_normal).
fn field_light_table_normal(j: u32) -> vec3<f32> {
    let n = FIELD_LIGHT_TABLE_SIDE;
    let uv = (vec2<f32>(f32(j % n), f32(j / n)) + vec2<f32>(0.5)) / f32(n);
    return normalize(dm_octahedron_point(2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0));
}

// Writes tile `group`'s table from the rays `field_light_gather` left in
// workgroup memory; every invocation of the workgroup calls it.
fn field_light_write_table(local_index: u32, group: vec3<u32>) {
    let base = field_light_table(vec2<i32>(group.xy));
    if pc.field_side == 0u || base == 0xffffffffu {
        return;
    }
    let picked = atomicLoad(&field_light_pick) != FIELD_LIGHT_NO_PICK;
    if local_index == 0u {
        field_light_tiles[base] = select(vec4<f32>(0.0), vec4<f32>(field_light_point, 1.0), picked);
    }
    if !picked {
        return;
    }
    // Each invocation takes four normals, j = local_index + 64 q, and reads
    // each ray once for all four: the ray's loads from workgroup memory,
    // not the products, are what a loop over the rays costs on lavapipe.
    let count = field_light_ray_count();
    var normals: mat4x3<f32>;
    for (var q = 0u; q < 4u; q++) {
        normals[q] = field_light_table_normal(local_index + 64u * q);
    }
    var field = mat4x3<f32>();
    var lobes = mat4x3<f32>();
    for (var r = 0u; r < count; r++) {
        let d = field_light_dirs[r].xyz;
        let f = field_light_rays[r].xyz;
        let l = field_light_lobes[r].xyz;
        let w = max(d * normals, vec4<f32>(0.0));
        field += mat4x3<f32>(w.x * f, w.y * f, w.z * f, w.w * f);
        lobes += mat4x3<f32>(w.x * l, w.y * l, w.z * l, w.w * l);
    }
    for (var q = 0u; q < 4u; q++) {
        let j = local_index + 64u * q;
        field_light_tiles[base + 1u + 2u * j] = vec4<f32>(field[q], 0.0);
        field_light_tiles[base + 2u + 2u * j] = vec4<f32>(lobes[q], 0.0);
    }
}

// A table's two sums at unit normal n, bilinear between its four nearest
// normals (field_light.rs TileTable::sums): field in [0], lobes in [1].
fn field_light_table_sums(base: u32, n: vec3<f32>) -> array<vec3<f32>, 2> {
    let texels = octahedral_bilinear(n, i32(FIELD_LIGHT_TABLE_SIDE));
    var field = vec3<f32>(0.0);
    var lobes = vec3<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let w = texels.weights[k];
        let j = texels.texels[k];
        field += w * field_light_tiles[base + 1u + 2u * j].xyz;
        lobes += w * field_light_tiles[base + 2u + 2u * j].xyz;
    }
    return array<vec3<f32>, 2>(field, lobes);
}

// The gain of a field sum over a lobes' sum (field_light.rs gain_of_sums).
fn field_light_gain_of_sums(field: vec3<f32>, lobes: vec3<f32>) -> vec3<f32> {
    let ok = lobes > vec3<f32>(0.0);
    let gain = select(vec3<f32>(1.0), field / select(vec3<f32>(1.0), lobes, ok), ok);
    return clamp(gain, vec3<f32>(0.0), vec3<f32>(FIELD_LIGHT_GAIN_MAX));
}

// The gain on the fitted lobes' diffuse light at pixel `pixel` of surface
// point x and unit normal n, blended from the tables of the four tiles
// around it (field_light.rs blended_gain); 1 where the feature is off or
// no tile around it picked a pixel.
fn field_light_blended_gain(pixel: vec2<u32>, x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    if pc.field_side == 0u {
        return vec3<f32>(1.0);
    }
    let side = f32(field_light_side());
    let centre = vec2<f32>(pixel) + vec2<f32>(0.5);
    // A tile's width on the surface there (field_light.rs tile_footprint).
    let chord = distance(camera_ray_dir(pc.camera, centre + vec2<f32>(side, 0.0)), camera_ray_dir(pc.camera, centre));
    let footprint = distance(x, pc.camera.origin) * chord;
    let u = centre / side - vec2<f32>(0.5);
    let b = floor(u);
    let f = u - b;
    var field = vec3<f32>(0.0);
    var lobes = vec3<f32>(0.0);
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let base = field_light_table(vec2<i32>(b) + o);
        if base == 0xffffffffu {
            continue;
        }
        let pick = field_light_tiles[base];
        if pick.w == 0.0 {
            continue;
        }
        let h = dot(n, pick.xyz - x) / max(footprint, FIELD_LIGHT_FOOTPRINT_MIN);
        let plane = max(exp(-min(h * h, 80.0)), FIELD_LIGHT_PLANE_WEIGHT_MIN);
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1) * plane;
        let sums = field_light_table_sums(base, n);
        field += w * sums[0];
        lobes += w * sums[1];
    }
    return field_light_gain_of_sums(field, lobes);
}
