//! The voxel-grid radiance field: density and HDR RGB at the nodes of a
//! regular grid spanning the bounds, read with trilinear interpolation; the
//! colour optionally view-dependent ([`super::sh`]). Mirrored in
//! `shaders/field/grid.wgsl`.

use glam::{DVec3, UVec3};

use super::occupancy::Occupancy;
use super::sh::{sh_colour_unclamped, sh_extra_coefficients, MAX_SH_DEGREE};
use super::sh_half::quantise_sh;
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
    /// With view-dependent colour the colour is the mean over directions.
    /// A node's density may be negative: the density at a point is the
    /// trilinear interpolation clamped at zero afterwards
    /// ([`density_at`]), so a node below zero moves where a surface
    /// crosses its cell (a trained field's surfaces sharper than a node
    /// spacing); a field of non-negative nodes reads as plain trilinear.
    pub nodes: Vec<[f32; 4]>,
    /// Degree of the view-dependent colour's spherical harmonics (0: the
    /// colour is the same in every direction).
    pub sh_degree: u32,
    /// The further RGB coefficients of each node
    /// ([`sh_extra_coefficients`] of them, node-major): coefficient k of
    /// node n at `n · count + k`. Empty at degree 0. Held at f16
    /// precision ([`Self::with_sh`]).
    pub sh: Vec<[f32; 3]>,
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
            sh_degree: 0,
            sh: Vec::new(),
            occupancy,
        }
    }

    /// The same field with view-dependent colour of `degree`, `sh` holding
    /// each node's further coefficients ([`Self::sh`]), rounded to the
    /// precision fields store them in ([`super::sh_half`]: f16 under a
    /// power-of-two scale), so the CPU reads what the device reads.
    ///
    /// Panics if the degree is above [`MAX_SH_DEGREE`] or `sh` has the
    /// wrong length (the loader checks both before calling).
    pub fn with_sh(mut self, degree: u32, sh: Vec<[f32; 3]>) -> Self {
        assert!(degree <= MAX_SH_DEGREE, "degree {degree}");
        assert_eq!(
            sh.len(),
            self.nodes.len() * sh_extra_coefficients(degree),
            "coefficient count does not match the nodes"
        );
        self.sh_degree = degree;
        self.sh = sh;
        quantise_sh(&mut self.sh);
        self
    }

    /// Coefficients beyond the base per node.
    pub fn sh_count(&self) -> usize {
        sh_extra_coefficients(self.sh_degree)
    }

    /// Trilinear interpolation of the further coefficients at `x` (empty at
    /// degree 0, zeros outside the bounds).
    pub fn interpolate_sh(&self, x: DVec3) -> Vec<DVec3> {
        let k = self.sh_count();
        let mut out = vec![DVec3::ZERO; k];
        if k == 0 {
            return out;
        }
        if let Some(corners) = self.corners(x) {
            for (n, w) in corners {
                for (o, c) in out.iter_mut().zip(&self.sh[n * k..(n + 1) * k]) {
                    *o += w * DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
                }
            }
        }
        out
    }

    /// The colour seen along `d` of interpolated values `v` at `x`
    /// (their base when the field has no view-dependent colour).
    fn view_colour(&self, v: [f64; 4], x: DVec3, d: DVec3) -> DVec3 {
        let base = DVec3::new(v[0], v[1], v[2]);
        if self.sh_degree == 0 {
            return base;
        }
        sh_colour_unclamped(base, &self.interpolate_sh(x), d).max(DVec3::ZERO)
    }

    /// Whether any node's density is above zero (a grid every density of
    /// which lies at or below renders nothing).
    pub fn holds_density(&self) -> bool {
        self.nodes.iter().any(|n| n[3] > 0.0)
    }

    /// Distance between neighbouring nodes along each axis.
    pub fn spacing(&self) -> DVec3 {
        self.bounds.size() / (self.resolution.as_dvec3() - DVec3::ONE)
    }

    /// ∇σ at `x` by central differences one node spacing (the smallest
    /// axis's) wide. The field's surface normal is −∇σ normalised.
    pub fn density_gradient(&self, x: DVec3) -> DVec3 {
        self.density_gradient_over(x, self.spacing().min_element())
    }

    /// ∇σ at `x` by central differences `step` either side: over more
    /// than a node spacing it reads the slope of a surface blurred over
    /// several nodes rather than of the nodes nearest `x`.
    pub fn density_gradient_over(&self, x: DVec3, step: f64) -> DVec3 {
        let d = |e: DVec3| self.density(x + e * step) - self.density(x - e * step);
        DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z)) / (2.0 * step)
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

/// The density of interpolated values `v`: their σ clamped at zero (the
/// clamp after interpolation: [`GridField::nodes`]). Mirrored by
/// `density_at` in `shaders/field/trilinear.wgsl`.
pub fn density_at(v: [f64; 4]) -> f64 {
    v[3].max(0.0)
}

impl RadianceField for GridField {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn density(&self, x: DVec3) -> f64 {
        density_at(self.interpolate(x))
    }

    fn colour(&self, x: DVec3, d: DVec3) -> DVec3 {
        self.view_colour(self.interpolate(x), x, d)
    }

    fn sample(&self, x: DVec3, d: DVec3) -> (f64, DVec3) {
        let v = self.interpolate(x);
        (density_at(v), self.view_colour(v, x, d))
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

    /// A node below zero next to one above puts the density's edge inside
    /// the cell, where the interpolated value crosses zero; nodes at or
    /// above zero read as plain trilinear.
    #[test]
    fn the_clamp_after_interpolation_puts_an_edge_inside_a_cell() {
        let res = UVec3::new(2, 2, 2);
        let bounds = Aabb::new(DVec3::ZERO, DVec3::ONE);
        // σ = 30 at x = 0, −90 at x = 1: zero at x = 0.25.
        let nodes = (0..8)
            .map(|i| [0.1, 0.1, 0.1, if i & 1 == 0 { 30.0 } else { -90.0 }])
            .collect();
        let f = GridField::new(res, bounds, nodes, 1);
        let at = |x: f64| f.density(DVec3::new(x, 0.5, 0.5));
        assert!((at(0.1) - 18.0).abs() < 1e-9, "{}", at(0.1));
        assert!(at(0.249) > 0.0 && at(0.251) == 0.0 && at(0.9) == 0.0);
        assert_eq!(f.interpolate(DVec3::new(0.5, 0.5, 0.5))[3], -30.0);
        let g = ramp();
        let x = DVec3::new(0.3, 0.2, 0.7);
        assert_eq!(g.density(x), g.interpolate(x)[3]);
    }
}
