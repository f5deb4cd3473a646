// S(d; x) from an object's compressed SSDF field, mirroring SsdfField::sample
// (passes/src/ssdf/field.rs): per pixel, ssdf_prepare(x) blends the
// coefficients of the 8 nodes around x (inside the grid) or takes the
// nearest node's (outside); then ssdf_value(d) reads the direction map
// bilinearly and, outside, applies the mode: 0 clamp, 1 infinity (π),
// 2 correct (turn towards the centre and shrink by the angular radii).
// Needs: read-only storage buffers `ssdf: SsdfObject`, `ssdf_rows` (per
// texel: mean, k basis values) and `ssdf_coefs` (per node: 1, k values),
// both array<vec4<f32>> in rows of ssdf_row_vec4s() vec4s zero-padded
// (passes/src/shadow/gpu.rs `gpu_rows`: a texel's value is the dot product
// of its row with the blended coefficients, read a vec4 at a time), and
// the frame's `objects: array<ObjectRecord>` (the object's pose, record
// `ssdf.object`); define SSDF_MAX_ROW_VEC4S (u32). The block is storage, not
// uniform, on purpose: Mesa 22.3's lavapipe recompiles (and leaks) a shader
// at every bind when branches and loop bounds depend on uniform values
// alone and inlining them halves the shader — this one did, ~1.2 MB and a
// JIT compile per frame.
#include "ssdf/angles.wgsl"
#include "common/octahedral_map.wgsl"
#include "object/record.wgsl"

struct SsdfObject {
    // Grid centre (object space) and bounding-sphere radius.
    grid: vec4<f32>,
    // Nodes per axis, direction map side, components, outside mode.
    dims: vec4<u32>,
    // The share of the sphere's silhouette the mesh fills times its albedo
    // (rgb; the cast shadow's bounce, shadow/bounce.wgsl), and the share
    // alone (w; the cast shadow's sphere_share).
    reflectance: vec4<f32>,
    // The object's record in `objects` (its pose).
    object: u32,
}

// The blended coefficients (1, c_1, …, c_k, 0, …).
var<private> ssdf_coef: array<vec4<f32>, SSDF_MAX_ROW_VEC4S>;
// 0 inside, 1 outside (nearest node), 2 outside in infinity mode.
var<private> ssdf_state: u32;
var<private> ssdf_x: vec3<f32>;
// Outside in the correct mode, what depends on the point alone: the unit
// directions to the grid's centre from it (cf) and from its nearest node
// (cb), the ratio of the sphere's angular radii seen from them, and the
// rotation taking cf to cb (its axis cf × cb and cosine).
var<private> ssdf_cf: vec3<f32>;
var<private> ssdf_cb: vec3<f32>;
var<private> ssdf_shrink: f32;

// The object's world-space bounding sphere (centre, radius).
fn ssdf_world_sphere() -> vec4<f32> {
    return objects[ssdf.object].sphere;
}

fn ssdf_to_object_point(x: vec3<f32>) -> vec3<f32> {
    let p = vec4<f32>(x, 1.0);
    let m = objects[ssdf.object].to_object;
    return vec3<f32>(dot(m[0], p), dot(m[1], p), dot(m[2], p));
}

fn ssdf_to_object_dir(d: vec3<f32>) -> vec3<f32> {
    let m = objects[ssdf.object].to_object;
    let v = vec3<f32>(dot(m[0].xyz, d), dot(m[1].xyz, d), dot(m[2].xyz, d));
    return normalize(v);
}

fn ssdf_spacing() -> f32 {
    return 3.0 * ssdf.grid.w / f32(ssdf.dims.x - 1u);
}

fn ssdf_node_position(n: vec3<u32>) -> vec3<f32> {
    return ssdf.grid.xyz - vec3<f32>(1.5 * ssdf.grid.w) + vec3<f32>(n) * ssdf_spacing();
}

fn ssdf_node_index(n: vec3<u32>) -> u32 {
    let s = ssdf.dims.x;
    return n.x + s * (n.y + s * n.z);
}

// vec4s a row of `ssdf_rows` and of `ssdf_coefs` holds (gpu.rs
// row_vec4s: the k + 1 values padded to a whole vec4).
fn ssdf_row_vec4s() -> u32 {
    return (ssdf.dims.z + 4u) / 4u;
}

