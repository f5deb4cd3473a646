// The voxel-grid radiance field: trilinear lookup of (r, g, b, σ) nodes,
// the view-dependent colour's further coefficients where the field has
// them (f16 in a binding of their own, passes/src/field/sh_half.rs), and
// the coarse occupancy grid for empty-space skipping. Mirrors
// passes/src/field/grid.rs and passes/src/field/occupancy.rs; the layout of
// `GridInfo` and of `grid_nodes` is written by passes/src/field/gpu_grid.rs.
// A sparse field (FIELD_SPARSE, a define of the pass's shader library, and
// brick_dims.x > 0) keeps only its non-zero bricks of nodes: the table
// after the occupancy cells in `grid_occupancy` gives each brick's slot
// (passes/src/field/bricks.rs).

#include "field/trilinear.wgsl"
#include "field/sh.wgsl"
#include "field/bricks.wgsl"

struct GridInfo {
    bounds_min: vec3<f32>,
    occupancy_block: u32,
    bounds_max: vec3<f32>,
    sh_degree: u32,
    resolution: vec3<u32>,
    sh_unscale: f32,
    occupancy_dims: vec3<u32>,
    _pad2: u32,
    brick_dims: vec3<u32>,
    _pad3: u32,
}

@group(0) @binding(0) var<uniform> grid_info: GridInfo;
@group(0) @binding(1) var<storage, read> grid_nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> grid_occupancy: array<u32>;
// The further coefficients: three halves (r, g, b) each, node after node
// in the pool's order, two halves a word, a word of padding at the end;
// the first half of each node's (rounded up) in `grid_sh`, the rest in
// `grid_sh_rest`, so that no binding holds more than half of them.
@group(0) @binding(31) var<storage, read> grid_sh: array<u32>;
@group(0) @binding(32) var<storage, read> grid_sh_rest: array<u32>;

#include "field/sh_trilinear.wgsl"

// Σ_j y_j·coefficient_j of pool node n with `count` (3 or 8) further
// coefficients (sh_trilinear.wgsl's accessor), y = `basis`. A node's
// coefficients are runs of halves, three a coefficient: the first
// (count + 1) / 2 at half 3·first·n of `grid_sh`, the rest at half
// 3·(count − first)·n of `grid_sh_rest`; they are read a word at a time
// (degree 2: six words from each, always whole; degree 1: three whole
// words, and the rest's one coefficient from the half it starts at).
// Mirrors sh_half::unpack_split_sh.
fn field_sh_node(n: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    var s: vec3<f32>;
    if count == 8u {
        let a = 6u * n;
        s = sh_pair(grid_sh[a], grid_sh[a + 1u], grid_sh[a + 2u], basis[0], basis[1])
            + sh_pair(grid_sh[a + 3u], grid_sh[a + 4u], grid_sh[a + 5u], basis[2], basis[3])
            + sh_pair(grid_sh_rest[a], grid_sh_rest[a + 1u], grid_sh_rest[a + 2u], basis[4], basis[5])
            + sh_pair(grid_sh_rest[a + 3u], grid_sh_rest[a + 4u], grid_sh_rest[a + 5u], basis[6], basis[7]);
    } else {
        let a = 3u * n;
        let h = 3u * n;
        let r0 = unpack2x16float(grid_sh_rest[h >> 1u]);
        let r1 = unpack2x16float(grid_sh_rest[(h >> 1u) + 1u]);
        let rest = select(vec3<f32>(r0.x, r0.y, r1.x), vec3<f32>(r0.y, r1.x, r1.y), (h & 1u) == 1u);
        s = sh_pair(grid_sh[a], grid_sh[a + 1u], grid_sh[a + 2u], basis[0], basis[1]) + basis[2] * rest;
    }
    return s * grid_info.sh_unscale;
}

// y0·c0 + y1·c1 for two coefficients c0, c1 held in three words (six
// halves: c0's r, g, b, then c1's).
fn sh_pair(w0: u32, w1: u32, w2: u32, y0: f32, y1: f32) -> vec3<f32> {
    let a = unpack2x16float(w0);
    let b = unpack2x16float(w1);
    let c = unpack2x16float(w2);
    return y0 * vec3<f32>(a.x, a.y, b.x) + y1 * vec3<f32>(b.y, c.x, c.y);
}

