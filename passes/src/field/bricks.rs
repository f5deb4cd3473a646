//! A grid field's nodes stored sparsely on the device: the grid is cut into
//! bricks of [`BRICK_SIDE`]³ nodes, and only the bricks holding a node
//! with any non-zero value (colour, density or a view-dependent
//! coefficient) are kept, in a pool; a table with one entry per brick gives
//! its slot in the pool, or [`EMPTY_BRICK`]. A dropped brick reads as
//! zeros, which is what its nodes held, so the sparse field is the dense
//! one exactly. Mirrored in `shaders/field/bricks.wgsl`, which
//! `field/grid.wgsl` and the trainer read through.
//!
//! The pool ([`BrickLayout::pool_values`]) holds the kept bricks' nodes,
//! slot by slot, each brick's nodes x fastest, then y, then z (a partial
//! brick at the grid's far faces keeps its full size, the nodes past the
//! grid zero), and each pool node's further coefficients in the same
//! order. The device holds the coefficients in a binding of their own, as
//! f16 (`super::gpu_grid`, `super::sh_half`); the trainer holds them as
//! f32 after the nodes ([`BrickLayout::device_values`]).

use glam::UVec3;

use super::grid::GridField;

/// Nodes per brick side.
pub const BRICK_SIDE: u32 = 8;

/// Nodes per brick.
pub const BRICK_NODES: u32 = BRICK_SIDE * BRICK_SIDE * BRICK_SIDE;

/// The table entry of a brick left out of the pool.
pub const EMPTY_BRICK: u32 = u32::MAX;

/// Which bricks of a field are kept, and where.
#[derive(Debug, Clone, PartialEq)]
pub struct BrickLayout {
    /// Bricks per axis.
    pub dims: UVec3,
    /// Per brick (x fastest): its slot in the pool or [`EMPTY_BRICK`].
    pub table: Vec<u32>,
    /// Bricks kept.
    pub slots: u32,
}

impl BrickLayout {
    /// Bricks per axis over a grid of `resolution` nodes.
    pub fn dims_of(resolution: UVec3) -> UVec3 {
        (resolution + UVec3::splat(BRICK_SIDE - 1)) / BRICK_SIDE
    }

    /// The layout keeping the bricks `keep` says (one per brick of
    /// [`Self::dims_of`] `resolution`, x fastest), in table order.
    ///
    /// Panics if `keep` has the wrong length.
    pub fn from_kept(resolution: UVec3, keep: &[bool]) -> Self {
        let dims = Self::dims_of(resolution);
        assert_eq!(keep.len(), (dims.x * dims.y * dims.z) as usize);
        Self::numbered(dims, keep)
    }

    /// Slots numbered in table order over the bricks `keep` says.
    fn numbered(dims: UVec3, keep: &[bool]) -> Self {
        let mut slots = 0;
        let table = keep
            .iter()
            .map(|&kept| {
                if kept {
                    slots += 1;
                    slots - 1
                } else {
                    EMPTY_BRICK
                }
            })
            .collect();
        Self { dims, table, slots }
    }

    /// The layout of `field`: every brick with a non-zero node kept.
    pub fn of(field: &GridField) -> Self {
        let r = field.resolution;
        let dims = Self::dims_of(r);
        let mut keep = vec![false; (dims.x * dims.y * dims.z) as usize];
        let k = field.sh_count();
        for z in 0..r.z {
            for y in 0..r.y {
                for x in 0..r.x {
                    let n = field.index(x, y, z);
                    let b = brick_index(dims, UVec3::new(x, y, z) / BRICK_SIDE);
                    if keep[b] {
                        continue;
                    }
                    let sh = &field.sh[n * k..(n + 1) * k];
                    keep[b] = field.nodes[n].iter().any(|&v| v != 0.0)
                        || sh.iter().flatten().any(|&v| v != 0.0);
                }
            }
        }
        Self::from_kept(r, &keep)
    }

