// The view-dependent part of a grid's colour at a trilinear cell: Σ over
// the cell's eight corners of weight × Σ_k y_k·coefficient_k (y the basis
// at the ray's direction, sh_basis, once per ray). The field's colour
// along dir is max(0, base + this); passes/src/field/grid.rs mirrors it.
// Needs: field/trilinear.wgsl, field/sh.wgsl, field/bricks.wgsl, and from
// the includer `field_node_index(i)` (node i's index in the pool, or
// EMPTY_BRICK) and `field_sh_coefficient(n, j)` (further coefficient j of
// the node at pool index n): the device's field holds them as f16
// (field/grid.wgsl), the trainer as f32 after its values.

// Further coefficients per node at `degree`.
fn sh_count(degree: u32) -> u32 {
    return (degree + 1u) * (degree + 1u) - 1u;
}

// Σ_j y_j·coefficient_j of pool node n with `count` (3 or 8) further
// coefficients. Written out rather than looped, as is sh_trilinear:
// llvmpipe ends all of an invocation's loops after 65535 iterations in
// all, and a loop here ran 8 + 8·count of them at every step of a march
// (a degree-2 field's rays were cut short from 2048 samples per ray on).
fn sh_node(n: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    var s = basis[0] * field_sh_coefficient(n, 0u) + basis[1] * field_sh_coefficient(n, 1u)
        + basis[2] * field_sh_coefficient(n, 2u);
    if count > 3u {
        s += basis[3] * field_sh_coefficient(n, 3u) + basis[4] * field_sh_coefficient(n, 4u)
            + basis[5] * field_sh_coefficient(n, 5u) + basis[6] * field_sh_coefficient(n, 6u)
            + basis[7] * field_sh_coefficient(n, 7u);
    }
    return s;
}

// Corner k's weighted term of sh_trilinear (zero where its brick was
// dropped).
fn sh_corner(cell: TrilinearCell, k: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    let n = field_node_index(cell.base + trilinear_corner(k));
    if n == EMPTY_BRICK {
        return vec3<f32>(0.0);
    }
    return trilinear_weight(cell.f, k) * sh_node(n, count, basis);
}

// The view-dependent part at a cell (a dropped brick's coefficients are
// zero); zero at degree 0.
fn sh_trilinear(cell: TrilinearCell, degree: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    if count == 0u {
        return vec3<f32>(0.0);
    }
    return sh_corner(cell, 0u, count, basis) + sh_corner(cell, 1u, count, basis)
        + sh_corner(cell, 2u, count, basis) + sh_corner(cell, 3u, count, basis)
        + sh_corner(cell, 4u, count, basis) + sh_corner(cell, 5u, count, basis)
        + sh_corner(cell, 6u, count, basis) + sh_corner(cell, 7u, count, basis);
}
