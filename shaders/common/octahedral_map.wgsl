// The octahedral map of directions, mirroring passes/src/probe/direction_map.rs:
// (u, v) ∈ [−1, 1]² → (u, 1 − |u| − |v|, v), the lower half folded over the
// corners; its inverse; and its texels' wrap across the map's edges.
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
