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

// Σ_j y_j·coefficient_j of pool node n with `count` further coefficients.
fn sh_node(n: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    var y = basis;
    var s = vec3<f32>(0.0);
    for (var j = 0u; j < count; j++) {
        s += y[j] * field_sh_coefficient(n, j);
    }
    return s;
}

// The view-dependent part at a cell (a dropped brick's coefficients are
// zero).
fn sh_trilinear(cell: TrilinearCell, degree: u32, basis: array<f32, 8>) -> vec3<f32> {
    let count = sh_count(degree);
    var c = vec3<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let n = field_node_index(cell.base + trilinear_corner(k));
        if n == EMPTY_BRICK {
            continue;
        }
        c += trilinear_weight(cell.f, k) * sh_node(n, count, basis);
    }
    return c;
}
