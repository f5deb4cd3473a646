//! Empty-space skipping for grid fields: a coarse grid whose cells say
//! whether any density can be non-zero inside them. Mirrored in
//! `shaders/field/grid.wgsl` (`occupancy_empty_until`).
//!
//! A coarse cell covers `block`³ node cells. It is marked occupied when any
//! node from one before its first to one after its last has σ > 0: the
//! one-node dilation means a march that steps slightly past a cell's exit
//! (rounding) still lands where σ is exactly zero, so skipping never changes
//! the integral.

use glam::{DVec3, UVec3};

use crate::geometry::Aabb;

/// Node cells per coarse cell and axis unless a caller chooses otherwise.
pub const DEFAULT_OCCUPANCY_BLOCK: u32 = 8;

/// The coarse occupancy grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Occupancy {
    /// Node cells per coarse cell and axis.
    pub block: u32,
    /// Coarse cells per axis.
    pub dims: UVec3,
    /// 1 where occupied, 0 where empty; x fastest.
    pub cells: Vec<u32>,
}

impl Occupancy {
    /// Builds the grid from `nodes` (r, g, b, σ) at `resolution`.
    pub fn build(resolution: UVec3, nodes: &[[f32; 4]], block: u32) -> Self {
        let block = block.max(1);
        let node_cells = resolution - UVec3::ONE;
        let dims = (node_cells + UVec3::splat(block - 1)) / block;
        let mut cells = vec![0u32; (dims.x * dims.y * dims.z) as usize];
        for cz in 0..dims.z {
            for cy in 0..dims.y {
                for cx in 0..dims.x {
                    let c = UVec3::new(cx, cy, cz);
                    let lo = (c * block).saturating_sub(UVec3::ONE);
                    let hi = ((c + UVec3::ONE) * block + UVec3::ONE).min(resolution - UVec3::ONE);
                    let mut occupied = false;
                    'scan: for k in lo.z..=hi.z {
                        for j in lo.y..=hi.y {
                            for i in lo.x..=hi.x {
                                let n = (i + resolution.x * (j + resolution.y * k)) as usize;
                                if nodes[n][3] > 0.0 {
                                    occupied = true;
                                    break 'scan;
                                }
                            }
                        }
                    }
                    cells[(cx + dims.x * (cy + dims.y * cz)) as usize] = occupied as u32;
                }
            }
        }
        Self { block, dims, cells }
    }

    /// Fraction of coarse cells that are empty.
    pub fn empty_fraction(&self) -> f64 {
        let empty = self.cells.iter().filter(|&&c| c == 0).count();
        empty as f64 / self.cells.len().max(1) as f64
    }

    /// When the coarse cell holding `p` is empty: the distance along `dir`
    /// from `p` to that cell's exit. `None` when it is occupied.
    pub fn empty_until(
        &self,
        bounds: &Aabb,
        resolution: UVec3,
        p: DVec3,
        dir: DVec3,
    ) -> Option<f64> {
        let node_cells = (resolution - UVec3::ONE).as_dvec3();
        let u = (p - bounds.min) / bounds.size() * node_cells;
        let b = self.block as f64;
        let c = (u / b)
            .floor()
            .clamp(DVec3::ZERO, self.dims.as_dvec3() - DVec3::ONE);
        let index = (c.x as u32 + self.dims.x * (c.y as u32 + self.dims.y * c.z as u32)) as usize;
        if self.cells[index] != 0 {
            return None;
        }
        let h = bounds.size() / node_cells;
        let lo = bounds.min + c * b * h;
        let hi = bounds.min + ((c + DVec3::ONE) * b).min(node_cells) * h;
        let mut exit = f64::INFINITY;
        for a in 0..3 {
            if dir[a] > 0.0 {
                exit = exit.min((hi[a] - p[a]) / dir[a]);
            } else if dir[a] < 0.0 {
                exit = exit.min((lo[a] - p[a]) / dir[a]);
            }
        }
        Some(exit.max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_dense_node_marks_its_neighbourhood_only() {
        let res = UVec3::splat(33);
        let mut nodes = vec![[0.0f32; 4]; 33 * 33 * 33];
        // Node (8, 0, 0) sits on the border of coarse cells 0 and 1 in x.
        nodes[8][3] = 1.0;
        let occ = Occupancy::build(res, &nodes, 8);
        assert_eq!(occ.dims, UVec3::splat(4));
        let at = |x: u32, y: u32, z: u32| occ.cells[(x + 4 * (y + 4 * z)) as usize];
        assert_eq!(at(0, 0, 0), 1);
        assert_eq!(at(1, 0, 0), 1);
        assert_eq!(at(2, 0, 0), 0);
        assert_eq!(at(0, 1, 0), 0);
        let bounds = Aabb::new(DVec3::ZERO, DVec3::splat(32.0));
        // From inside empty cell (2,0,0) heading +x: exit at x = 24.
        let s = occ
            .empty_until(&bounds, res, DVec3::new(17.0, 1.0, 1.0), DVec3::X)
            .unwrap();
        assert!((s - 7.0).abs() < 1e-12);
        assert_eq!(
            occ.empty_until(&bounds, res, DVec3::new(3.0, 1.0, 1.0), DVec3::X),
            None
        );
    }
}
