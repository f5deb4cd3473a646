//! Pinhole cameras: the scene-file description and the per-image frame that
//! turns a pixel into a ray. Mirrored in `shaders/common/camera.wgsl`.

use glam::DVec3;
use serde::Deserialize;

use crate::geometry::Ray;

/// A camera as a scene file describes it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Optional name, for messages and `--camera NAME`.
    #[serde(default)]
    pub name: Option<String>,
    /// Eye position.
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub position: DVec3,
    /// Point the camera looks at.
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub look_at: DVec3,
    /// Approximate up direction (default +Y).
    #[serde(default = "default_up")]
    #[serde(deserialize_with = "crate::scene::vec3::exact")]
    pub up: DVec3,
    /// Vertical field of view in degrees (default 50).
    #[serde(default = "default_fov")]
    pub fov_y: f64,
}

fn default_up() -> DVec3 {
    DVec3::Y
}

fn default_fov() -> f64 {
    50.0
}

impl CameraSpec {
    /// Why the camera cannot be used, if it cannot.
    pub fn problem(&self) -> Option<String> {
        if !(self.position.is_finite() && self.look_at.is_finite() && self.up.is_finite()) {
            return Some("position, look_at and up must be finite".into());
        }
        let f = self.look_at - self.position;
        if !f.is_finite() {
            return Some("look_at − position overflows: bring them closer to the origin".into());
        }
        if f.length() < 1e-9 {
            return Some("look_at equals position".into());
        }
        let unit = crate::scene::vec3::unit;
        let across = unit(f).zip(unit(self.up)).map(|(f, u)| f.cross(u).length());
        if across.is_none_or(|a| a < 1e-6) {
            return Some("up is zero or parallel to the viewing direction".into());
        }
        if !(self.fov_y > 0.0 && self.fov_y < 179.0) {
            return Some(format!(
                "fov_y = {} is outside (0, 179) degrees",
                self.fov_y
            ));
        }
        None
    }
}

