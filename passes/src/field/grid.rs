//! The voxel-grid radiance field: density and view-independent HDR RGB at
//! the nodes of a regular grid spanning the bounds, read with trilinear
//! interpolation. Mirrored in `shaders/field/grid.wgsl`.

use glam::{DVec3, UVec3};

use super::occupancy::Occupancy;
use super::RadianceField;
use crate::geometry::Aabb;

/// A grid field: `resolution` nodes per axis, node (0,0,0) at `bounds.min`
/// and the last node at `bounds.max`; each node holds (r, g, b, σ).
#[derive(Debug, Clone)]
pub struct GridField {
    /// Nodes per axis (each at least 2).
    pub resolution: UVec3,
    /// The region the nodes span.
    pub bounds: Aabb,
    /// Linear HDR colour and density per node, x fastest, then y, then z.
    pub nodes: Vec<[f32; 4]>,
    /// Empty-space structure built from the nodes.
    pub occupancy: Occupancy,
}

impl GridField {
    /// A field from its nodes; builds the occupancy structure with
    /// `occupancy_block` node cells per coarse cell and axis.
    ///
    /// Panics if `nodes.len()` does not match the resolution (the loader
    /// checks this before calling).
    pub fn new(
        resolution: UVec3,
        bounds: Aabb,
        nodes: Vec<[f32; 4]>,
        occupancy_block: u32,
    ) -> Self {
        assert_eq!(
            nodes.len(),
            (resolution.x * resolution.y * resolution.z) as usize,
            "node count does not match the resolution"
        );
        let occupancy = Occupancy::build(resolution, &nodes, occupancy_block);
        Self {
            resolution,
            bounds,
            nodes,
            occupancy,
        }
    }

    /// Distance between neighbouring nodes along each axis.
    pub fn spacing(&self) -> DVec3 {
        self.bounds.size() / (self.resolution.as_dvec3() - DVec3::ONE)
    }

    /// ∇σ at `x` by central differences one node spacing (the smallest
    /// axis's) wide. The field's surface normal is −∇σ normalised.
    pub fn density_gradient(&self, x: DVec3) -> DVec3 {
        let h = self.spacing().min_element();
        let d = |e: DVec3| self.density(x + e * h) - self.density(x - e * h);
        DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z)) / (2.0 * h)
    }

    /// Index of node (i, j, k) in [`Self::nodes`].
    pub fn index(&self, i: u32, j: u32, k: u32) -> usize {
        (i + self.resolution.x * (j + self.resolution.y * k)) as usize
    }

    /// The eight nodes around `x` and their trilinear weights (summing to
    /// 1), or None outside the bounds. The one definition of the grid's
    /// interpolation: [`Self::interpolate`] reads through it and the
    /// trainer scatters gradients through it.
    pub fn corners(&self, x: DVec3) -> Option<[(usize, f64); 8]> {
        if !self.bounds.contains(x) {
            return None;
        }
        let cells = self.resolution.as_dvec3() - DVec3::ONE;
        let u = (x - self.bounds.min) / self.bounds.size() * cells;
        let base = u.floor().clamp(DVec3::ZERO, cells - DVec3::ONE);
        let f = (u - base).clamp(DVec3::ZERO, DVec3::ONE);
        let (i, j, k) = (base.x as u32, base.y as u32, base.z as u32);
        Some(std::array::from_fn(|corner| {
            let corner = corner as u32;
            let (di, dj, dk) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if di == 1 { f.x } else { 1.0 - f.x })
                * (if dj == 1 { f.y } else { 1.0 - f.y })
                * (if dk == 1 { f.z } else { 1.0 - f.z });
            (self.index(i + di, j + dj, k + dk), w)
        }))
    }

    /// Trilinear interpolation of the four channels at `x`; zero outside the
    /// bounds.
    pub fn interpolate(&self, x: DVec3) -> [f64; 4] {
        let mut out = [0.0; 4];
        if let Some(corners) = self.corners(x) {
            for (n, w) in corners {
                let n = self.nodes[n];
                for c in 0..4 {
                    out[c] += w * n[c] as f64;
                }
            }
        }
        out
    }
}

impl RadianceField for GridField {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn density(&self, x: DVec3) -> f64 {
        self.interpolate(x)[3]
    }

    fn colour(&self, x: DVec3, _d: DVec3) -> DVec3 {
        let v = self.interpolate(x);
        DVec3::new(v[0], v[1], v[2])
    }

    fn sample(&self, x: DVec3, _d: DVec3) -> (f64, DVec3) {
        let v = self.interpolate(x);
        (v[3], DVec3::new(v[0], v[1], v[2]))
    }

    fn empty_until(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        self.occupancy
            .empty_until(&self.bounds, self.resolution, origin, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> GridField {
        let res = UVec3::new(3, 2, 2);
        let mut nodes = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    let v = (i + 10 * j + 100 * k) as f32;
                    nodes.push([v, 2.0 * v, 0.0, v]);
                }
            }
        }
        GridField::new(
            res,
            Aabb::new(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0)),
            nodes,
            8,
        )
    }

    #[test]
    fn trilinear_reproduces_nodes_and_linear_functions() {
        let f = ramp();
        assert_eq!(f.density(DVec3::new(1.0, 1.0, 0.0)), 11.0);
        // The node values are linear in position: i + 10j + 100k with i = x.
        let x = DVec3::new(1.25, 0.5, 0.75);
        assert!((f.density(x) - (1.25 + 5.0 + 75.0)).abs() < 1e-12);
        assert!((f.colour(x, DVec3::Z).y - 2.0 * (1.25 + 5.0 + 75.0)).abs() < 1e-12);
        assert_eq!(f.density(DVec3::new(2.5, 0.5, 0.5)), 0.0);
        assert_eq!(f.density(DVec3::new(2.0, 1.0, 1.0)), 112.0);
    }
}
