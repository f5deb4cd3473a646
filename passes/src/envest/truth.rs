//! Ground truth for validating an estimated environment on a recipe, whose
//! lights are known: the direct irradiance a chosen set of the recipe's
//! lights delivers at a point (occluded by the recipe's own geometry), the
//! same for a set of SG lobes, the points where the two are compared, and
//! the hidden light as SG lobes for rendering objects with the truth.

use glam::DVec3;

use super::env_model::{env_term, EnvSampler};
use super::near_lights::PointLight;
use crate::bake::{emitter_cone, sample_emitter, PathTracer};
use crate::geometry::Ray;
use crate::lighting::environment_lobes;
use crate::rng::Pcg32;
use crate::scene::{Environment, Primitive, Recipe, Scene};
use crate::sg::Sg64;
use crate::sgfit::model::luminance;

/// Which of a recipe's lights to count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lights {
    /// The light the field does not show: emitters outside its bounds and
    /// the environment (what the estimate should recover).
    Hidden,
    /// Every light: all emitters and the environment.
    All,
}

/// Where an estimate is checked: each object's centre x_o and a 3 × 3 grid
/// over the field's floor plan at a third of its height (grid points inside
/// or within 5 % of the field's size of a solid are left out), each facing
/// up and along the four horizontal axes (light from below the field's
/// surfaces is never seen by a surface point, so it is not asked for).
pub fn test_points(scene: &Scene, recipe: &Recipe) -> Vec<(DVec3, DVec3)> {
    let mut centres: Vec<DVec3> = scene.objects.iter().map(|o| o.sphere().0).collect();
    let (lo, size) = (recipe.bounds.min, recipe.bounds.size());
    let clearance = 0.05 * size.max_element();
    for i in 0..3 {
        for k in 0..3 {
            let f = |j: i32| 0.25 + 0.25 * j as f64;
            let x = lo + DVec3::new(f(i) * size.x, size.y / 3.0, f(k) * size.z);
            let clear = recipe
                .primitives
                .iter()
                .all(|p| p.medium_density.is_some() || p.shape.sdf(x) > clearance);
            if clear {
                centres.push(x);
            }
        }
    }
    let axes = [DVec3::Y, DVec3::X, -DVec3::X, DVec3::Z, -DVec3::Z];
    centres
        .into_iter()
        .flat_map(|c| axes.map(|n| (c, n)))
        .collect()
}

pub(crate) fn emitters(recipe: &Recipe, lights: Lights) -> Vec<&Primitive> {
    let (inside, outside) = recipe.lights();
    match lights {
        Lights::Hidden => outside,
        Lights::All => inside.into_iter().chain(outside).collect(),
    }
}

/// Direct irradiance at `x` with normal `n` from `lights` of `recipe` (and
/// its environment `env`), `samples` per light; occluded by the recipe's
/// geometry when `occluded`.
#[allow(clippy::too_many_arguments)]
pub fn light_irradiance(
    recipe: &Recipe,
    env: &Environment,
    lights: Lights,
    x: DVec3,
    n: DVec3,
    samples: u32,
    seed: u64,
    occluded: bool,
) -> DVec3 {
    let tracer = PathTracer::new(recipe, env, 0);
    let visibility = |ray: &Ray, t: f64| {
        if occluded {
            tracer.visibility(ray, t)
        } else {
            1.0
        }
    };
    let mut rng = Pcg32::new(seed, 0x7207);
    let mut e = DVec3::ZERO;
    for p in emitters(recipe, lights) {
        for _ in 0..samples {
            let Some(ls) = sample_emitter(p, x, rng.next_2d()) else {
                continue;
            };
            let cos = ls.dir.dot(n);
            if cos <= 0.0 {
                continue;
            }
            let ray = Ray {
                origin: x,
                dir: ls.dir,
            };
            let vis = visibility(&ray, ls.distance * (1.0 - 1e-9));
            e += p.emission * vis * cos / (ls.pdf * samples as f64);
        }
    }
    if !env.is_black() {
        for _ in 0..samples {
            let u = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
            let Some((dir, pdf)) = env.sample(u) else {
                break;
            };
            let cos = dir.dot(n);
            if cos <= 0.0 || pdf <= 0.0 {
                continue;
            }
            let vis = visibility(&Ray { origin: x, dir }, f64::INFINITY);
            e += env.eval(dir) * vis * cos / (pdf * samples as f64);
        }
    }
    e
}