/// A camera set up for one image size: origin and the scaled basis vectors a
/// pixel's normalised coordinates multiply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    /// Eye position.
    pub origin: DVec3,
    /// Right vector scaled by tan(fov/2)·aspect.
    pub right: DVec3,
    /// Up vector scaled by tan(fov/2).
    pub up: DVec3,
    /// Unit viewing direction.
    pub forward: DVec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl CameraFrame {
    /// The frame of `spec` for a `width`×`height` image (the spec must have
    /// no [`CameraSpec::problem`]).
    pub fn new(spec: &CameraSpec, width: u32, height: u32) -> Self {
        // As `normalize()` for every camera `problem()` accepts; a default
        // frame, never NaN, for one it refuses.
        let unit = crate::scene::vec3::unit;
        let forward = unit(spec.look_at - spec.position).unwrap_or(DVec3::NEG_Z);
        let right = unit(forward.cross(unit(spec.up).unwrap_or(DVec3::Y))).unwrap_or(DVec3::X);
        let up = right.cross(forward);
        let tan = (spec.fov_y.to_radians() * 0.5).tan();
        let aspect = width as f64 / height as f64;
        Self {
            origin: spec.position,
            right: right * tan * aspect,
            up: up * tan,
            forward,
            width,
            height,
        }
    }

    /// The unit-direction ray through image position (`x`, `y`) in pixels
    /// (pixel centres at +0.5; y grows downwards).
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let nx = 2.0 * x / self.width as f64 - 1.0;
        let ny = 1.0 - 2.0 * y / self.height as f64;
        Ray {
            origin: self.origin,
            dir: (self.forward + nx * self.right + ny * self.up).normalize(),
        }
    }

    /// The ray through the centre of pixel (`px`, `py`).
    pub fn pixel_ray(&self, px: u32, py: u32) -> Ray {
        self.ray(px as f64 + 0.5, py as f64 + 0.5)
    }

    /// Where `p` lands in the image, in pixels (the inverse of
    /// [`Self::ray`]), or None when it is not in front of the camera.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if z <= 1e-9 {
            return None;
        }
        let nx = d.dot(self.right) / (z * self.right.length_squared());
        let ny = d.dot(self.up) / (z * self.up.length_squared());
        Some((
            (nx + 1.0) * 0.5 * self.width as f64,
            (1.0 - ny) * 0.5 * self.height as f64,
        ))
    }

    /// Whether any of the sphere (`centre`, `radius`) can be in the image:
    /// false only when it lies wholly behind the eye or outside one of the
    /// four side planes of the view frustum (conservative near corners).
    pub fn sphere_visible(&self, centre: DVec3, radius: f64) -> bool {
        let d = centre - self.origin;
        if d.dot(self.forward) < -radius {
            return false;
        }
        // The side planes through the eye, each spanned by a frustum edge
        // direction and an image axis; normals turned to face inwards.
        let planes = [
            (self.forward + self.right).cross(self.up),
            (self.forward - self.right).cross(self.up),
            (self.forward + self.up).cross(self.right),
            (self.forward - self.up).cross(self.right),
        ];
        planes.iter().all(|n| {
            let n = n.normalize();
            let inward = if n.dot(self.forward) < 0.0 { -n } else { n };
            d.dot(inward) >= -radius
        })
    }

    /// The pixels the sphere (`centre`, `radius`) can cover, as (x0, y0,
    /// x1, y1) with the ends exclusive, clipped to the image (empty where
    /// it misses the image): the projection of its bounding cube's corners,
    /// widened by a pixel. None when the cube reaches behind the image
    /// plane (the sphere may then cover any pixel).
    pub fn sphere_pixels(&self, centre: DVec3, radius: f64) -> Option<[u32; 4]> {
        let (mut lo, mut hi) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for corner in 0..8 {
            let s = |bit: u32| if corner & bit == 0 { -radius } else { radius };
            let (x, y) = self.project(centre + DVec3::new(s(1), s(2), s(4)))?;
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        let clip = |v: f64, n: u32| v.clamp(0.0, n as f64) as u32;
        Some([
            clip((lo.0 - 1.0).floor(), self.width),
            clip((lo.1 - 1.0).floor(), self.height),
            clip((hi.0 + 1.0).ceil(), self.width),
            clip((hi.1 + 1.0).ceil(), self.height),
        ])
    }

    /// The camera as the march, shading and cast-shadow push blocks hold
    /// it (f32, with the image size).
    pub fn rays(&self) -> CameraRays {
        CameraRays {
            origin: self.origin.as_vec3().to_array(),
            width: self.width,
            right: self.right.as_vec3().to_array(),
            height: self.height,
            up: self.up.as_vec3().to_array(),
            _pad0: 0,
            forward: self.forward.as_vec3().to_array(),
            _pad1: 0,
        }
    }
}

