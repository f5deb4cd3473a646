// The view-dependent part of a grid's colour at a trilinear cell: Σ over
// the cell's eight corners of weight × Σ_k y_k·coefficient_k (y the basis
// at the ray's direction, sh_basis, once per ray), read
// from `grid_nodes` (which the includer declares: the pool's nodes, then
// each node's (ℓ+1)²−1 further coefficients as (r, g, b, 0), node-major;
// passes/src/field/gpu_grid.rs device_values, field/bricks.rs). The
// field's colour along dir is max(0, base + this);
// passes/src/field/grid.rs mirrors it.
// Needs: field/trilinear.wgsl, field/sh.wgsl, field/bricks.wgsl, and from
// the includer `field_node_index(i)`: node i's index in the pool, or
// EMPTY_BRICK.

// Further coefficients per node at `degree`.
fn sh_count(degree: u32) -> u32 {
    return (degree + 1u) * (degree + 1u) - 1u;
}

// Σ_j y_j·coefficient_j of the node whose `count` further coefficients
// start at grid_nodes[first].
fn sh_node(first: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    var y = basis;
    var s = vec3<f32>(0.0);
    for (var j = 0u; j < count; j++) {
        s += y[j] * grid_nodes[first + j].xyz;
    }
    return s;
}

// The view-dependent part at a cell of a grid whose coefficients follow
// its `pool_nodes` nodes (a dropped brick's are zero).
fn sh_trilinear(cell: TrilinearCell, degree: u32, pool_nodes: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let n = field_node_index(cell.base + trilinear_corner(k));
        if n == EMPTY_BRICK {
            continue;
        }
        c += trilinear_weight(cell.f, k) * sh_node(pool_nodes + count * n, count, basis);
    }
    return c;
}
