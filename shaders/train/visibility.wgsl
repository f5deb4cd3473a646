// Each node's visibility over a set of rays: the largest rendering weight
// it takes in any of them, the sample's weight T·α times the node's
// trilinear weight at the sample, along the march's quadrature (with
// SKIP_EMPTY, as the field will be rendered). What pruning reads
// (passes/src/train/prune.rs, whose ray_visibility this mirrors; the loop
// is march/volume_march.wgsl's without the colour). Weights are positive,
// so their bits order as the floats do: an atomic max on the bits keeps
// the largest. Indexed by the node's place in `grid_nodes` (a sparse
// field's pool).

#include "common/ray_box.wgsl"
#include "field/grid.wgsl"

struct VisibilityPush {
    ray_count: u32,
    step: f32,
    termination: f32,
    pad: u32,
}

var<immediate> pc: VisibilityPush;
// Per ray: (origin, 0) then (unit direction, 0).
@group(0) @binding(3) var<storage, read> visibility_rays: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> visibility: array<atomic<u32>>;

// Raises node i's visibility to at least `value`.
fn raise(i: vec3<u32>, value: f32) {
    let n = field_node_index(i);
    if (FIELD_SPARSE && n == EMPTY_BRICK) || value <= 0.0 {
        return;
    }
    atomicMax(&visibility[n], bitcast<u32>(value));
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let r = id.x + 65535u * 64u * id.y;
    if r >= pc.ray_count {
        return;
    }
    let origin = visibility_rays[2u * r].xyz;
    let dir = visibility_rays[2u * r + 1u].xyz;
    let tb = ray_box(origin, dir, grid_info.bounds_min, grid_info.bounds_max);
    let t0 = tb.x;
    let t1 = tb.y;
    if tb.x > tb.y || t1 <= t0 {
        return;
    }
    var transmittance = 1.0;
    var k = 0u;
    loop {
        let a = t0 + f32(k) * pc.step;
        if a >= t1 {
            break;
        }
        let b = min(a + pc.step, t1);
        let t = 0.5 * (a + b);
        let x = origin + t * dir;
        if SKIP_EMPTY {
            let s = grid_empty_until(x, dir);
            if s >= 0.0 {
                k = max(k + 1u, u32(ceil((t + s - t0) / pc.step - 0.5)));
                continue;
            }
        }
        let sigma = grid_sample(x).w;
        let attenuation = exp(-sigma * (b - a));
        let w = transmittance * (1.0 - attenuation);
        if w > 0.0 {
            let cell = trilinear_cell(x, grid_info.bounds_min, grid_info.bounds_max, grid_info.resolution);
            if cell.inside {
                for (var c = 0u; c < 8u; c++) {
                    raise(cell.base + trilinear_corner(c), w * trilinear_weight(cell.f, c));
                }
            }
        }
        transmittance *= attenuation;
        if transmittance < pc.termination {
            break;
        }
        k += 1u;
    }
}
