// The view-dependent part of a grid's colour at a trilinear cell: Σ over
// the cell's eight corners of weight × Σ_k y_k·coefficient_k (y the basis
// at the ray's direction, sh_basis, once per ray). The field's colour
// along dir is max(0, base + this); passes/src/field/grid.rs mirrors it.
// Needs: field/trilinear.wgsl, field/sh.wgsl, field/bricks.wgsl, and from
// the includer `field_node_index(i)` (node i's index in the pool, or
// EMPTY_BRICK) and `field_sh_node(n, count, basis)` (Σ_j y_j·coefficient_j
// of the node at pool index n): the device's field holds them as f16
// (field/grid.wgsl), the trainer as f32 pages (train/sh_pages.wgsl).

// Further coefficients per node at `degree`.
fn sh_count(degree: u32) -> u32 {
    return (degree + 1u) * (degree + 1u) - 1u;
}

// Corner k's weighted term of sh_trilinear, its node at pool index n
// (zero where n is EMPTY_BRICK: its brick was dropped).
fn sh_corner_at(cell: TrilinearCell, k: u32, n: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    if n == EMPTY_BRICK {
        return vec3<f32>(0.0);
    }
    return trilinear_weight(cell.f, k) * field_sh_node(n, count, basis);
}

// Corner k's weighted term of sh_trilinear.
fn sh_corner(cell: TrilinearCell, k: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    return sh_corner_at(cell, k, field_node_index(cell.base + trilinear_corner(k)), count, basis);
}

// The view-dependent part at a cell (a dropped brick's coefficients are
// zero); zero at degree 0. llvmpipe ends all of an invocation's loops
// after 65535 iterations in all, and does not unroll a loop over the
// corners (its body is too large): with SH_CORNER_LOOP (a bool define,
// passes/src/march/knobs.rs SH_CORNER_LOOP_DEFINE) the corners are taken
// in a loop, 1.6 times faster there but eight iterations a sample, for
// kernels of one ray an invocation; without it they are written out and
// cost none. (A loop over a node's coefficients inside, 8 + 8·8 a sample,
// cut a degree-2 field's rays short from 2048 samples per ray on.)
fn sh_trilinear(cell: TrilinearCell, degree: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    if count == 0u {
        return vec3<f32>(0.0);
    }
    if SH_CORNER_LOOP {
        var c = vec3<f32>(0.0);
        for (var k = 0u; k < 8u; k++) {
            c += sh_corner(cell, k, count, basis);
        }
        return c;
    }
    return sh_corner(cell, 0u, count, basis) + sh_corner(cell, 1u, count, basis)
        + sh_corner(cell, 2u, count, basis) + sh_corner(cell, 3u, count, basis)
        + sh_corner(cell, 4u, count, basis) + sh_corner(cell, 5u, count, basis)
        + sh_corner(cell, 6u, count, basis) + sh_corner(cell, 7u, count, basis);
}

// sh_trilinear where the pool indices of the cell's corners are already
// known (`nodes`, corner k's at k: a kernel that also reads the corners'
// values and scatters their gradients looks each up once), the corners
// always in a loop: for kernels compiled with SH_CORNER_LOOP (the
// trainer's, passes/src/train/gpu.rs).
fn sh_trilinear_nodes(cell: TrilinearCell, nodes: CellNodes, degree: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    if count == 0u {
        return vec3<f32>(0.0);
    }
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        c += sh_corner_at(cell, k, node_of(nodes, k), count, basis);
    }
    return c;
}
