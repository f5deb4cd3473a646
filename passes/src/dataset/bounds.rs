//! Where the field lies: from the dataset's `aabb` key, instant-ngp's
//! `aabb_scale` (with its `scale` and `offset`), a bound the user gives, or
//! the cameras' common view.

use glam::DVec3;

use super::pose::Pose;
use crate::geometry::Aabb;

/// Where a dataset's bounds came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BoundsSource {
    /// The user's bound (`--bounds`).
    Given,
    /// The file's `aabb` key.
    AabbKey,
    /// instant-ngp's `aabb_scale` cube mapped back through `scale` and
    /// `offset`.
    NgpAabbScale,
    /// The cameras' common view ([`common_view`]).
    Cameras,
}

impl std::fmt::Display for BoundsSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BoundsSource::Given => "given on the command line",
            BoundsSource::AabbKey => "the file's `aabb`",
            BoundsSource::NgpAabbScale => "instant-ngp's `aabb_scale`, `scale` and `offset`",
            BoundsSource::Cameras => {
                "the cameras' common view (the point nearest every optical axis, and the half-width the median camera sees there)"
            }
        })
    }
}

/// instant-ngp's defaults for `scale` and `offset`.
pub const NGP_DEFAULT_SCALE: f64 = 0.33;
/// instant-ngp's default `offset` (in its own axes).
pub const NGP_DEFAULT_OFFSET: [f64; 3] = [0.5, 0.5, 0.5];

/// The world box instant-ngp trains in for `aabb_scale` a, `scale` s and
/// `offset` o: its unit cube grown to [0.5 − a/2, 0.5 + a/2]³ in its own
/// axes, where a world point p sits at perm(p)·s + o and perm takes
/// (x, y, z) to (y, z, x).
pub fn ngp_bounds(aabb_scale: f64, scale: f64, offset: [f64; 3]) -> Aabb {
    let (lo, hi) = (0.5 - 0.5 * aabb_scale, 0.5 + 0.5 * aabb_scale);
    // ngp axis k holds world axis perm[k]: ngp (x, y, z) = world (y, z, x).
    let world_axis_of_ngp = [1usize, 2, 0];
    let mut min = DVec3::ZERO;
    let mut max = DVec3::ZERO;
    for k in 0..3 {
        let a = (lo - offset[k]) / scale;
        let b = (hi - offset[k]) / scale;
        let w = world_axis_of_ngp[k];
        min[w] = a.min(b);
        max[w] = a.max(b);
    }
    Aabb::new(min, max)
}

/// A cube around what the cameras look at: centred on the least-squares
/// point nearest every optical axis, with half-width the median over the
/// cameras of (distance to that point) × tan(half the camera's narrower
/// field of view). `half_fovs` gives each camera's narrower half-angle.
/// None when the axes are (near) parallel: no common point.
pub fn common_view(poses: &[Pose], half_fovs: &[f64]) -> Option<Aabb> {
    // Σ (I − d dᵀ) c = Σ (I − d dᵀ) o.
    let mut a = glam::DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for p in poses {
        let d = p.forward();
        let m = glam::DMat3::IDENTITY - glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        a += m;
        b += m * p.origin();
    }
    if poses.len() < 2 || a.determinant().abs() < 1e-9 * (poses.len() as f64).powi(3) {
        return None;
    }
    let centre = a.inverse() * b;
    let mut halves: Vec<f64> = poses
        .iter()
        .zip(half_fovs)
        .map(|(p, h)| (centre - p.origin()).length() * h.tan())
        .collect();
    halves.sort_by(f64::total_cmp);
    let half = halves[halves.len() / 2];
    // A box too small to hold a node apart from its neighbours (a camera at
    // the common point) is no box.
    let scale = 1.0 + centre.abs().max_element();
    let b = Aabb::new(centre - DVec3::splat(half), centre + DVec3::splat(half));
    (half.is_finite() && half > 1e-6 * scale && b.is_valid()).then_some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// instant-ngp's defaults (scale 0.33, offset 0.5) with aabb_scale 1
    /// put its unit cube at ±1.515 around the world origin.
    #[test]
    fn ngp_cube_maps_back_to_the_world() {
        let b = ngp_bounds(1.0, NGP_DEFAULT_SCALE, NGP_DEFAULT_OFFSET);
        assert!((b.max - DVec3::splat(0.5 / 0.33)).length() < 1e-12);
        assert!((b.min + DVec3::splat(0.5 / 0.33)).length() < 1e-12);
        // An offset along ngp's x moves the world's y.
        let b = ngp_bounds(2.0, 0.5, [0.7, 0.5, 0.5]);
        assert!(
            (b.center() - DVec3::new(0.0, -0.4, 0.0)).length() < 1e-12,
            "{b:?}"
        );
        assert!((b.size() - DVec3::splat(4.0)).length() < 1e-12);
    }

    /// Cameras on a ring looking at a point find it, and the box is what
    /// they see there.
    #[test]
    fn a_ring_of_cameras_finds_its_target() {
        let target = DVec3::new(0.3, 0.5, -0.2);
        let poses: Vec<Pose> = (0..8)
            .map(|i| {
                let a = i as f64 * 0.785;
                let eye = target + DVec3::new(3.0 * a.cos(), 1.0, 3.0 * a.sin());
                Pose::new(Pose::looking_at(eye, target, DVec3::Y).matrix).unwrap()
            })
            .collect();
        let b = common_view(&poses, &[0.4; 8]).unwrap();
        assert!((b.center() - target).length() < 1e-9, "{b:?}");
        let half = 10f64.sqrt() * 0.4f64.tan();
        assert!((b.size().x - 2.0 * half).abs() < 1e-9);
        // Parallel cameras have no common point.
        let flat: Vec<Pose> = (0..4)
            .map(|i| Pose::new(glam::DMat4::from_translation(DVec3::X * i as f64)).unwrap())
            .collect();
        assert!(common_view(&flat, &[0.4; 4]).is_none());
    }
}