// Where node i lies in grid_nodes, or EMPTY_BRICK where its brick was
// dropped (the node is zero). Mirrors BrickLayout::pool_index.
fn field_node_index(i: vec3<u32>) -> u32 {
    if FIELD_SPARSE && grid_info.brick_dims.x != 0u {
        let o = grid_info.occupancy_dims;
        let slot = grid_occupancy[o.x * o.y * o.z + brick_table_index(i, grid_info.brick_dims)];
        if slot == EMPTY_BRICK {
            return EMPTY_BRICK;
        }
        return brick_pool_index(slot, i);
    }
    let r = grid_info.resolution;
    return i.x + r.x * (i.y + r.y * i.z);
}

fn grid_node(i: vec3<u32>) -> vec4<f32> {
    let n = field_node_index(i);
    if FIELD_SPARSE && n == EMPTY_BRICK {
        return vec4<f32>(0.0);
    }
    return grid_nodes[n];
}

// Trilinear (r, g, b, σ) at x; zero outside the bounds.
fn grid_sample(x: vec3<f32>) -> vec4<f32> {
    let cell = trilinear_cell(x, grid_info.bounds_min, grid_info.bounds_max, grid_info.resolution);
    if !cell.inside {
        return vec4<f32>(0.0);
    }
    let f = cell.f;
    let i = cell.base;
    let x00 = mix(grid_node(i), grid_node(i + vec3<u32>(1u, 0u, 0u)), f.x);
    let x10 = mix(grid_node(i + vec3<u32>(0u, 1u, 0u)), grid_node(i + vec3<u32>(1u, 1u, 0u)), f.x);
    let x01 = mix(grid_node(i + vec3<u32>(0u, 0u, 1u)), grid_node(i + vec3<u32>(1u, 0u, 1u)), f.x);
    let x11 = mix(grid_node(i + vec3<u32>(0u, 1u, 1u)), grid_node(i + vec3<u32>(1u, 1u, 1u)), f.x);
    let v = mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
    // A node's density may be negative; the clamp is after interpolation
    // (a surface sharper than a node spacing).
    return vec4<f32>(v.xyz, density_at(v.w));
}

// The colour at x along a ray whose direction's basis is `basis`
// (sh_basis), given the base colour `base` that grid_sample(x) returned:
// base + Σ_k Y_k·coefficient_k(x), clamped at zero; `base` itself when
// the field has no view-dependent colour.
fn grid_view_colour(x: vec3<f32>, basis: array<f32, 8>, base: vec3<f32>) -> vec3<f32> {
    if grid_info.sh_degree == 0u {
        return base;
    }
    let cell = trilinear_cell(x, grid_info.bounds_min, grid_info.bounds_max, grid_info.resolution);
    if !cell.inside {
        return base;
    }
    return max(base + sh_trilinear(cell, grid_info.sh_degree, basis), vec3<f32>(0.0));
}

// When the coarse cell holding x is empty: the distance along dir from x to
// the cell's exit. Negative when the cell is occupied.
fn grid_empty_until(x: vec3<f32>, dir: vec3<f32>) -> f32 {
    let cells = vec3<f32>(grid_info.resolution - vec3<u32>(1u));
    let extent = grid_info.bounds_max - grid_info.bounds_min;
    let u = (x - grid_info.bounds_min) / extent * cells;
    let b = f32(grid_info.occupancy_block);
    let dims = grid_info.occupancy_dims;
    let c = clamp(floor(u / b), vec3<f32>(0.0), vec3<f32>(dims) - vec3<f32>(1.0));
    let ci = vec3<u32>(c);
    if grid_occupancy[ci.x + dims.x * (ci.y + dims.y * ci.z)] != 0u {
        return -1.0;
    }
    let h = extent / cells;
    let lo = grid_info.bounds_min + c * b * h;
    let hi = grid_info.bounds_min + min((c + vec3<f32>(1.0)) * b, cells) * h;
    // Per axis, the distance to the face the ray leaves by (none along an
    // axis it does not move on); no loop, since llvmpipe counts each loop
    // iteration of an invocation against 65535 in all (sh_trilinear.wgsl).
    let moving = dir != vec3<f32>(0.0);
    let face = select(lo, hi, dir > vec3<f32>(0.0));
    let t = select(vec3<f32>(3.0e38), (face - x) / select(vec3<f32>(1.0), dir, moving), moving);
    return max(min(t.x, min(t.y, t.z)), 0.0);
}
