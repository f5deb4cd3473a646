//! Where an SSDF field is sampled: a cube of n³ nodes centred at the
//! object's bounding-sphere centre, its side 3 × the sphere's radius
//! (METHOD.md "SSDF field"), in the object's own frame.

use glam::{DVec3, UVec3};

/// The side of the grid in bounding-sphere radii.
pub const GRID_SIDE_IN_RADII: f64 = 3.0;

/// The node lattice of an SSDF field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsdfGrid {
    /// Centre (object space): the bounding sphere's centre.
    pub centre: DVec3,
    /// The bounding sphere's radius.
    pub radius: f64,
    /// Nodes along each axis (≥ 2).
    pub nodes: u32,
}

impl SsdfGrid {
    /// Half the grid's side.
    pub fn half_side(&self) -> f64 {
        0.5 * GRID_SIDE_IN_RADII * self.radius
    }

    /// Distance between neighbouring nodes.
    pub fn spacing(&self) -> f64 {
        2.0 * self.half_side() / (self.nodes - 1) as f64
    }

    /// Number of nodes.
    pub fn count(&self) -> usize {
        (self.nodes as usize).pow(3)
    }

    /// Node index (x fastest) of lattice coordinates.
    pub fn index(&self, n: UVec3) -> usize {
        let s = self.nodes as usize;
        n.x as usize + s * (n.y as usize + s * n.z as usize)
    }

    /// The position of the node with lattice coordinates `n`.
    pub fn position(&self, n: UVec3) -> DVec3 {
        self.centre - DVec3::splat(self.half_side()) + n.as_dvec3() * self.spacing()
    }

    /// The lattice coordinates of node `i` (x fastest).
    pub fn coordinates(&self, i: usize) -> UVec3 {
        let s = self.nodes as usize;
        UVec3::new((i % s) as u32, ((i / s) % s) as u32, (i / (s * s)) as u32)
    }

    /// The position of node `i` (x fastest).
    pub fn position_of(&self, i: usize) -> DVec3 {
        self.position(self.coordinates(i))
    }

    /// `p` in lattice units (0 at the first node, n − 1 at the last).
    pub fn lattice(&self, p: DVec3) -> DVec3 {
        (p - self.centre + DVec3::splat(self.half_side())) / self.spacing()
    }

    /// Whether `p` lies inside the grid's cube (boundary included).
    pub fn contains(&self, p: DVec3) -> bool {
        let l = self.lattice(p);
        let top = (self.nodes - 1) as f64;
        l.cmpge(DVec3::ZERO).all() && l.cmple(DVec3::splat(top)).all()
    }
}
