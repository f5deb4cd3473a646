//! The random views surface points are drawn from (METHOD.md "Environment
//! light estimation"): cameras on a sphere around the field's centre, at
//! half the field's size (its longest side) from it, looking at the centre.

use glam::DVec3;

use crate::camera::CameraSpec;
use crate::geometry::Aabb;
use crate::rng::Pcg32;

/// Vertical field of view of the sampled views, in degrees.
pub const VIEW_FOV_DEGREES: f64 = 60.0;

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
