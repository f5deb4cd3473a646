//! Rays and axis-aligned boxes: the geometry every pass shares. Mirrored in
//! `shaders/common/ray_box.wgsl`.

mod mesh_bvh;

pub use mesh_bvh::{MeshHit, MeshScene, MeshSurface};

use glam::DVec3;
use serde::Deserialize;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Aabb {
    /// Smallest corner.
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub min: DVec3,
    /// Largest corner.
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub max: DVec3,
}

impl Aabb {
    /// A box from its corners.
    pub fn new(min: DVec3, max: DVec3) -> Self {
        Self { min, max }
    }

    /// Edge lengths.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// The centre point.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }

    /// The eight corners, corner k taking max along x where bit 0 of k is
    /// set, along y for bit 1, along z for bit 2.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|k| {
            DVec3::new(
                if k & 1 == 0 { self.min.x } else { self.max.x },
                if k & 2 == 0 { self.min.y } else { self.max.y },
                if k & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// Whether every edge is finite and positive.
    pub fn is_valid(&self) -> bool {
        self.min.is_finite() && self.max.is_finite() && self.min.cmplt(self.max).all()
    }

    /// Whether `p` lies inside or on the box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Whether `other` lies entirely inside this box.
    pub fn contains_box(&self, other: &Aabb) -> bool {
        self.contains(other.min) && self.contains(other.max)
    }

    /// Whether the two boxes overlap (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }
}

/// A ray `origin + t·dir` (`dir` need not be unit length, but the passes use
/// unit directions so that `t` is a distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: DVec3,
    /// Direction.
    pub dir: DVec3,
}

impl Ray {
    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }
}

/// Entry and exit parameters of `ray` through `aabb` (slab method), clamped
/// to `t ≥ 0`; `None` when the ray misses. Zero direction components are
/// handled by IEEE infinities, as in the WGSL mirror.
pub fn ray_box(ray: &Ray, aabb: &Aabb) -> Option<(f64, f64)> {
    let inv = DVec3::ONE / ray.dir;
    let t0 = (aabb.min - ray.origin) * inv;
    let t1 = (aabb.max - ray.origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    // `max_element` of a vector holding NaN (0·∞ when the origin lies on a
    // slab plane of a zero component) must ignore it: fold by hand.
    let t_near = [near.x, near.y, near.z]
        .into_iter()
        .filter(|v| !v.is_nan())
        .fold(0.0_f64, f64::max);
    let t_far = [far.x, far.y, far.z]
        .into_iter()
        .filter(|v| !v.is_nan())
        .fold(f64::INFINITY, f64::min);
    (t_near <= t_far).then_some((t_near, t_far))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_box_hits_misses_and_starts_inside() {
        let b = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let r = Ray {
            origin: DVec3::new(0.0, 0.0, -5.0),
            dir: DVec3::Z,
        };
        assert_eq!(ray_box(&r, &b), Some((4.0, 6.0)));
        let miss = Ray {
            origin: DVec3::new(2.0, 0.0, -5.0),
            dir: DVec3::Z,
        };
        assert_eq!(ray_box(&miss, &b), None);
        let inside = Ray {
            origin: DVec3::ZERO,
            dir: DVec3::X,
        };
        assert_eq!(ray_box(&inside, &b), Some((0.0, 1.0)));
        let behind = Ray {
            origin: DVec3::new(0.0, 0.0, 5.0),
            dir: DVec3::Z,
        };
        assert_eq!(ray_box(&behind, &b), None);
    }
}
