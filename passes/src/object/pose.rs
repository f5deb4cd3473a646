//! Where an object stands in the field: translation, rotation (degrees
//! about X, then Y, then Z) and scale (uniform or per axis), as scene files
//! and the interactive app set them every frame.

use glam::{DMat3, DMat4, DQuat, DVec3, EulerRot};
use serde::Deserialize;

/// Uniform or per-axis scale, as a scene file writes it.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    /// One factor for all axes.
    Uniform(f64),
    /// One factor per axis.
    PerAxis(#[serde(deserialize_with = "crate::scene::vec3::exact")] DVec3),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

impl Scale {
    /// The per-axis factors.
    pub fn vector(&self) -> DVec3 {
        match *self {
            Scale::Uniform(s) => DVec3::splat(s),
            Scale::PerAxis(v) => v,
        }
    }
}

/// Smallest and largest scale factor accepted: beyond these a float
/// G-buffer and the SG probe lose all meaning, so they are input errors.
pub const SCALE_RANGE: (f64, f64) = (1e-4, 1e4);

/// An object's pose.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// Where the object's origin goes.
    #[serde(default, deserialize_with = "crate::scene::vec3::exact")]
    pub position: DVec3,
    /// Rotation in degrees about X, then Y, then Z.
    #[serde(default, deserialize_with = "crate::scene::vec3::exact")]
    pub rotation: DVec3,
    /// Scale.
    #[serde(default)]
    pub scale: Scale,
}

impl Default for Pose {
    fn default() -> Self {
        Self {
            position: DVec3::ZERO,
            rotation: DVec3::ZERO,
            scale: Scale::default(),
        }
    }
}

impl Pose {
    /// What is wrong with it (field, message), if anything.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        if !self.position.is_finite() {
            return Some(("position", "must be finite".into()));
        }
        if !self.rotation.is_finite() {
            return Some(("rotation", "must be finite".into()));
        }
        let s = self.scale.vector();
        let (lo, hi) = SCALE_RANGE;
        if !(s.is_finite() && s.min_element() >= lo && s.max_element() <= hi) {
            return Some((
                "scale",
                format!("{s} must be finite and in [{lo:e}, {hi:e}] per axis (mirroring is not supported)"),
            ));
        }
        None
    }

    /// The rotation.
    pub fn quat(&self) -> DQuat {
        let r = self.rotation * (std::f64::consts::PI / 180.0);
        // Extrinsic X, then Y, then Z = intrinsic ZYX.
        DQuat::from_euler(EulerRot::ZYX, r.z, r.y, r.x)
    }

    /// Object-to-world transform.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(self.scale.vector(), self.quat(), self.position)
    }

    /// The transform of normals (inverse transpose of the linear part).
    pub fn normal_matrix(&self) -> DMat3 {
        DMat3::from_mat4(self.matrix()).inverse().transpose()
    }

    /// World-space bounding sphere of an object whose object-space sphere
    /// is (`centre`, `radius`).
    pub fn sphere(&self, centre: DVec3, radius: f64) -> (DVec3, f64) {
        (
            self.matrix().transform_point3(centre),
            radius * self.scale.vector().max_element(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_is_x_then_y_then_z_in_degrees() {
        let p = Pose {
            rotation: DVec3::new(90.0, 90.0, 0.0),
            ..Pose::default()
        };
        // X by 90° takes +Y to +Z; Y by 90° then takes +Z to +X.
        let v = p.matrix().transform_vector3(DVec3::Y);
        assert!((v - DVec3::X).length() < 1e-12, "{v}");
    }

    #[test]
    fn absurd_scales_are_refused() {
        for s in [0.0, -1.0, 1e9, f64::NAN] {
            let p = Pose {
                scale: Scale::Uniform(s),
                ..Pose::default()
            };
            assert_eq!(p.problem().map(|x| x.0), Some("scale"), "{s}");
        }
        assert!(Pose::default().problem().is_none());
    }
}
