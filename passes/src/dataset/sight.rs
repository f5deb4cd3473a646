//! Whether the cameras see the field's bounds: a camera that sees none of
//! them teaches the field nothing, and a dataset most of whose cameras look
//! away from them has poses in another camera convention, or bounds in
//! other units, more often than it is a capture of something else.

use glam::{DMat4, DVec4};

use super::intrinsics::Intrinsics;
use super::pose::Pose;
use crate::geometry::{ray_box, Aabb, Ray};

/// Rays along each side of the grid over an image by which [`sees_bounds`]
/// looks for the bounds (the image's edges included).
pub const SIGHT_RAYS: u32 = 16;

/// Whether a camera at `pose` with intrinsics `k` sees any of `bounds`:
/// one ray of a [`SIGHT_RAYS`]² grid over its image (edges included)
/// meets the box in front of the camera, or a corner or the centre of the
/// box lands on the image in front of it. A camera inside the box sees it.
/// A sliver of the box between the grid's rays with no corner on the image
/// is missed, which can only call a camera at a box's edge blind.
pub fn sees_bounds(pose: &Pose, k: &Intrinsics, bounds: &Aabb) -> bool {
    let (w, h) = (k.width as f64, k.height as f64);
    let last = (SIGHT_RAYS - 1) as f64;
    let origin = pose.origin();
    let ray_meets = (0..SIGHT_RAYS * SIGHT_RAYS).any(|i| {
        let u = w * (i % SIGHT_RAYS) as f64 / last;
        let v = h * (i / SIGHT_RAYS) as f64 / last;
        k.direction(u, v).is_some_and(|d| {
            let ray = Ray {
                origin,
                dir: pose.to_world(d),
            };
            ray_box(&ray, bounds).is_some_and(|(_, far)| far > 0.0)
        })
    });
    if ray_meets {
        return true;
    }
    let to_camera = pose.matrix.inverse();
    let mut points = bounds
        .corners()
        .into_iter()
        .chain(std::iter::once(bounds.center()));
    points.any(|p| {
        let d = to_camera.transform_point3(p);
        k.project(d)
            .is_some_and(|(u, v)| (0.0..=w).contains(&u) && (0.0..=h).contains(&v))
    })
}

/// `pose` read in OpenCV's camera convention (x right, y down, looking
/// along +z: COLMAP's, and many tools' that start from it) instead of the
/// OpenGL one `transforms.json` uses: the same matrix with its second and
/// third columns negated.
pub fn as_opencv(pose: &Pose) -> Pose {
    let flip = DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0));
    Pose {
        matrix: pose.matrix * flip,
    }
}

/// How many of `cameras` see none of `bounds` ([`sees_bounds`]): as read,
/// and with their poses read in OpenCV's convention ([`as_opencv`]).
pub struct Sight {
    /// The positions in `cameras` of those that see none of the bounds.
    pub blind: Vec<usize>,
    /// How many would see none of them read in OpenCV's convention.
    pub blind_as_opencv: usize,
    /// How many cameras there are.
    pub cameras: usize,
}

