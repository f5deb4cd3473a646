//! Next-event sampling of a recipe's emitters: a direction towards a point
//! of the light, with its density in solid angle. Spheres are sampled
//! uniformly in the cone they subtend; a quad's face uniformly by area
//! (one-sided: nothing from behind it).

use std::f64::consts::PI;

use glam::DVec3;

use crate::geometry::Ray;
use crate::scene::{Primitive, Shape};

/// A sampled direction towards an emitter.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the shading point.
    pub dir: DVec3,
    /// Distance to the light's surface along `dir`.
    pub distance: f64,
    /// Density of `dir` in solid angle.
    pub pdf: f64,
}

/// A direction from `x` towards emitter `light` for uniform `u`, or `None`
/// when `x` is inside it, behind a one-sided face, or it is not an emitter
/// the tracer samples.
pub fn sample_emitter(light: &Primitive, x: DVec3, u: [f64; 2]) -> Option<LightSample> {
    if let Some(face) = light.face {
        let q = face.point(u[0], u[1]);
        let to = q - x;
        let d2 = to.length_squared();
        let distance = d2.sqrt();
        if distance <= 0.0 {
            return None;
        }
        let dir = to / distance;
        let cos_light = -dir.dot(face.normal);
        if cos_light <= 1e-12 {
            return None;
        }
        return Some(LightSample {
            dir,
            distance,
            pdf: d2 / (cos_light * face.area()),
        });
    }
    let Shape::Sphere { centre, radius } = light.shape else {
        return None;
    };
    let to = centre - x;
    let d2 = to.length_squared();
    if d2 <= radius * radius * (1.0 + 1e-9) {
        return None;
    }
    let axis = to / d2.sqrt();
    let sin2 = radius * radius / d2;
    // 1 − cos θmax without cancellation for far, small lights.
    let one_minus_cos_max = sin2 / (1.0 + (1.0 - sin2).sqrt());
    let one_minus_cos = u[0] * one_minus_cos_max;
    let cos = 1.0 - one_minus_cos;
    let sin = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = axis.any_orthonormal_pair();
    let dir = sin * phi.cos() * t + sin * phi.sin() * b + cos * axis;
    let ray = Ray { origin: x, dir };
    let distance = light
        .shape
        .interval(&ray)
        .map_or(d2.sqrt(), |(t0, _)| t0.max(0.0));
    Some(LightSample {
        dir,
        distance,
        pdf: 1.0 / (2.0 * PI * one_minus_cos_max),
    })
}

/// The solid angle emitter `light` subtends from `x` (exact for spheres and
/// faces; zero from inside or behind) and the unit direction to its centre.
pub fn emitter_cone(light: &Primitive, x: DVec3) -> Option<(DVec3, f64)> {
    if let Some(face) = light.face {
        let solid = face.solid_angle(x);
        let axis = (face.centre - x).try_normalize()?;
        return (solid > 0.0).then_some((axis, solid));
    }
    let Shape::Sphere { centre, radius } = light.shape else {
        return None;
    };
    let to = centre - x;
    let d = to.length();
    if d <= radius {
        return None;
    }
    let sin2 = (radius / d).powi(2);
    let one_minus_cos_max = sin2 / (1.0 + (1.0 - sin2).sqrt());
    Some((to / d, 2.0 * PI * one_minus_cos_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use crate::scene::Face;
    use glam::DMat3;

    fn quad() -> Primitive {
        let face = Face {
            centre: DVec3::new(0.0, 1.0, 0.0),
            u: DVec3::X * 0.3,
            v: DVec3::Z * 0.2,
            normal: DVec3::NEG_Y,
        };
        Primitive {
            name: "panel".into(),
            shape: Shape::Box {
                centre: DVec3::new(0.0, 1.005, 0.0),
                half: DVec3::new(0.3, 0.2, 0.005),
                rotation: DMat3::from_cols(DVec3::X, DVec3::Z, DVec3::NEG_Y),
            },
            albedo: DVec3::ZERO,
            checker: None,
            emission: DVec3::ONE,
            face: Some(face),
            medium_density: None,
            in_field: Some(true),
        }
    }

    /// 1/pdf averages to the solid angle the light subtends (exact for both
    /// kinds), and the sampled distance lands on the light's surface.
    #[test]
    fn inverse_density_integrates_to_the_solid_angle() {
        let sphere = Primitive {
            shape: Shape::Sphere {
                centre: DVec3::new(0.2, 1.5, -0.1),
                radius: 0.25,
            },
            face: None,
            ..quad()
        };
        let mut rng = Pcg32::new(9, 1);
        for light in [quad(), sphere] {
            for x in [DVec3::ZERO, DVec3::new(0.7, 0.2, 0.4)] {
                let (_, solid) = emitter_cone(&light, x).unwrap();
                let n = 200_000;
                let mut sum = 0.0;
                for _ in 0..n {
                    let s = sample_emitter(&light, x, rng.next_2d()).unwrap();
                    sum += 1.0 / s.pdf;
                    assert!(light.shape.sdf(x + s.dir * s.distance).abs() < 1e-9);
                }
                let est = sum / n as f64;
                assert!(
                    (est / solid - 1.0).abs() < 0.01,
                    "{} {est} vs {solid}",
                    light.name
                );
            }
        }
        // Behind a one-sided face: nothing.
        assert!(sample_emitter(&quad(), DVec3::new(0.0, 2.0, 0.0), [0.5, 0.5]).is_none());
        assert!(emitter_cone(&quad(), DVec3::new(0.0, 2.0, 0.0)).is_none());
    }
}