    /// The layout keeping every brick either `self` or `other` keeps
    /// (slots renumbered in table order).
    ///
    /// Panics if the two are over different grids of bricks.
    pub fn union(&self, other: &BrickLayout) -> BrickLayout {
        assert_eq!(self.dims, other.dims);
        let keep: Vec<bool> = self
            .table
            .iter()
            .zip(&other.table)
            .map(|(&a, &b)| a != EMPTY_BRICK || b != EMPTY_BRICK)
            .collect();
        Self::numbered(self.dims, &keep)
    }

    /// Each slot's index in the table.
    pub fn slot_bricks(&self) -> Vec<u32> {
        let mut out = vec![0; self.slots as usize];
        for (b, &slot) in self.table.iter().enumerate() {
            if slot != EMPTY_BRICK {
                out[slot as usize] = b as u32;
            }
        }
        out
    }

    /// Nodes the pool holds.
    pub fn pool_nodes(&self) -> u64 {
        self.slots as u64 * BRICK_NODES as u64
    }

    /// Where node `i` lies in the pool, or None where its brick was
    /// dropped (it is zero). The CPU mirror of `grid_node_index`.
    pub fn pool_index(&self, i: UVec3) -> Option<u64> {
        let slot = self.table[brick_index(self.dims, i / BRICK_SIDE)];
        (slot != EMPTY_BRICK).then(|| {
            let l = i % BRICK_SIDE;
            slot as u64 * BRICK_NODES as u64 + (l.x + BRICK_SIDE * (l.y + BRICK_SIDE * l.z)) as u64
        })
    }

    /// The field's nodes in the pool, slot by slot, and their further
    /// coefficients (`sh_count` a node) in the same order.
    pub fn pool_values(&self, field: &GridField) -> (Vec<[f32; 4]>, Vec<[f32; 3]>) {
        let pool = self.pool_nodes() as usize;
        let k = field.sh_count();
        let mut nodes = vec![[0.0f32; 4]; pool];
        let mut sh = vec![[0.0f32; 3]; pool * k];
        let r = field.resolution;
        for z in 0..r.z {
            for y in 0..r.y {
                for x in 0..r.x {
                    let Some(p) = self.pool_index(UVec3::new(x, y, z)) else {
                        continue;
                    };
                    let (p, n) = (p as usize, field.index(x, y, z));
                    nodes[p] = field.nodes[n];
                    sh[p * k..(p + 1) * k].copy_from_slice(&field.sh[n * k..(n + 1) * k]);
                }
            }
        }
        (nodes, sh)
    }

    /// The field's node array as the trainer holds it in this layout (the
    /// module's doc).
    pub fn device_values(&self, field: &GridField) -> Vec<[f32; 4]> {
        let (nodes, sh) = self.pool_values(field);
        nodes
            .into_iter()
            .chain(sh.into_iter().map(|c| [c[0], c[1], c[2], 0.0]))
            .collect()
    }
}

impl BrickLayout {
    /// The dense nodes and further coefficients (`sh_count` a node) of a
    /// grid of `resolution` nodes from `values` in this layout (the
    /// inverse of [`Self::device_values`]; a dropped brick's nodes zero).
    pub fn dense_values(
        &self,
        values: &[[f32; 4]],
        resolution: UVec3,
        sh_count: usize,
    ) -> (Vec<[f32; 4]>, Vec<[f32; 3]>) {
        let pool = self.pool_nodes() as usize;
        let count = (resolution.x * resolution.y * resolution.z) as usize;
        let mut nodes = vec![[0.0f32; 4]; count];
        let mut sh = vec![[0.0f32; 3]; count * sh_count];
        for z in 0..resolution.z {
            for y in 0..resolution.y {
                for x in 0..resolution.x {
                    let Some(p) = self.pool_index(UVec3::new(x, y, z)) else {
                        continue;
                    };
                    let p = p as usize;
                    let n = (x + resolution.x * (y + resolution.y * z)) as usize;
                    nodes[n] = values[p];
                    for j in 0..sh_count {
                        let v = values[pool + p * sh_count + j];
                        sh[n * sh_count + j] = [v[0], v[1], v[2]];
                    }
                }
            }
        }
        (nodes, sh)
    }
}

