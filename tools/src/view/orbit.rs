//! The viewer's camera: orbit about a target point or fly from the eye.
//! Yaw and pitch give the viewing direction; the eye sits `distance`
//! behind the target. Orbiting turns about the target, looking turns about
//! the eye, panning and flying move both.

use glam::DVec3;
use inlay_passes::camera::CameraSpec;

/// Pitch stays this far (radians) from straight up or down, so the view
/// direction never lines up with +Y.
const PITCH_LIMIT: f64 = 1.55;

/// An orbit/fly camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// The point orbited.
    pub target: DVec3,
    /// Heading about +Y, radians (0 looks along −Z).
    pub yaw: f64,
    /// Elevation, radians (positive looks up).
    pub pitch: f64,
    /// Eye-to-target distance.
    pub distance: f64,
    /// Vertical field of view, degrees.
    pub fov_y: f64,
}

impl OrbitCamera {
    /// The camera matching a scene camera (its up taken as +Y).
    pub fn from_spec(spec: &CameraSpec) -> Self {
        let d = spec.look_at - spec.position;
        let distance = d.length().max(1e-6);
        let f = d / distance;
        Self {
            target: spec.look_at,
            yaw: f.x.atan2(-f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin().clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance,
            fov_y: spec.fov_y,
        }
    }

    /// The unit viewing direction.
    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(sy * cp, sp, -cy * cp)
    }

    /// The eye position.
    pub fn eye(&self) -> DVec3 {
        self.target - self.distance * self.forward()
    }

    /// The scene-file camera this is now.
    pub fn spec(&self) -> CameraSpec {
        CameraSpec {
            name: None,
            position: self.eye(),
            look_at: self.target,
            up: DVec3::Y,
            fov_y: self.fov_y,
        }
    }

    /// Turns about the target by `dyaw`, `dpitch` radians.
    pub fn orbit(&mut self, dyaw: f64, dpitch: f64) {
        self.yaw += dyaw;
        self.pitch = (self.pitch + dpitch).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Turns about the eye (fly mode's mouse look).
    pub fn look(&mut self, dyaw: f64, dpitch: f64) {
        let eye = self.eye();
        self.orbit(dyaw, dpitch);
        self.target = eye + self.distance * self.forward();
    }

    /// Moves eye and target by `right`, `up` and `ahead` distances along the
    /// camera's axes (up is world +Y).
    pub fn translate(&mut self, right: f64, up: f64, ahead: f64) {
        let f = self.forward();
        let r = f.cross(DVec3::Y).normalize_or_zero();
        self.target += right * r + up * DVec3::Y + ahead * f;
    }

    /// Moves the eye towards the target by the factor `scale` (< 1: closer).
    pub fn zoom(&mut self, scale: f64) {
        self.distance = (self.distance * scale).clamp(1e-3, 1e4);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_camera_survives_the_round_trip_and_orbiting_keeps_the_distance() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(1.0, 0.8, 2.5),
            look_at: DVec3::new(0.0, 0.1, 0.0),
            up: DVec3::Y,
            fov_y: 45.0,
        };
        let mut c = OrbitCamera::from_spec(&spec);
        assert!((c.eye() - spec.position).length() < 1e-12);
        assert!(c.spec().problem().is_none());
        c.orbit(0.7, 3.0);
        assert!((c.eye() - c.target).length() - spec.look_at.distance(spec.position) < 1e-12);
        assert!(c.pitch <= PITCH_LIMIT && c.spec().problem().is_none());
        let eye = c.eye();
        c.look(0.3, -0.2);
        assert!((c.eye() - eye).length() < 1e-12, "looking keeps the eye");
        c.translate(0.0, 0.5, 0.0);
        assert!((c.eye() - eye - DVec3::new(0.0, 0.5, 0.0)).length() < 1e-12);
    }
}
