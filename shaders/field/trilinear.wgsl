// The cell of a regular grid of nodes (node 0 at bounds_min, the last at
// bounds_max) that holds x, and x's fractions within it; the weight of each
// of its eight corners. Mirrors GridField::corners in
// passes/src/field/grid.rs (corner k: +1 along x if bit 0, y bit 1, z bit 2).

struct TrilinearCell {
    base: vec3<u32>,
    f: vec3<f32>,
    inside: bool,
}

fn trilinear_cell(x: vec3<f32>, bounds_min: vec3<f32>, bounds_max: vec3<f32>, resolution: vec3<u32>) -> TrilinearCell {
    let inside = all(x >= bounds_min) && all(x <= bounds_max);
    let cells = vec3<f32>(resolution - vec3<u32>(1u));
    let u = (x - bounds_min) / (bounds_max - bounds_min) * cells;
    let base = clamp(floor(u), vec3<f32>(0.0), cells - vec3<f32>(1.0));
    let f = clamp(u - base, vec3<f32>(0.0), vec3<f32>(1.0));
    return TrilinearCell(vec3<u32>(base), f, inside);
}

fn trilinear_corner(k: u32) -> vec3<u32> {
    return vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
}

fn trilinear_weight(f: vec3<f32>, k: u32) -> f32 {
    let c = vec3<f32>(trilinear_corner(k));
    let w = mix(vec3<f32>(1.0) - f, f, c);
    return w.x * w.y * w.z;
}

// The density of a trilinear blend of node densities: clamped at zero after
// interpolation (a node's density may be negative). Mirrors density_at in
// passes/src/field/grid.rs.
fn density_at(raw: f32) -> f32 {
    return max(raw, 0.0);
}

// The pool indices of a cell's eight corner nodes, corner k's
// (trilinear_corner(k)) at k: corners 0–3 in lo, 4–7 in hi. A kernel
// that reads a sample's corners more than once looks them up once.
struct CellNodes {
    lo: vec4<u32>,
    hi: vec4<u32>,
}

// Corner k's pool index.
fn node_of(c: CellNodes, k: u32) -> u32 {
    let v = select(c.lo, c.hi, k >= 4u);
    return v[k & 3u];
}
