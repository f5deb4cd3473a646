//! A procedural albedo texture: a 3D checkerboard in world space, so that a
//! field trained from photographs has texture to triangulate on.

use glam::DVec3;
use serde::Deserialize;

/// Cubes of edge `size` alternate between the primitive's albedo and
/// `albedo`: the cube holding x has the second colour when
/// ⌊x/size⌋ + ⌊y/size⌋ + ⌊z/size⌋ is odd.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checker {
    /// Edge of one cube (scene units).
    pub size: f64,
    /// The second colour.
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub albedo: DVec3,
}

impl Checker {
    /// Whether `x` lies in a cube of the second colour.
    pub fn odd(&self, x: DVec3) -> bool {
        let c = (x / self.size).floor();
        (c.x + c.y + c.z).rem_euclid(2.0) == 1.0
    }

    /// The albedo at `x`, given the primitive's own `base`.
    pub fn albedo_at(&self, base: DVec3, x: DVec3) -> DVec3 {
        if self.odd(x) {
            self.albedo
        } else {
            base
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_cubes_alternate_across_zero() {
        let c = Checker {
            size: 0.5,
            albedo: DVec3::ONE,
        };
        let base = DVec3::ZERO;
        assert_eq!(c.albedo_at(base, DVec3::splat(0.1)), base);
        assert_eq!(c.albedo_at(base, DVec3::new(0.6, 0.1, 0.1)), DVec3::ONE);
        assert_eq!(c.albedo_at(base, DVec3::new(-0.1, 0.1, 0.1)), DVec3::ONE);
        assert_eq!(c.albedo_at(base, DVec3::new(-0.1, -0.1, 0.1)), base);
        assert_eq!(c.albedo_at(base, DVec3::new(-0.6, -0.1, 0.1)), DVec3::ONE);
    }
}
