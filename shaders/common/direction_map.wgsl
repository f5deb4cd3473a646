// Direction maps of probe images, mirroring passes/src/probe/direction_map.rs:
// equirect (2n × n, +Y up, φ = atan2(z, x) across, θ from +Y down) or, with
// the OCTAHEDRAL bool const, the octahedral map (n × n, (u, v) ∈ [−1, 1]² →
// (u, 1 − |u| − |v|, v), lower half folded over the corners).
// Needs: a bool const `OCTAHEDRAL`.
#include "common/octahedral_map.wgsl"

const DM_PI: f32 = 3.14159265358979;

// Unit direction at map coordinates `uv` ∈ [0, 1]² (xyz) and the solid
// angle per unit of map area there, dω/(du dv) (w): sin θ · 2π² for
// equirect, 4/|p|³ for the octahedral map.
fn dm_direction_density(uv: vec2<f32>) -> vec4<f32> {
    if OCTAHEDRAL {
        let p = dm_octahedron_point(2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0);
        let len = length(p);
        return vec4<f32>(p / len, 4.0 / (len * len * len));
    }
    let phi = 2.0 * DM_PI * uv.x;
    let theta = DM_PI * uv.y;
    let d = vec3<f32>(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    return vec4<f32>(d, 2.0 * DM_PI * DM_PI * sin(theta));
}

// Map coordinates of sub-sample `ij` of texel `t` when each texel is split
// into `side` × `side` cells: the cell's centre.
fn dm_subsample_uv(t: vec2<u32>, ij: vec2<u32>, side: u32, size: vec2<u32>) -> vec2<f32> {
    return (vec2<f32>(t) + (vec2<f32>(ij) + vec2<f32>(0.5)) / f32(side)) / vec2<f32>(size);
}

// Unit direction through the centre of texel `t` of a map of `size` texels.
fn dm_direction(t: vec2<u32>, size: vec2<u32>) -> vec3<f32> {
    return dm_direction_density(dm_subsample_uv(t, vec2<u32>(0u), 1u, size)).xyz;
}

// Cells per texel side of the octahedral solid angle's midpoint rule.
const DM_SOLID_ANGLE_CELLS: u32 = 4u;

// Solid angle of texel `t` (exact for equirect; for the octahedral map the
// midpoint rule on dω = du dv / |p|³ over DM_SOLID_ANGLE_CELLS² cells).
fn dm_solid_angle(t: vec2<u32>, size: vec2<u32>) -> f32 {
    let s = vec2<f32>(size);
    if OCTAHEDRAL {
        var sum = 0.0;
        for (var k = 0u; k < DM_SOLID_ANGLE_CELLS * DM_SOLID_ANGLE_CELLS; k++) {
            let ij = vec2<u32>(k % DM_SOLID_ANGLE_CELLS, k / DM_SOLID_ANGLE_CELLS);
            sum += dm_direction_density(dm_subsample_uv(t, ij, DM_SOLID_ANGLE_CELLS, size)).w;
        }
        return sum / f32(DM_SOLID_ANGLE_CELLS * DM_SOLID_ANGLE_CELLS) / (s.x * s.y);
    }
    let t0 = DM_PI * f32(t.y) / s.y;
    let t1 = DM_PI * (f32(t.y) + 1.0) / s.y;
    return 2.0 * DM_PI / s.x * (cos(t0) - cos(t1));
}