// Fills the coefficients for object-space point x.
fn ssdf_prepare(x: vec3<f32>) {
    let m = ssdf_row_vec4s();
    let top = f32(ssdf.dims.x - 1u);
    let l = (x - ssdf.grid.xyz + vec3<f32>(1.5 * ssdf.grid.w)) / ssdf_spacing();
    ssdf_x = x;
    for (var j = 0u; j < m; j++) {
        ssdf_coef[j] = vec4<f32>(0.0);
    }
    if all(l >= vec3<f32>(0.0)) && all(l <= vec3<f32>(top)) {
        ssdf_state = 0u;
        let base = max(min(floor(l), vec3<f32>(top - 1.0)), vec3<f32>(0.0));
        let f = l - base;
        let b = vec3<u32>(base);
        for (var corner = 0u; corner < 8u; corner++) {
            let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, corner >> 2u);
            let w3 = select(vec3<f32>(1.0) - f, f, o == vec3<u32>(1u));
            let w = w3.x * w3.y * w3.z;
            let node = ssdf_node_index(b + o);
            for (var j = 0u; j < m; j++) {
                ssdf_coef[j] += w * ssdf_coefs[node * m + j];
            }
        }
        // The mean's weight: the corners' weights sum to 1 up to rounding.
        ssdf_coef[0].x = 1.0;
        return;
    }
    if ssdf.dims.w == 1u {
        ssdf_state = 2u;
        return;
    }
    ssdf_state = 1u;
    let n = vec3<u32>(clamp(round(l), vec3<f32>(0.0), vec3<f32>(top)));
    let xb = ssdf_node_position(n);
    let o = ssdf.grid.xyz;
    let r = ssdf.grid.w;
    let df = length(o - x);
    let db = length(o - xb);
    ssdf_cf = (o - x) / df;
    ssdf_cb = (o - xb) / db;
    ssdf_shrink = asin(min(r / df, 1.0)) / asin(min(r / db, 1.0));
    let node = ssdf_node_index(n);
    for (var j = 0u; j < m; j++) {
        ssdf_coef[j] = ssdf_coefs[node * m + j];
    }
}

// The map's value along d, bilinear over its four nearest texels: their
// rows blended first, then one dot product with the coefficients.
fn ssdf_direction_value(d: vec3<f32>) -> f32 {
    let n = i32(ssdf.dims.y);
    let m = ssdf_row_vec4s();
    // The map's edges fold onto themselves (SsdfField's wrap_octahedral).
    let texels = octahedral_bilinear(d, n);
    let r00 = texels.texels.x * m;
    let r10 = texels.texels.y * m;
    let r01 = texels.texels.z * m;
    let r11 = texels.texels.w * m;
    let w = texels.weights;
    var s = 0.0;
    for (var j = 0u; j < m; j++) {
        let row = w.x * ssdf_rows[r00 + j] + w.y * ssdf_rows[r10 + j] + w.z * ssdf_rows[r01 + j] + w.w * ssdf_rows[r11 + j];
        s += dot(ssdf_coef[j], row);
    }
    return s;
}

// S along unit object-space direction d from the prepared point. The map
// is read once, along d or, for a point beyond the grid, along d turned
// to the nearest node's view, and the cases are chosen by select: lavapipe
// runs both sides of a branch for a group of invocations, and a second
// read in the other branch cost the self-shadowed shading 2–5 ms of its
// 60–70 on DOG at 1280 × 720 (docs/benchmarks.md, issue 26's twentieth
// pass). A point the SSDF leaves unshadowed (state 2, π) reads along d,
// which is always a direction the map can be read along, and drops it.
fn ssdf_value(d: vec3<f32>) -> f32 {
    let beyond = ssdf_state == 1u && ssdf.dims.w != 0u;
    let cf = ssdf_cf;
    let cb = ssdf_cb;
    let shrink = ssdf_shrink;
    let alpha = ssdf_angle_between(d, cf);
    // The smallest rotation taking cf to cb, applied to d.
    let axis = cross(cf, cb);
    let c = dot(cf, cb);
    var db_dir = -d;
    if c > -1.0 + 1e-6 {
        db_dir = d * c + cross(axis, d) + axis * (dot(axis, d) / (1.0 + c));
    }
    let v = ssdf_direction_value(select(d, normalize(db_dir), beyond));
    return select(select(v, alpha - shrink * (alpha - v), beyond), SSDF_PI, ssdf_state == 2u);
}