/// Index of brick `b` in a table of `dims` bricks.
pub fn brick_index(dims: UVec3, b: UVec3) -> usize {
    (b.x + dims.x * (b.y + dims.y * b.z)) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::DVec3;

    /// A 20 × 11 × 9 field (partial bricks on every far face) whose only
    /// non-zero nodes are a blob around node (13, 4, 2), with degree-1
    /// coefficients on one node elsewhere.
    fn blob() -> GridField {
        let res = UVec3::new(20, 11, 9);
        let mut nodes = vec![[0.0f32; 4]; (res.x * res.y * res.z) as usize];
        let index = |x: u32, y: u32, z: u32| (x + res.x * (y + res.y * z)) as usize;
        for (x, y, z) in [(13, 4, 2), (14, 4, 2), (13, 5, 3)] {
            nodes[index(x, y, z)] = [1.0, 2.0, 3.0, 4.0 + x as f32];
        }
        let field = GridField::new(res, Aabb::new(DVec3::ZERO, DVec3::ONE), nodes, 4);
        let mut sh = vec![[0.0f32; 3]; field.nodes.len() * 3];
        sh[index(2, 9, 8) * 3 + 1] = [0.5, -0.25, 0.125];
        field.with_sh(1, sh)
    }

    #[test]
    fn only_bricks_with_a_value_are_kept() {
        let field = blob();
        let layout = BrickLayout::of(&field);
        assert_eq!(layout.dims, UVec3::new(3, 2, 2));
        // The blob's brick (1, 0, 0) and the coefficient's (0, 1, 1).
        assert_eq!(layout.slots, 2);
        let kept: Vec<usize> = (0..layout.table.len())
            .filter(|&b| layout.table[b] != EMPTY_BRICK)
            .collect();
        assert_eq!(kept, [1, 9]);
    }

    #[test]
    fn the_pool_holds_every_node_where_the_table_says() {
        let field = blob();
        let layout = BrickLayout::of(&field);
        let values = layout.device_values(&field);
        let pool = layout.pool_nodes() as usize;
        assert_eq!(values.len(), pool * 4);
        let r = field.resolution;
        for z in 0..r.z {
            for y in 0..r.y {
                for x in 0..r.x {
                    let n = field.index(x, y, z);
                    let (node, sh) = match layout.pool_index(UVec3::new(x, y, z)) {
                        Some(p) => {
                            let p = p as usize;
                            let sh: Vec<[f32; 3]> = (0..3)
                                .map(|j| {
                                    let v = values[pool + p * 3 + j];
                                    [v[0], v[1], v[2]]
                                })
                                .collect();
                            (values[p], sh)
                        }
                        None => ([0.0; 4], vec![[0.0; 3]; 3]),
                    };
                    assert_eq!(node, field.nodes[n], "node ({x}, {y}, {z})");
                    assert_eq!(sh, &field.sh[n * 3..n * 3 + 3], "node ({x}, {y}, {z})");
                }
            }
        }
    }

    #[test]
    fn the_dense_values_come_back_from_the_pool() {
        let field = blob();
        let layout = BrickLayout::of(&field);
        let (nodes, sh) = layout.dense_values(&layout.device_values(&field), field.resolution, 3);
        assert_eq!(nodes, field.nodes);
        assert_eq!(sh, field.sh);
        let slots = layout.slot_bricks();
        assert_eq!(slots, [1, 9]);
    }

    #[test]
    fn an_empty_field_keeps_no_brick() {
        let res = UVec3::new(9, 9, 9);
        let nodes = vec![[0.0f32; 4]; 729];
        let field = GridField::new(res, Aabb::new(DVec3::ZERO, DVec3::ONE), nodes, 4);
        let layout = BrickLayout::of(&field);
        assert_eq!(layout.slots, 0);
        assert!(layout.device_values(&field).is_empty());
    }
}
