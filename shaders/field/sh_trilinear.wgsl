// The view-dependent part of a grid's colour at a trilinear cell: Σ over
// the cell's eight corners of weight × Σ_k y_k·coefficient_k (y the basis
// at the ray's direction, sh_basis, once per ray), read
// from `grid_nodes` (which the includer declares: the N base nodes, then
// each node's (ℓ+1)²−1 further coefficients as (r, g, b, 0), node-major;
// passes/src/field/gpu_grid.rs device_values). The field's colour along
// dir is max(0, base + this); passes/src/field/grid.rs mirrors it.
// Needs: field/trilinear.wgsl, field/sh.wgsl.

// Further coefficients per node at `degree`.
fn sh_count(degree: u32) -> u32 {
    return (degree + 1u) * (degree + 1u) - 1u;
}

// Index in grid_nodes of node i's first further coefficient.
fn sh_first(i: vec3<u32>, resolution: vec3<u32>, degree: u32) -> u32 {
    let r = resolution;
    return r.x * r.y * r.z + sh_count(degree) * (i.x + r.x * (i.y + r.y * i.z));
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

// The view-dependent part at a cell of a dense grid.
fn sh_trilinear(cell: TrilinearCell, resolution: vec3<u32>, degree: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let n = sh_first(cell.base + trilinear_corner(k), resolution, degree);
        c += trilinear_weight(cell.f, k) * sh_node(n, count, basis);
    }
    return c;
}