impl Sight {
    /// Which of `cameras` see `bounds`, read both ways.
    pub fn of<'a>(
        cameras: impl Iterator<Item = (&'a Pose, &'a Intrinsics)>,
        bounds: &Aabb,
    ) -> Self {
        let mut s = Sight {
            blind: Vec::new(),
            blind_as_opencv: 0,
            cameras: 0,
        };
        for (i, (pose, k)) in cameras.enumerate() {
            s.cameras += 1;
            if !sees_bounds(pose, k, bounds) {
                s.blind.push(i);
            }
            if !sees_bounds(&as_opencv(pose), k, bounds) {
                s.blind_as_opencv += 1;
            }
        }
        s
    }

    /// Why the poses cannot be trained on as read, if they cannot: more
    /// than half the cameras see none of the bounds. Where OpenCV's
    /// convention would at least halve those, the message says how to
    /// convert the poses; otherwise it names the bounds' units and axes,
    /// and poses written world-to-camera.
    pub fn problem(&self) -> Option<String> {
        let blind = self.blind.len();
        if 2 * blind <= self.cameras {
            return None;
        }
        let head = format!(
            "{blind} of the {} frames' cameras see none of the field's bounds",
            self.cameras
        );
        Some(if 2 * self.blind_as_opencv <= blind {
            format!(
                "{head}; {} would see them read in OpenCV's camera convention (x right, y \
                 down, looking along +z; COLMAP's): transform_matrix is camera-to-world in OpenGL's \
                 (y up, looking along −z), so negate the second and third columns of each \
                 frame's matrix",
                self.cameras - self.blind_as_opencv
            )
        } else {
            format!(
                "{head}: check that the bounds (`aabb`, `aabb_scale`, --bounds) are in the \
                 poses' units and axes, and that the poses are camera-to-world (not their \
                 inverse)"
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn ring(count: usize, target: DVec3) -> Vec<Pose> {
        (0..count)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / count as f64;
                let eye = target + DVec3::new(3.0 * a.cos(), 1.0, 3.0 * a.sin());
                Pose::looking_at(eye, target, DVec3::Y)
            })
            .collect()
    }

    /// Cameras looking at the box see it, from inside it too; read in
    /// OpenCV's convention they look away, and the problem says to convert.
    #[test]
    fn cameras_that_look_away_from_the_bounds_are_found_and_the_convention_named() {
        let b = Aabb::new(DVec3::splat(-0.5), DVec3::splat(0.5));
        let k = Intrinsics::centred(64, 48, 40.0);
        let poses = ring(8, DVec3::ZERO);
        let sight = Sight::of(poses.iter().map(|p| (p, &k)), &b);
        assert!(sight.blind.is_empty());
        assert_eq!(sight.blind_as_opencv, 8);
        assert_eq!(sight.problem(), None);
        // Inside the box, looking out: the box is all around.
        let inside = Pose::looking_at(DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!(sees_bounds(&inside, &k, &b));
        // A floor far larger than the view, so that no corner lands on the
        // image: the rays find it.
        let wide = Aabb::new(DVec3::new(-1e3, -1.0, -1e3), DVec3::new(1e3, -0.9, 1e3));
        assert!(sees_bounds(&poses[0], &k, &wide));
        // A box far smaller than a pixel at the view's centre: its corners
        // land on the image though no ray meets it.
        let tiny = Aabb::new(DVec3::splat(-1e-4), DVec3::splat(1e-4));
        assert!(sees_bounds(&poses[0], &k, &tiny));

        // The same cameras written in OpenCV's convention.
        let cv: Vec<Pose> = poses.iter().map(as_opencv).collect();
        let sight = Sight::of(cv.iter().map(|p| (p, &k)), &b);
        assert_eq!(sight.blind, (0..8).collect::<Vec<_>>());
        assert_eq!(sight.blind_as_opencv, 0);
        let p = sight.problem().unwrap();
        assert!(p.contains("8 of the 8") && p.contains("OpenCV"), "{p}");

        // Bounds far off to the side: no convention helps; the bounds are
        // named.
        let off = Aabb::new(DVec3::splat(40.0), DVec3::splat(41.0));
        let p = Sight::of(poses.iter().map(|p| (p, &k)), &off)
            .problem()
            .unwrap();
        assert!(
            p.contains("check that the bounds") && !p.contains("OpenCV"),
            "{p}"
        );

        // Most cameras looking away, and no convention that would help.
        let mut most = poses.clone();
        for p in most.iter_mut().take(5) {
            *p = Pose::looking_at(p.origin(), p.origin() * 2.0, DVec3::Y);
        }
        let sight = Sight::of(most.iter().map(|p| (p, &k)), &b);
        assert_eq!(sight.blind, vec![0, 1, 2, 3, 4]);
        let p = sight.problem().unwrap();
        assert!(
            p.contains("5 of the 8") && p.contains("not their inverse"),
            "{p}"
        );

        // A few cameras looking elsewhere are not a problem.
        let mut some = poses.clone();
        some[3] = Pose::looking_at(some[3].origin(), some[3].origin() * 2.0, DVec3::Y);
        let sight = Sight::of(some.iter().map(|p| (p, &k)), &b);
        assert_eq!(sight.blind, vec![3]);
        assert_eq!(sight.problem(), None);
    }
}
