// Total variation: each node's gradient of the squared differences to its
// six neighbours, Σ_nb (v − v_nb) per channel, weighted per channel group
// (colour, density), a difference d pulled by d / √(1 + (d·inv)²) with the
// group's own inv (a Charbonnier penalty: squared below 1/inv, its size
// beyond; inv 0: squared everywhere), and the density's sparsity prior (σ₊ / (1 +
// (σ₊·inv)²) with its own edge's inv, weighted), into the gradient buffer Adam's step left empty;
// train/descend.wgsl then takes one plain step along it. A sparse grid's
// nodes are its pool's, a dropped brick's neighbours zero (held so).
// Mirrors passes/src/train/tv.rs tv_gradient.

struct TvPush {
    resolution: vec3<u32>,
    count: u32,
    colour_weight: f32,
    density_weight: f32,
    density_edge_inverse: f32,
    // The sparsity prior's weight λ (passes/src/train/tv.rs TvWeights).
    sparsity: f32,
    // Bricks per axis of a sparse grid (0: dense; field/bricks.wgsl).
    brick_dims: vec3<u32>,
    // 1 / the colour difference beyond which its penalty grows as its
    // size (0: squared everywhere; tv.rs TvWeights::colour_edge).
    colour_edge_inverse: f32,
    // 1 / the sparsity prior's edge, the density its pull is strongest
    // at (0: σ₊² everywhere; tv.rs TvWeights::sparsity_edge).
    sparsity_edge_inverse: f32,
    pad1: u32,
    pad2: u32,
    pad3: u32,
}

var<immediate> pc: TvPush;
@group(0) @binding(0) var<storage, read> params: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> grad: array<vec4<f32>>;
// A sparse grid's brick table, and each slot's index in it (one unused
// entry each for a dense grid).
@group(0) @binding(2) var<storage, read> bricks: array<u32>;
@group(0) @binding(3) var<storage, read> slot_bricks: array<u32>;

#include "field/bricks.wgsl"

// A neighbour's values: zero where a sparse grid dropped its brick.
fn neighbour(m: vec3<u32>) -> vec4<f32> {
    let r = pc.resolution;
    if pc.brick_dims.x == 0u {
        return params[m.x + r.x * (m.y + r.y * m.z)];
    }
    let slot = bricks[brick_table_index(m, pc.brick_dims)];
    if slot == EMPTY_BRICK {
        return vec4<f32>(0.0);
    }
    return params[brick_pool_index(slot, m)];
}

// Half the penalty's derivative for a difference d: d / √(1 + (d·inv)²)
// with the colour's inv for r, g, b and the density's for σ
// (passes/src/train/tv.rs edge_pull).
fn pull(d: vec4<f32>) -> vec4<f32> {
    let inv = vec4<f32>(vec3<f32>(pc.colour_edge_inverse), pc.density_edge_inverse);
    let s = d * inv;
    return d / sqrt(vec4<f32>(1.0) + s * s);
}

// Half the sparsity prior's derivative over its weight for a density σ:
// σ₊ / (1 + (σ₊·inv)²) (passes/src/train/tv.rs sparsity_pull).
fn sparsity_pull(sigma: f32) -> f32 {
    let s = max(sigma, 0.0);
    let q = s * pc.sparsity_edge_inverse;
    return s / (1.0 + q * q);
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = id.x + 65535u * 64u * id.y;
    if n >= pc.count {
        return;
    }
    let r = pc.resolution;
    var i = vec3<u32>(n % r.x, (n / r.x) % r.y, n / (r.x * r.y));
    if pc.brick_dims.x != 0u {
        i = brick_node(slot_bricks[n / BRICK_NODES], pc.brick_dims, n % BRICK_NODES);
        if any(i >= r) {
            return; // a partial brick's padding: stays zero
        }
    }
    let v = params[n];
    var acc = vec4<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        var e = vec3<u32>(0u);
        e[a] = 1u;
        if i[a] + 1u < r[a] {
            acc += pull(v - neighbour(i + e));
        }
        if i[a] > 0u {
            acc += pull(v - neighbour(i - e));
        }
    }
    let w = vec4<f32>(pc.colour_weight, pc.colour_weight, pc.colour_weight, pc.density_weight);
    acc *= w;
    acc.w += pc.sparsity * sparsity_pull(v.w);
    grad[n] += 2.0 * acc;
}