inlay_engine::gpu_struct! {
    /// A camera frame in f32 as the per-pixel passes' push blocks
    /// (`MarchPush`, `ShadePush`, `CastPush`) carry it: `CameraRays` of
    /// `shaders/common/camera.wgsl`.
    pub struct CameraRays = "common/camera.wgsl" : "CameraRays" {
        /// The eye.
        pub origin: [f32; 3],
        /// Image width.
        pub width: u32,
        /// Right, scaled to the half-width at unit distance.
        pub right: [f32; 3],
        /// Image height.
        pub height: u32,
        /// Up, scaled to the half-height at unit distance.
        pub up: [f32; 3],
        /// Padding (WGSL aligns the next vec3 to 16 bytes).
        pub _pad0: u32,
        /// Forward (unit).
        pub forward: [f32; 3],
        /// Padding (the struct's size rounds up to 16 bytes).
        pub _pad1: u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel whose ray meets the sphere lies in `sphere_pixels`; a
    /// sphere around the eye, or behind it, gives None.
    #[test]
    fn sphere_pixels_hold_every_pixel_the_sphere_covers() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(0.3, 0.8, 2.0),
            look_at: DVec3::new(0.0, 0.2, 0.0),
            up: DVec3::Y,
            fov_y: 45.0,
        };
        let cam = CameraFrame::new(&spec, 64, 48);
        for (centre, radius) in [
            (DVec3::new(0.0, 0.2, 0.0), 0.1),
            (DVec3::new(-0.4, 0.0, 0.3), 0.25),
            (DVec3::new(0.9, 0.5, -0.5), 0.05),
        ] {
            let [x0, y0, x1, y1] = cam.sphere_pixels(centre, radius).unwrap();
            let mut hits = 0;
            for py in 0..48 {
                for px in 0..64 {
                    let r = cam.pixel_ray(px, py);
                    let oc = r.origin - centre;
                    let b = oc.dot(r.dir);
                    if b * b - (oc.length_squared() - radius * radius) >= 0.0 && b < 0.0 {
                        hits += 1;
                        assert!(px >= x0 && px < x1 && py >= y0 && py < y1, "({px}, {py})");
                    }
                }
            }
            assert!(hits > 0);
            assert!((x1 - x0) * (y1 - y0) < 64 * 48);
        }
        assert!(cam.sphere_pixels(spec.position, 0.1).is_none());
    }

    #[test]
    fn centre_pixel_looks_forward_and_corners_span_the_fov() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(0.0, 0.0, 5.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov_y: 90.0,
        };
        assert!(spec.problem().is_none());
        let f = CameraFrame::new(&spec, 200, 100);
        let c = f.ray(100.0, 50.0);
        assert!((c.dir - DVec3::NEG_Z).length() < 1e-12);
        let top = f.ray(100.0, 0.0);
        assert!((top.dir.angle_between(DVec3::NEG_Z).to_degrees() - 45.0).abs() < 1e-9);
        assert!(top.dir.y > 0.0);
        let right = f.ray(200.0, 50.0);
        assert!(right.dir.x > 0.0);
    }

    #[test]
    fn projection_inverts_the_ray_and_the_frustum_test_is_exact_on_its_planes() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(0.3, 1.0, 4.0),
            look_at: DVec3::new(0.0, 0.2, 0.0),
            up: DVec3::Y,
            fov_y: 60.0,
        };
        let f = CameraFrame::new(&spec, 320, 180);
        for (x, y) in [(0.5, 0.5), (160.0, 90.0), (300.25, 12.75)] {
            let p = f.ray(x, y).at(3.0);
            let (px, py) = f.project(p).unwrap();
            assert!((px - x).abs() < 1e-9 && (py - y).abs() < 1e-9);
            assert!(f.sphere_visible(p, 0.0));
        }
        assert!(f.project(f.origin - f.forward).is_none());
        assert!(!f.sphere_visible(f.origin - 2.0 * f.forward, 1.0));
        assert!(f.sphere_visible(f.origin - 2.0 * f.forward, 2.5));
        // Just past the right edge at depth 3: out for a small sphere, in
        // once its radius reaches across the plane.
        let edge = f.ray(320.0, 90.0).at(3.0);
        let outward = f.right.normalize();
        assert!(!f.sphere_visible(edge + 0.2 * outward, 0.1));
        assert!(f.sphere_visible(edge + 0.2 * outward, 0.2));
        let top = f.ray(160.0, 0.0).at(3.0);
        assert!(!f.sphere_visible(top + 0.3 * f.up.normalize(), 0.1));
    }

    #[test]
    fn degenerate_cameras_are_named() {
        let mut spec = CameraSpec {
            name: None,
            position: DVec3::ZERO,
            look_at: DVec3::Y,
            up: DVec3::Y,
            fov_y: 50.0,
        };
        assert!(spec.problem().unwrap().contains("parallel"));
        spec.look_at = DVec3::ZERO;
        assert!(spec.problem().unwrap().contains("equals"));
        spec.look_at = DVec3::X;
        spec.fov_y = 0.0;
        assert!(spec.problem().unwrap().contains("fov_y"));
    }
}
