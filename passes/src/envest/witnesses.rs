//! Which surface points a field's photographs saw.
//!
//! A trained field is right only where its photographs looked. The
//! estimate's views come from all around the field (the paper's sphere),
//! and from below DOG's floor they see its underside, which no photograph
//! did: the trainer gave it the colour of the lit top, which the fit can
//! only read as light from below (on DOG trained at 128 nodes from 64
//! views, a tenth of the points, their radiance ~400× the bake's; leaving
//! them out did not move DOG's error beyond its seeds' spread, the rest
//! outweighing them: `docs/fidelity.md`, "Thirteenth pass"). With
//! witnesses, a surface point is kept only when some photograph saw it:
//! the point faces the camera, lies inside its view, and the field between
//! them is under half opaque (marched from [`START_OFFSET`] node spacings
//! off the surface, out of its own shell).

use glam::DVec3;

use crate::camera::{CameraFrame, CameraSpec};
use crate::field::GridField;
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};

/// How far along its normal, in node spacings, the march toward a camera
/// starts from a surface point (a trained surface's density is a shell a
/// couple of nodes deep; the point sits inside it).
pub const START_OFFSET: f64 = 2.0;

/// Opacity between a point and a camera under which the camera saw it.
pub const MAX_OCCLUSION: f64 = 0.5;

/// One photograph's camera: where it was and what it took in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Witness {
    /// Its frame (position, orientation, field of view, image size).
    pub frame: CameraFrame,
}

impl Witness {
    /// The camera `spec` whose image is `width` × `height` (only their
    /// ratio matters).
    pub fn new(spec: &CameraSpec, width: u32, height: u32) -> Self {
        Self {
            frame: CameraFrame::new(spec, width, height),
        }
    }

    /// Whether `x` lies inside the camera's view.
    pub fn frames(&self, x: DVec3) -> bool {
        let (w, h) = (self.frame.width as f64, self.frame.height as f64);
        self.frame
            .project(x)
            .is_some_and(|(u, v)| (0.0..=w).contains(&u) && (0.0..=h).contains(&v))
    }
}

/// The cameras a field was made from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Witnesses {
    /// Every camera.
    pub cameras: Vec<Witness>,
}

impl Witnesses {
    /// Whether some camera saw the surface point `x` of `field` whose
    /// normal is `normal`: facing it, inside its view, and the field
    /// between (marched with `knobs`) under [`MAX_OCCLUSION`] opaque.
    pub fn saw(&self, field: &GridField, knobs: &MarchKnobs, x: DVec3, normal: DVec3) -> bool {
        let start = x + START_OFFSET * field.spacing().min_element() * normal;
        self.cameras.iter().any(|c| {
            let to_camera = c.frame.origin - start;
            if normal.dot(to_camera) <= 0.0 || !c.frames(x) {
                return false;
            }
            let distance = to_camera.length();
            let ray = Ray {
                origin: start,
                dir: to_camera / distance,
            };
            march_ray(field, &ray, distance, knobs).opacity < MAX_OCCLUSION
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::UVec3;

    /// A floor slab at y ≈ 0 under a camera high above; a wall on one side.
    fn floor_and_wall() -> GridField {
        let res = UVec3::new(21, 21, 21);
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let h = 0.1;
        let nodes = (0..res.x * res.y * res.z)
            .map(|n| {
                let (i, j) = (n % res.x, (n / res.x) % res.y);
                let (x, y) = (-1.0 + h * i as f64, -1.0 + h * j as f64);
                let floor = y.abs() < 0.05;
                // A wall at x = 0.5 from the floor up, between the
                // camera at x = 3 and the floor's left half.
                let wall = (x - 0.5).abs() < 0.05 && y > 0.0;
                let sigma = if floor || wall { 200.0 } else { 0.0 };
                [0.5, 0.5, 0.5, sigma]
            })
            .collect();
        GridField::new(res, bounds, nodes, 4)
    }

    fn camera(position: DVec3, look_at: DVec3) -> Witness {
        Witness::new(
            &CameraSpec {
                name: None,
                position,
                look_at,
                up: DVec3::Y,
                fov_y: 60.0,
            },
            3,
            2,
        )
    }

    /// The floor's top is seen from above, its underside is not; a point
    /// behind the wall is not, nor one out of the camera's view.
    #[test]
    fn a_point_counts_as_seen_only_facing_a_camera_with_nothing_between() {
        let field = floor_and_wall();
        let knobs = MarchKnobs::default();
        let above = Witnesses {
            cameras: vec![camera(DVec3::new(0.0, 3.0, 0.1), DVec3::ZERO)],
        };
        let top = DVec3::new(0.2, 0.05, 0.0);
        assert!(above.saw(&field, &knobs, top, DVec3::Y));
        assert!(!above.saw(&field, &knobs, DVec3::new(0.2, -0.05, 0.0), -DVec3::Y));
        // From the right, low: the wall hides the floor's left half.
        let right = Witnesses {
            cameras: vec![camera(DVec3::new(3.0, 0.6, 0.0), DVec3::ZERO)],
        };
        assert!(right.saw(&field, &knobs, DVec3::new(0.8, 0.05, 0.0), DVec3::Y));
        assert!(!right.saw(&field, &knobs, DVec3::new(-0.3, 0.05, 0.0), DVec3::Y));
        // Looking away from the point.
        let away = Witnesses {
            cameras: vec![camera(DVec3::new(0.0, 3.0, 0.0), DVec3::new(0.0, 6.0, 0.5))],
        };
        assert!(!away.saw(&field, &knobs, top, DVec3::Y));
        // Any one camera suffices.
        let both = Witnesses {
            cameras: [away.cameras.clone(), above.cameras.clone()].concat(),
        };
        assert!(both.saw(&field, &knobs, top, DVec3::Y));
        assert!(!Witnesses::default().saw(&field, &knobs, top, DVec3::Y));
    }
}
