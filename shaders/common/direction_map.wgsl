// Direction maps of probe images, mirroring passes/src/probe/direction_map.rs:
// equirect (2n × n, +Y up, φ = atan2(z, x) across, θ from +Y down) or, with
// the OCTAHEDRAL bool const, the octahedral map (n × n, (u, v) ∈ [−1, 1]² →
// (u, 1 − |u| − |v|, v), lower half folded over the corners).
// Needs: a bool const `OCTAHEDRAL`.

const DM_PI: f32 = 3.14159265358979;

fn dm_octahedron_point(u: f32, v: f32) -> vec3<f32> {
    let y = 1.0 - abs(u) - abs(v);
    if y >= 0.0 {
        return vec3<f32>(u, y, v);
    }
    // sign() of 0 is 0 in WGSL but the fold never sees u or v at exactly 0
    // (texel centres of the lower half have |u| + |v| > 1).
    return vec3<f32>((1.0 - abs(v)) * sign(u), y, (1.0 - abs(u)) * sign(v));
}

// Unit direction through the centre of texel `t` of a map of `size` texels.
fn dm_direction(t: vec2<u32>, size: vec2<u32>) -> vec3<f32> {
    let uv = (vec2<f32>(t) + vec2<f32>(0.5)) / vec2<f32>(size);
    if OCTAHEDRAL {
        return normalize(dm_octahedron_point(2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0));
    }
    let phi = 2.0 * DM_PI * uv.x;
    let theta = DM_PI * uv.y;
    return vec3<f32>(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
}

// Solid angle of texel `t` (exact for equirect, midpoint rule on
// dω = du dv / |p|³ for the octahedral map).
fn dm_solid_angle(t: vec2<u32>, size: vec2<u32>) -> f32 {
    let s = vec2<f32>(size);
    if OCTAHEDRAL {
        let uv = 2.0 * (vec2<f32>(t) + vec2<f32>(0.5)) / s - vec2<f32>(1.0);
        let p = length(dm_octahedron_point(uv.x, uv.y));
        return 4.0 / (s.x * s.y) / (p * p * p);
    }
    let t0 = DM_PI * f32(t.y) / s.y;
    let t1 = DM_PI * (f32(t.y) + 1.0) / s.y;
    return 2.0 * DM_PI / s.x * (cos(t0) - cos(t1));
}
