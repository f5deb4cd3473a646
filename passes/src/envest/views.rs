//! The random views surface points are drawn from (METHOD.md "Environment
//! light estimation"): cameras on a sphere around the field's centre, at
//! half the field's size (its longest side) from it, looking at the centre;
//! or, for a field trained from photographs, the photographs' own cameras
//! ([`ViewSource::Cameras`]).
//!
//! A field a trainer made is right only where its photographs saw it,
//! and a real capture's field may not be whole from every side; its
//! cameras are views it is right from. On DOG, whose photographs all look
//! down from a cap, they constrain the light less than the sphere does
//! (docs/fidelity.md, "Eleventh pass"), so the sphere stays the default.

use glam::DVec3;

use crate::camera::CameraSpec;
use crate::geometry::Aabb;
use crate::rng::Pcg32;

/// Vertical field of view of the sampled views, in degrees.
pub const VIEW_FOV_DEGREES: f64 = 60.0;

/// Where the estimate's views come from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ViewSource {
    /// Random directions on a sphere around the field (the paper's; for
    /// fields right from every side, such as baked ones).
    #[default]
    Sphere,
    /// These cameras (a trained field's photographs'), taken in a seeded
    /// random order, each once before any repeats; a repeated camera
    /// draws other pixels.
    Cameras(Vec<CameraSpec>),
}

impl ViewSource {
    /// The `index`-th view of `bounds` for `seed`.
    pub fn view(&self, bounds: &Aabb, seed: u64, index: u64) -> CameraSpec {
        match self {
            ViewSource::Cameras(cameras) if !cameras.is_empty() => {
                let n = cameras.len() as u64;
                // A seeded shuffle of 0..n, drawn afresh for each round.
                let round = index / n;
                let mut order: Vec<usize> = (0..cameras.len()).collect();
                let mut rng = Pcg32::new(seed, 0x6361_6d73_0000_0000 ^ round);
                for i in (1..order.len()).rev() {
                    let j = rng.next_u32() as usize % (i + 1);
                    order.swap(i, j);
                }
                cameras[order[(index % n) as usize]].clone()
            }
            _ => random_view(bounds, seed, index),
        }
    }

    /// How many distinct views it can give (`None`: unbounded).
    pub fn distinct(&self) -> Option<usize> {
        match self {
            ViewSource::Cameras(c) if !c.is_empty() => Some(c.len()),
            _ => None,
        }
    }
}

/// The `index`-th random view of `bounds` for `seed`: a direction uniform
/// on the sphere, the camera half the longest side from the centre.
pub fn random_view(bounds: &Aabb, seed: u64, index: u64) -> CameraSpec {
    let mut rng = Pcg32::new(seed, 0x7669_6577_0000_0000 ^ index);
    let [u, v] = rng.next_2d();
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * v;
    let dir = DVec3::new(r * phi.cos(), z, r * phi.sin());
    let centre = bounds.center();
    let distance = 0.5 * bounds.size().max_element();
    let up = if dir.y.abs() > 0.99 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    CameraSpec {
        name: Some(format!("estimate-view-{index}")),
        position: centre + distance * dir,
        look_at: centre,
        up,
        fov_y: VIEW_FOV_DEGREES,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cameras come each once per round, in a seeded order.
    #[test]
    fn cameras_are_each_used_once_before_any_repeats() {
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let cameras: Vec<CameraSpec> = (0..5).map(|i| random_view(&bounds, 9, i)).collect();
        let source = ViewSource::Cameras(cameras.clone());
        let index_of = |c: &CameraSpec| cameras.iter().position(|d| d == c).unwrap();
        for round in 0..3u64 {
            let mut seen: Vec<usize> = (0..5)
                .map(|i| index_of(&source.view(&bounds, 1, round * 5 + i)))
                .collect();
            seen.sort();
            assert_eq!(seen, vec![0, 1, 2, 3, 4]);
        }
        let first: Vec<usize> = (0..5)
            .map(|i| index_of(&source.view(&bounds, 1, i)))
            .collect();
        let other: Vec<usize> = (0..5)
            .map(|i| index_of(&source.view(&bounds, 2, i)))
            .collect();
        assert_ne!(first, other, "the order depends on the seed");
        assert_eq!(source.distinct(), Some(5));
        assert_eq!(
            ViewSource::Sphere.view(&bounds, 3, 4),
            random_view(&bounds, 3, 4)
        );
    }
}
