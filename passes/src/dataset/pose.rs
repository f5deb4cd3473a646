//! Camera poses: the camera-to-world matrices of `transforms.json`, which
//! must be rigid (a rotation and a translation).

use glam::{DMat3, DMat4, DVec3};

/// How far RᵀR may stray from the identity, and the bottom row from
/// 0 0 0 1, for a pose to count as rigid (JSON files carry poses rounded
/// to 6–7 digits, and tools that wrote them in f32).
pub const RIGID_TOLERANCE: f64 = 1e-3;

/// A rigid camera-to-world transform in the OpenGL camera convention
/// (x right, y up, looking along −z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// The camera-to-world matrix, re-orthonormalised.
    pub matrix: DMat4,
}

impl Pose {
    /// The pose of `m`, or why `m` is not rigid.
    pub fn new(m: DMat4) -> Result<Self, String> {
        if !m.is_finite() {
            return Err("not finite".into());
        }
        let bottom = m.row(3);
        if (bottom - glam::DVec4::W).abs().max_element() > RIGID_TOLERANCE {
            return Err(format!("bottom row is {bottom}, not 0 0 0 1"));
        }
        let r = DMat3::from_mat4(m);
        let rtr = r.transpose() * r;
        let off = (rtr - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        if off > RIGID_TOLERANCE {
            return Err(format!(
                "its 3 × 3 part is not a rotation (RᵀR differs from the identity by {off:.2e}: scaled or sheared)"
            ));
        }
        if r.determinant() < 0.0 {
            return Err("its 3 × 3 part is a reflection (determinant < 0)".into());
        }
        // Gram–Schmidt, so that rays stay unit length.
        let x = r.x_axis.normalize();
        let y = (r.y_axis - x * x.dot(r.y_axis)).normalize();
        let z = x.cross(y);
        Ok(Self {
            matrix: DMat4::from_cols(
                x.extend(0.0),
                y.extend(0.0),
                z.extend(0.0),
                m.w_axis.truncate().extend(1.0),
            ),
        })
    }

    /// The pose of a camera at `eye` looking at `target`, `up` roughly up
    /// (not parallel to the view).
    pub fn looking_at(eye: DVec3, target: DVec3, up: DVec3) -> Self {
        let f = (target - eye).normalize();
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        Self {
            matrix: DMat4::from_cols(
                r.extend(0.0),
                u.extend(0.0),
                (-f).extend(0.0),
                eye.extend(1.0),
            ),
        }
    }

    /// The camera's position.
    pub fn origin(&self) -> DVec3 {
        self.matrix.w_axis.truncate()
    }

    /// A camera-frame direction in the world.
    pub fn to_world(&self, d: DVec3) -> DVec3 {
        self.matrix.transform_vector3(d)
    }

    /// The viewing direction (−z of the camera).
    pub fn forward(&self) -> DVec3 {
        -self.matrix.z_axis.truncate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_poses_pass_and_others_say_why_not() {
        let good = DMat4::from_rotation_translation(
            glam::DQuat::from_euler(glam::EulerRot::YXZ, 0.3, -0.2, 0.1),
            DVec3::new(1.0, 2.0, 3.0),
        );
        let p = Pose::new(good).unwrap();
        assert!((p.origin() - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12);
        let scaled = good * DMat4::from_scale(DVec3::splat(1.1));
        assert!(Pose::new(scaled).unwrap_err().contains("not a rotation"));
        let mirrored = good * DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
        assert!(Pose::new(mirrored).unwrap_err().contains("reflection"));
        let mut projective = good;
        projective.x_axis.w = 0.5;
        assert!(Pose::new(projective).unwrap_err().contains("bottom row"));
        let mut nan = good;
        nan.w_axis.x = f64::NAN;
        assert!(Pose::new(nan).is_err());
    }
}
