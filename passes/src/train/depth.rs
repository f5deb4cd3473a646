//! What a depth map says along one training ray, and the loss that holds
//! the field to it.
//!
//! A capture that records depth (a phone's LiDAR, an RGB-D camera, a
//! renderer's depth pass) says where the surface is along each pixel's
//! ray, which a photograph of a plain surface cannot: every haze of the
//! surface's colour in front of it renders the same pixel. With the
//! march's weights w_i = T_i α_i at the samples t_i and T_N the
//! transmittance past the last, the depth loss of a ray whose surface lies
//! at length D along it is
//!
//! L_z = μ/Diag · (Σ_i w_i ρ(t_i − D) + T_N ρ(t_exit − D)),
//!
//! ρ(x) = √(x² + s²) − s (quadratic within the tolerance s, linear beyond,
//! so a wrong depth pulls no harder than a far one), Diag the field's
//! diagonal (μ does not depend on the scene's units) and t_exit where the
//! ray leaves the bounds. The loss is smallest with all the ray's weight at
//! D: it clears what stands in front of the surface and what lies behind
//! it, and where D lies past the bounds it clears the whole ray. It is
//! A D further than [`FAR_TOLERANCES`] tolerances past t_exit is taken
//! there ([`effective_target`]): beyond, ρ is linear to within 0.2 %, the
//! gradient the same, and f32 keeps the differences a far D would round
//! away. The loss is
//! linear in the weights, with ρ(t_i − D) in the place of a colour, so its
//! gradient takes the colour's form: ∂L_z/∂σ_i = μ/Diag · Δ_i·(T_{i+1}
//! ρ_i − Σ_{j>i} w_j ρ_j − T_N ρ_exit) (`crate::train::render`).
//! Mirrored in `shaders/train/ray_grad_body.wgsl` (`depth_penalty`).

use glam::DVec3;

/// One ray's depth term: where the depth map puts the surface along the
/// ray, and the loss's weight and tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthTerm {
    /// D: the length along the (unit) ray to the recorded surface.
    pub target: f64,
    /// μ: the loss's weight (divided by the field's diagonal inside).
    pub weight: f64,
    /// s: the length within which the loss is quadratic (scene units,
    /// positive).
    pub tolerance: f64,
}

/// How many tolerances past the bounds a recorded surface is taken at most
/// ([`effective_target`]).
pub const FAR_TOLERANCES: f64 = 16.0;

/// The depth the loss takes for a surface recorded at `target` along a
/// ray that leaves the bounds at `exit`, with tolerance `s`: `target`, or
/// [`FAR_TOLERANCES`] × `s` past `exit` where it lies further.
pub fn effective_target(target: f64, exit: f64, s: f64) -> f64 {
    target.min(exit + FAR_TOLERANCES * s)
}

/// ρ(x) = √(x² + s²) − s: the depth loss's penalty for weight `x` away
/// from the recorded surface, with tolerance `s` (taken as x² / (√(x² +
/// s²) + s), which f32 keeps where x is small beside s).
pub fn depth_penalty(x: f64, s: f64) -> f64 {
    x * x / ((x * x + s * s).sqrt() + s)
}

/// The length along the unit ray `dir` to the point at z-depth `z` (the
/// distance along the camera's viewing direction `forward`, unit, as depth
/// maps record it), or None where the map records nothing there (`z` not
/// positive or not finite) or the ray does not go forward.
pub fn ray_depth(z: f32, dir: DVec3, forward: DVec3) -> Option<f64> {
    let cos = dir.dot(forward);
    (z.is_finite() && z > 0.0 && cos > 1e-6).then(|| z as f64 / cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The penalty is 0 at the surface, quadratic within the tolerance
    /// and grows as |x| − s beyond it, the same on both sides.
    #[test]
    fn the_penalty_is_quadratic_near_and_linear_far() {
        let s = 0.01;
        assert_eq!(depth_penalty(0.0, s), 0.0);
        let near = depth_penalty(1e-4, s);
        assert!((near / (0.5 * 1e-8 / s) - 1.0).abs() < 1e-4, "{near}");
        let far = depth_penalty(10.0, s);
        assert!((far - (10.0 - s)).abs() < 1e-5, "{far}");
        assert_eq!(depth_penalty(-0.3, s), depth_penalty(0.3, s));
    }

    /// A surface recorded far past the bounds is taken 16 tolerances past
    /// them; one nearer as it is.
    #[test]
    fn a_far_surface_is_taken_a_few_tolerances_past_the_bounds() {
        assert_eq!(effective_target(1e30, 3.0, 0.01), 3.0 + 0.16);
        assert_eq!(effective_target(3.1, 3.0, 0.01), 3.1);
        assert_eq!(effective_target(1.0, 3.0, 0.01), 1.0);
    }

    /// A z-depth becomes the length along an oblique ray; nothing where
    /// the map records nothing or the ray goes sideways.
    #[test]
    fn z_depth_becomes_the_length_along_the_ray() {
        let forward = DVec3::NEG_Z;
        let dir = DVec3::new(0.6, 0.0, -0.8);
        assert!((ray_depth(2.0, dir, forward).unwrap() - 2.5).abs() < 1e-12);
        assert_eq!(ray_depth(0.0, dir, forward), None);
        assert_eq!(ray_depth(f32::NAN, dir, forward), None);
        assert_eq!(ray_depth(f32::INFINITY, dir, forward), None);
        assert_eq!(ray_depth(1.0, DVec3::X, forward), None);
    }
}