/// Irradiance at `x` with normal `n` from the light the field shows: the
/// emitters inside it and everything they light, `bounces` scattering
/// events deep (what the object's probe carries, where direct light from
/// a lamp behind foliage can be a small part of it). Hidden emitters and
/// the environment are left out.
pub fn field_light_irradiance(
    recipe: &Recipe,
    x: DVec3,
    n: DVec3,
    samples: u32,
    bounces: u32,
    seed: u64,
) -> DVec3 {
    let mut geometry = recipe.clone();
    geometry
        .primitives
        .retain(|p| !p.is_emitter() || p.in_field == Some(true));
    let env = Environment::Black;
    let tracer = PathTracer::new(&geometry, &env, bounces);
    let mut rng = Pcg32::new(seed, 0xF1E1);
    tracer.irradiance(x, n, samples, &mut rng)
}

/// Irradiance at `x` with normal `n` from distant `lobes`; occluded by
/// `recipe` when `occluded` (the same occlusion as [`light_irradiance`], so
/// the two differ only by the light; the hidden emitters' spheres, which
/// the lobes stand for, do not occlude).
#[allow(clippy::too_many_arguments)]
pub fn lobes_irradiance(
    recipe: &Recipe,
    lobes: &[Sg64],
    x: DVec3,
    n: DVec3,
    samples: u32,
    seed: u64,
    occluded: bool,
) -> DVec3 {
    if lobes.is_empty() {
        return DVec3::ZERO;
    }
    let env = Environment::Black;
    // The lobes stand for the hidden lights, so those lights' own spheres
    // must not block them.
    let mut geometry = recipe.clone();
    geometry
        .primitives
        .retain(|p| !p.is_emitter() || p.in_field == Some(true));
    let tracer = PathTracer::new(&geometry, &env, 0);
    let visibility = |dir: DVec3| {
        if occluded {
            tracer.visibility(&Ray { origin: x, dir }, f64::INFINITY)
        } else {
            1.0
        }
    };
    let sampler = EnvSampler::new(lobes);
    let mut rng = Pcg32::new(seed, 0x10BE);
    env_term(lobes, &sampler, n, samples, &visibility, &mut rng).irradiance
}

/// Irradiance at `x` with normal `n` from point `lights`, occluded by
/// `recipe` when `occluded` (the hidden emitters they stand for do not
/// occlude, as in [`lobes_irradiance`]).
pub fn point_lights_irradiance(
    recipe: &Recipe,
    lights: &[PointLight],
    x: DVec3,
    n: DVec3,
    occluded: bool,
) -> DVec3 {
    if lights.is_empty() {
        return DVec3::ZERO;
    }
    let mut geometry = recipe.clone();
    geometry
        .primitives
        .retain(|p| !p.is_emitter() || p.in_field == Some(true));
    let env = Environment::Black;
    let tracer = PathTracer::new(&geometry, &env, 0);
    lights
        .iter()
        .map(|l| {
            let (e, dir) = l.irradiance(x, n);
            if e.max_element() <= 0.0 || !occluded {
                return e;
            }
            let d = (l.position - x).length();
            e * tracer.visibility(&Ray { origin: x, dir }, d)
        })
        .sum()
}

/// The recipe's hidden light as distant SG lobes seen from `at`: the
/// environment's lobes, and each emitter outside the field as one lobe
/// along its direction with amplitude its radiance and sharpness 2π/Ω (Ω
/// its solid angle; the lobe's integral is then radiance × Ω), sharpness
/// capped at `max_sharpness` with the integral kept.
pub fn hidden_light_lobes(
    recipe: &Recipe,
    env: &Environment,
    at: DVec3,
    max_sharpness: f64,
) -> Vec<Sg64> {
    hidden_light_lobes_except(recipe, env, at, max_sharpness, |_| false)
}

/// As [`hidden_light_lobes`], leaving out the emitters `skip` picks (which
/// the caller lights otherwise).
pub fn hidden_light_lobes_except(
    recipe: &Recipe,
    env: &Environment,
    at: DVec3,
    max_sharpness: f64,
    skip: impl Fn(&Primitive) -> bool,
) -> Vec<Sg64> {
    let mut lobes = environment_lobes(env);
    for p in emitters(recipe, Lights::Hidden)
        .into_iter()
        .filter(|p| !skip(p))
    {
        let Some((axis, solid)) = emitter_cone(p, at) else {
            continue;
        };
        let sharpness = 2.0 * std::f64::consts::PI / solid;
        let capped = sharpness.min(max_sharpness);
        let keep = |l: f64| 2.0 * std::f64::consts::PI / l * Sg64::one_minus_exp_neg(2.0 * l);
        lobes.push(Sg64 {
            direction: axis,
            sharpness: capped,
            amplitude: p.emission * keep(sharpness) / keep(capped),
        });
    }
    lobes
}

