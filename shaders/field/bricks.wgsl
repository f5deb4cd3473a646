// Bricks of a sparse grid: BRICK_SIDE³ nodes each; a table with one entry
// per brick holds its slot in the pool, or EMPTY_BRICK where the brick was
// dropped (its nodes are zero). Mirrors passes/src/field/bricks.rs
// (BrickLayout::pool_index).

const BRICK_SIDE: u32 = 8u;
const BRICK_NODES: u32 = 512u;
const EMPTY_BRICK: u32 = 0xffffffffu;

// Index in a table of `dims` bricks of the brick holding node i.
fn brick_table_index(i: vec3<u32>, dims: vec3<u32>) -> u32 {
    let b = i / BRICK_SIDE;
    return b.x + dims.x * (b.y + dims.y * b.z);
}

// Index in the pool of node i, whose brick has `slot`.
fn brick_pool_index(slot: u32, i: vec3<u32>) -> u32 {
    let l = i % BRICK_SIDE;
    return slot * BRICK_NODES + l.x + BRICK_SIDE * (l.y + BRICK_SIDE * l.z);
}

// The step in the pool from a node to its neighbour along axis a in the
// same brick: brick_pool_index's strides (x fastest).
fn brick_pool_stride(a: u32) -> u32 {
    let strides = vec3<u32>(1u, BRICK_SIDE, BRICK_SIDE * BRICK_SIDE);
    return strides[a];
}

// The grid coordinates of node `local` (0..BRICK_NODES, x fastest) of the
// brick at index `t` of a table of `dims` bricks.
fn brick_node(t: u32, dims: vec3<u32>, local: u32) -> vec3<u32> {
    let b = vec3<u32>(t % dims.x, (t / dims.x) % dims.y, t / (dims.x * dims.y));
    let l = vec3<u32>(local % BRICK_SIDE, (local / BRICK_SIDE) % BRICK_SIDE, local / (BRICK_SIDE * BRICK_SIDE));
    return b * BRICK_SIDE + l;
}
