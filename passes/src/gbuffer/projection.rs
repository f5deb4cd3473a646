//! The raster projection matching the march's pinhole rays: a pixel centre
//! projects exactly where `CameraFrame::pixel_ray` points, so the G-buffer
//! and the march agree on every pixel. Near and far planes hug the objects'
//! bounding spheres to keep depth precision.

use glam::{DMat4, DVec3, DVec4};

use crate::camera::CameraFrame;

/// World → WGSL clip space (x right, y up, depth in [0, 1]; naga flips y
/// for Vulkan) for `camera`, with near/far planes around `spheres`
/// (centre, radius).
pub fn view_projection(camera: &CameraFrame, spheres: &[(DVec3, f64)]) -> DMat4 {
    let f = camera.forward;
    let mut far = 0.0f64;
    let mut near = f64::INFINITY;
    for &(c, r) in spheres {
        let z = (c - camera.origin).dot(f);
        far = far.max(z + r);
        near = near.min(z - r);
    }
    let far = (far * 1.01).max(1e-3);
    // A camera inside a sphere (or behind one) gets a near plane close to it.
    let near = near.clamp(far * 1e-5, far * 0.999);
    let o = camera.origin;
    let row = |axis: DVec3, scale: f64| (axis * scale).extend(-axis.dot(o) * scale);
    let r = row(camera.right, 1.0 / camera.right.length_squared());
    let u = row(camera.up, 1.0 / camera.up.length_squared());
    let w = row(f, 1.0);
    let k = far / (far - near);
    let z = w * k - DVec4::new(0.0, 0.0, 0.0, near * k);
    DMat4::from_cols(r, u, z, w).transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraSpec;

    /// Points along a pixel's ray land on that pixel's centre, at depths
    /// between 0 (near) and 1 (far).
    #[test]
    fn pixel_rays_project_to_their_pixel_centres() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(0.3, 1.0, 2.0),
            look_at: DVec3::new(0.0, 0.2, 0.0),
            up: DVec3::Y,
            fov_y: 40.0,
        };
        let cam = CameraFrame::new(&spec, 64, 48);
        let m = view_projection(&cam, &[(DVec3::new(0.0, 0.2, 0.0), 0.5)]);
        for (px, py) in [(0, 0), (63, 47), (10, 30), (32, 24)] {
            let ray = cam.pixel_ray(px, py);
            let mut last = -1.0;
            for t in [2.0, 2.2, 2.4] {
                let c = m * ray.at(t).extend(1.0);
                let ndc = c.truncate() / c.w;
                let x = (ndc.x + 1.0) * 0.5 * 64.0;
                let y = (1.0 - ndc.y) * 0.5 * 48.0;
                assert!((x - (px as f64 + 0.5)).abs() < 1e-9, "{x}");
                assert!((y - (py as f64 + 0.5)).abs() < 1e-9, "{y}");
                assert!(ndc.z > last && (0.0..=1.0).contains(&ndc.z), "{}", ndc.z);
                last = ndc.z;
            }
        }
    }
}