/// The recipe's hidden light in the fit's own terms: each hidden ball
/// emitter as a point light at its centre (intensity its radiance × πr²,
/// what a uniformly bright ball sends every way), and the environment's
/// lobes with every other hidden emitter as a lobe seen from `at`
/// ([`hidden_light_lobes_except`]).
pub fn hidden_light_model(
    recipe: &Recipe,
    env: &Environment,
    at: DVec3,
    max_sharpness: f64,
) -> (Vec<Sg64>, Vec<PointLight>) {
    let ball = |p: &Primitive| match p.shape {
        crate::scene::Shape::Sphere { centre, radius } => Some((centre, radius)),
        _ => None,
    };
    let lights = emitters(recipe, Lights::Hidden)
        .into_iter()
        .filter_map(|p| {
            ball(p).map(|(centre, radius)| PointLight {
                position: centre,
                intensity: p.emission * std::f64::consts::PI * radius * radius,
            })
        })
        .collect();
    let lobes = hidden_light_lobes_except(recipe, env, at, max_sharpness, |p| ball(p).is_some());
    (lobes, lights)
}

/// An estimated environment checked against a recipe's lights at
/// [`test_points`]: the irradiance each delivers there, occluded by the
/// recipe's geometry (what an object placed there receives). The recipe's
/// emitters count at their true distance from each point; the estimate is
/// distant light.
#[derive(Debug, Clone, PartialEq)]
pub struct Validation {
    /// The test points (position, normal).
    pub points: Vec<(DVec3, DVec3)>,
    /// Irradiance from the estimated lobes at each point.
    pub estimated: Vec<DVec3>,
    /// Irradiance from the recipe's hidden light at each point.
    pub hidden: Vec<DVec3>,
    /// Irradiance from all of the recipe's lights at each point.
    pub all: Vec<DVec3>,
}

impl Validation {
    /// Checks `lobes` on `scene`'s recipe with `samples` per light and point.
    pub fn new(scene: &Scene, recipe: &Recipe, lobes: &[Sg64], samples: u32, seed: u64) -> Self {
        Self::with_lights(scene, recipe, lobes, &[], samples, seed)
    }

    /// Checks `lobes` and near point `lights` together.
    pub fn with_lights(
        scene: &Scene,
        recipe: &Recipe,
        lobes: &[Sg64],
        lights: &[PointLight],
        samples: u32,
        seed: u64,
    ) -> Self {
        let points = test_points(scene, recipe);
        let env = &scene.environment;
        let mut v = Self {
            estimated: Vec::new(),
            hidden: Vec::new(),
            all: Vec::new(),
            points: points.clone(),
        };
        for (i, (x, n)) in points.into_iter().enumerate() {
            let s = seed.wrapping_add(i as u64);
            v.estimated.push(
                lobes_irradiance(recipe, lobes, x, n, samples, s, true)
                    + point_lights_irradiance(recipe, lights, x, n, true),
            );
            v.hidden.push(light_irradiance(
                recipe,
                env,
                Lights::Hidden,
                x,
                n,
                samples,
                s,
                true,
            ));
            v.all.push(light_irradiance(
                recipe,
                env,
                Lights::All,
                x,
                n,
                samples,
                s,
                true,
            ));
        }
        v
    }

    /// Σ|E_est − E_hidden| / Σ E_hidden in luminance (infinite when the
    /// recipe hides no light and the estimate is not black).
    pub fn hidden_error(&self) -> f64 {
        let diff: f64 = self
            .estimated
            .iter()
            .zip(&self.hidden)
            .map(|(e, h)| (luminance(*e) - luminance(*h)).abs())
            .sum();
        let total: f64 = self.hidden.iter().map(|h| luminance(*h)).sum();
        if total > 0.0 {
            diff / total
        } else if diff > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }

    /// Σ E_est / Σ E_all in luminance: the estimate's share of the
    /// irradiance the recipe's lights deliver.
    pub fn fraction_of_lights(&self) -> f64 {
        let est: f64 = self.estimated.iter().map(|e| luminance(*e)).sum();
        let all: f64 = self.all.iter().map(|a| luminance(*a)).sum();
        if all > 0.0 {
            est / all
        } else {
            f64::INFINITY
        }
    }
}
