// The octahedral map of directions, mirroring passes/src/probe/direction_map.rs:
// (u, v) ∈ [−1, 1]² → (u, 1 − |u| − |v|, v), the lower half folded over the
// corners; its inverse; its texels' wrap across the map's edges; and the
// bilinear read's texels and weights.
#include "common/octahedral_wrap.wgsl"

// The point of the octahedron |x| + |y| + |z| = 1 at (u, v) ∈ [−1, 1]²
// (direction_map.rs octahedron_point).
fn dm_octahedron_point(u: f32, v: f32) -> vec3<f32> {
    let y = 1.0 - abs(u) - abs(v);
    if y >= 0.0 {
        return vec3<f32>(u, y, v);
    }
    // sign() of 0 is 0 in WGSL but the fold never sees u or v at exactly 0
    // (texel centres and sub-sample cell centres of the lower half have
    // |u| + |v| > 1 and never lie on an axis).
    return vec3<f32>((1.0 - abs(v)) * sign(u), y, (1.0 - abs(u)) * sign(v));
}

// Map coordinates in [0, 1]² of unit d (direction_map.rs octahedral_uv).
fn octahedral_uv(d: vec3<f32>) -> vec2<f32> {
    let p = d / (abs(d.x) + abs(d.y) + abs(d.z));
    var a = p.x;
    var b = p.z;
    if p.y < 0.0 {
        let sa = select(-1.0, 1.0, a >= 0.0);
        let sb = select(-1.0, 1.0, b >= 0.0);
        let fa = (1.0 - abs(b)) * sa;
        let fb = (1.0 - abs(a)) * sb;
        a = fa;
        b = fb;
    }
    return vec2<f32>(0.5 * (a + 1.0), 0.5 * (b + 1.0));
}

// The four texels of an n × n octahedral map around unit d (indices
// y · n + x, wrapped across the map's edges) and their bilinear weights,
// in the order (0, 0), (1, 0), (0, 1), (1, 1) from the lower corner
// (direction_map.rs octahedral_bilinear).
struct OctBilinear {
    texels: vec4<u32>,
    weights: vec4<f32>,
}

fn octahedral_bilinear(d: vec3<f32>, n: i32) -> OctBilinear {
    let p = octahedral_uv(d) * f32(n) - vec2<f32>(0.5);
    let b = floor(p);
    let f = p - b;
    let t = vec2<i32>(b);
    let t00 = oct_wrap(t, n);
    let t10 = oct_wrap(t + vec2<i32>(1, 0), n);
    let t01 = oct_wrap(t + vec2<i32>(0, 1), n);
    let t11 = oct_wrap(t + vec2<i32>(1, 1), n);
    let texels = vec4<u32>(u32(t00.y * n + t00.x), u32(t10.y * n + t10.x), u32(t01.y * n + t01.x), u32(t11.y * n + t11.x));
    let weights = vec4<f32>((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    return OctBilinear(texels, weights);
}
