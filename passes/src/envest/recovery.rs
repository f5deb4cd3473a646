//! Did an estimate find each hidden light? For every emitter of a recipe
//! outside its field, seen from a point (an object's centre): the lobes of
//! the estimate within a search cone around the emitter's direction, how
//! far their energy-weighted mean direction and their strongest lobe
//! point from it, and how much light they carry against the emitter's.

use glam::DVec3;

use super::truth::Lights;
use crate::bake::emitter_cone;
use crate::scene::Recipe;
use crate::sg::Sg64;
use crate::sgfit::model::luminance;

/// Half-angle of the cone (degrees) searched around a hidden emitter for
/// the lobe that stands for it: wide enough to find a lobe that missed by
/// the 25°, narrow enough not to take another light's.
pub const SEARCH_CONE_DEGREES: f64 = 40.0;

/// One hidden emitter as the estimate recovered it.
#[derive(Debug, Clone, PartialEq)]
pub struct EmitterRecovery {
    /// The emitter's name in the recipe.
    pub name: String,
    /// Unit direction from the point to the emitter.
    pub direction: DVec3,
    /// Angle (degrees) from it to the estimate's strongest lobe within
    /// [`SEARCH_CONE_DEGREES`]; `None` when no lobe points there.
    pub angle_degrees: Option<f64>,
    /// That lobe's integrated luminance over the emitter's (radiance × solid
    /// angle); 0 when there is none.
    pub energy_ratio: f64,
    /// Angle (degrees) from the emitter to the energy-weighted mean
    /// direction of all the lobes within the cone (an estimate may spread
    /// one bulb over several lobes); `None` when none is there.
    pub centroid_degrees: Option<f64>,
    /// Their summed integrated luminance over the emitter's.
    pub cone_energy_ratio: f64,
}

/// How `lobes` recovered each hidden emitter of `recipe`, seen from `at`.
pub fn emitter_recovery(recipe: &Recipe, lobes: &[Sg64], at: DVec3) -> Vec<EmitterRecovery> {
    let cos_cone = SEARCH_CONE_DEGREES.to_radians().cos();
    super::truth::emitters(recipe, Lights::Hidden)
        .into_iter()
        .filter_map(|p| {
            let (direction, solid) = emitter_cone(p, at)?;
            let energy = luminance(p.emission) * solid;
            let near: Vec<(&Sg64, f64)> = lobes
                .iter()
                .filter(|l| l.direction.dot(direction) >= cos_cone)
                .map(|l| (l, luminance(l.integral())))
                .collect();
            let best = near.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
            let total: f64 = near.iter().map(|(_, e)| e).sum();
            let centroid: DVec3 = near.iter().map(|(l, e)| l.direction * *e).sum();
            let angle = |d: DVec3| d.dot(direction).clamp(-1.0, 1.0).acos().to_degrees();
            Some(EmitterRecovery {
                name: p.name.clone(),
                direction,
                angle_degrees: best.map(|(l, _)| angle(l.direction)),
                energy_ratio: best.map_or(0.0, |(_, e)| e / energy.max(1e-300)),
                centroid_degrees: centroid.try_normalize().map(angle),
                cone_energy_ratio: total / energy.max(1e-300),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::scene::{Primitive, Shape};

    /// The recipe's own hidden light as lobes recovers the bulb exactly; a
    /// lobe turned 20° away is found 20° off; one turned 60° is not found.
    #[test]
    fn recovery_measures_direction_and_energy() {
        let bulb = Primitive {
            name: "bulb".into(),
            shape: Shape::Sphere {
                centre: DVec3::new(0.5, 3.0, 0.0),
                radius: 0.05,
            },
            albedo: DVec3::ZERO,
            checker: None,
            emission: DVec3::splat(1e4),
            face: None,
            medium_density: None,
            in_field: Some(false),
        };
        let recipe = Recipe {
            bounds: Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            primitives: vec![bulb],
        };
        let at = DVec3::ZERO;
        let truth = super::super::truth::hidden_light_lobes(
            &recipe,
            &crate::scene::Environment::Black,
            at,
            1e9,
        );
        let r = &emitter_recovery(&recipe, &truth, at)[0];
        assert!(r.angle_degrees.unwrap() < 1e-6);
        assert!((r.energy_ratio - 1.0).abs() < 1e-3, "{}", r.energy_ratio);
        let turn = |deg: f64| {
            let q = glam::DQuat::from_rotation_z(deg.to_radians());
            vec![Sg64 {
                direction: q * truth[0].direction,
                ..truth[0]
            }]
        };
        let r = &emitter_recovery(&recipe, &turn(20.0), at)[0];
        assert!((r.angle_degrees.unwrap() - 20.0).abs() < 1e-6);
        // Split in two halves ±15° either side: each is 15° off, their
        // centroid on the bulb, their sum all of its light.
        let mut split = turn(15.0);
        split.extend(turn(-15.0));
        for l in &mut split {
            l.amplitude *= 0.5;
        }
        let r = &emitter_recovery(&recipe, &split, at)[0];
        assert!((r.angle_degrees.unwrap() - 15.0).abs() < 1e-6);
        assert!(r.centroid_degrees.unwrap() < 1e-6);
        assert!((r.cone_energy_ratio - 1.0).abs() < 1e-3);
        let r = &emitter_recovery(&recipe, &turn(60.0), at)[0];
        assert_eq!(r.angle_degrees, None);
        assert_eq!(r.energy_ratio, 0.0);
    }
}
