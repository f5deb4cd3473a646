// Total variation: each node's gradient of the squared differences to its
// six neighbours, Σ_nb (v − v_nb) per channel, weighted per channel group
// (colour, density), a difference d pulled by d / √(1 + (d·inv)²) with the
// group's own inv (a Charbonnier penalty: squared below 1/inv, its size
// beyond; inv 0: squared everywhere), and the density's sparsity prior (σ₊ / (1 +
// (σ₊·inv)²) with its own edge's inv, weighted), into the gradient buffer Adam's step left empty;
// train/descend.wgsl then takes one plain step along it. A sparse grid's
// nodes are its pool's, a dropped brick's neighbours zero (held so).
// With TV_COLOUR false (a bool define: the colour's weight is zero,
// passes/src/train/gpu.rs) only the densities are read and their
// gradient written: the colours' would be zero.
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

// The pool index of node n's neighbour one step along axis a (up or
// down), n at grid coordinates i, or EMPTY_BRICK where a sparse grid
// dropped the neighbour's brick. In n's own brick (and on a dense grid)
// it lies at a fixed stride from n; only a step out of the brick reads
// the brick table.
fn neighbour_index(n: u32, i: vec3<u32>, a: u32, up: bool) -> u32 {
    let r = pc.resolution;
    let dense = pc.brick_dims.x == 0u;
    // A dense grid's strides, x fastest (ray_grad_body's field_node_index).
    let dense_strides = vec3<u32>(1u, r.x, r.x * r.y);
    let stride = select(brick_pool_stride(a), dense_strides[a], dense);
    let local = i[a] % BRICK_SIDE;
    if dense || (up && local + 1u < BRICK_SIDE) {
        return select(n - stride, n + stride, up);
    }
    if !up && local > 0u {
        return n - stride;
    }
    var m = i;
    m[a] = select(i[a] - 1u, i[a] + 1u, up);
    let slot = bricks[brick_table_index(m, pc.brick_dims)];
    if slot == EMPTY_BRICK {
        return EMPTY_BRICK;
    }
    return brick_pool_index(slot, m);
}

// The values of the node at pool index k: zero where it is EMPTY_BRICK;
// only its density without TV_COLOUR.
fn neighbour(k: u32) -> vec4<f32> {
    if k == EMPTY_BRICK {
        return vec4<f32>(0.0);
    }
    if TV_COLOUR {
        return params[k];
    }
    return vec4<f32>(0.0, 0.0, 0.0, params[k].w);
}

// Half the penalty's derivative for a difference d: d / √(1 + (d·inv)²)
// with the colour's inv for r, g, b and the density's for σ
// (passes/src/train/tv.rs edge_pull).
// Without TV_COLOUR only σ's (the others zero).
fn pull(d: vec4<f32>) -> vec4<f32> {
    if !TV_COLOUR {
        let s = d.w * pc.density_edge_inverse;
        return vec4<f32>(0.0, 0.0, 0.0, d.w / sqrt(1.0 + s * s));
    }
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
    let v = neighbour(n);
    var acc = vec4<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        if i[a] + 1u < r[a] {
            acc += pull(v - neighbour(neighbour_index(n, i, a, true)));
        }
        if i[a] > 0u {
            acc += pull(v - neighbour(neighbour_index(n, i, a, false)));
        }
    }
    let w = vec4<f32>(pc.colour_weight, pc.colour_weight, pc.colour_weight, pc.density_weight);
    acc *= w;
    acc.w += pc.sparsity * sparsity_pull(v.w);
    if TV_COLOUR {
        grad[n] += 2.0 * acc;
    } else {
        grad[n].w += 2.0 * acc.w;
    }
}
